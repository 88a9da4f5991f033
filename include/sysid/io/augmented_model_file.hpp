#pragma once
/// @file
/// Purpose: augmented models in model files (DESIGN.md: `"type": "augmented"`,
/// the nominal state-space model under "nominal" plus named blocks and how they
/// connect), and the diagnose report (DESIGN.md "diagnose: the report contract").
///
/// Layout of the augmented part (keys after the nominal):
///
///   "blocks": [ {"kind": "cubic_stiffness", "input": "u", "output": "y",
///                "connection": "plant_feedback",
///                "params": {"coefficient": 1.2e6}}, ... ],
///   "substeps": 4
///
/// `params` holds every parameter the simulation reads (physics_block.hpp), in
/// the units of DESIGN.md; `connection` is where the block acts (actuator,
/// plant_feedback, plant_parallel, sensor, coupling) and is written for readers,
/// recomputed from the kind on reading. Channels are named as in the nominal
/// model's inputs and outputs (u1.., y1.. when it has no names).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sysid/diagnose/augmented_model.hpp"
#include "sysid/diagnose/diagnose.hpp"
#include "sysid/io/model_json.hpp"

namespace sysid {

/// The augmented model of a model file of any type: a state-space or polynomial
/// file gives the model with no blocks. Errors: sysid::DataError naming
/// `source` and the offending block ("blocks[1].params: missing 'width'"), also
/// for a channel name the nominal lacks or has more than once.
AugmentedModel augmented_model_from_file(const ModelFile& file, const std::string& source);

/// A model file of type "augmented" (type "state-space" when there are no blocks).
ModelFile augmented_model_to_file(const AugmentedModel& model,
                                  const nlohmann::json& provenance = nlohmann::json::object());

/// The report JSON of DESIGN.md: fit_before, fit_after, validation, findings
/// (kind, params — the DESIGN.md ones —, fit_before, fit_after, location,
/// evidence, summary), plus the mismatch tests, every candidate considered, and
/// the model parameters of each finding under "model_params".
nlohmann::json diagnose_report_to_json(const DiagnoseReport& report, double Ts);

}  // namespace sysid
