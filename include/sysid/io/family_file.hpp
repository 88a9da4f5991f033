#pragma once
/// @file
/// Purpose: the model-family file (DESIGN.md "Model families over operating
/// conditions"): the members' models with their conditions and fits, the modes
/// followed across them, the nominal and the uncertainty bound and weight.
///
/// Format: see DESIGN.md; every model object inside (members[i].model,
/// nominal.model, uncertainty.weight) is exactly a model file's root object
/// (io/model_json.hpp), so any reader of model files reads them. Besides the
/// contract's keys each mode carries "spread" (family/mode_spread.hpp) and the
/// uncertainty "allowance" (how estimation error was allowed for) and "weight_fit"
/// (order and conservatism of the weight).
///
/// Errors: reading raises sysid::DataError naming the file and the key
/// ("members[3].model: A: ..."); writing is atomic (io/atomic_file.hpp).
#include <sysid/family/mode_spread.hpp>
#include <sysid/family/mode_tracking.hpp>
#include <sysid/family/model_family.hpp>
#include <sysid/io/model_json.hpp>

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace sysid {

struct FamilyFileMember {
  std::vector<ConditionValue> conditions;  ///< one per FamilyFile::condition_names
  std::string log;                         ///< as the manifest names it
  std::string validate;                    ///< as the manifest names it; empty when none
  ModelFile model;
  Eigen::VectorXd fit_percent;  ///< per output (NaN written as null)
};

struct FamilyFileUncertainty {
  std::string form;  ///< "multiplicative-output" | "multiplicative-input" | "additive"
  double band_lo_hz = 0.0, band_hi_hz = 0.0;
  Eigen::VectorXd frequency_hz, bound;
  std::string allowance;                 ///< how the members' estimation error was allowed for
  std::optional<ModelFile> weight;       ///< absent when no weight could be fitted
  nlohmann::json weight_fit = nlohmann::json::object();  ///< order, median/max conservatism
};

struct FamilyFile {
  double Ts = 0.0;
  std::vector<std::string> inputs, outputs, condition_names;
  std::vector<FamilyFileMember> members;
  std::vector<TrackedMode> modes;
  /// One per mode, or empty (not written). Written as each mode's "spread"; not
  /// read back (mode_spread() recomputes it from the modes and the conditions).
  std::vector<ModeSpread> mode_spreads;
  std::optional<int> nominal_member;     ///< null in the file when the nominal is not a member
  std::string nominal_criterion;
  ModelFile nominal_model;
  std::optional<FamilyFileUncertainty> uncertainty;  ///< absent with one member
};

/// Purpose: the family file of analysed members (one piece of code for the program
/// and the Python package): `members` as given (logs, models, fits), their
/// conditions from `conditions` (one value per member each), the modes with their
/// spread against the conditions, the nominal (the member the analysis chose, its
/// model exactly) and the uncertainty (form, band, grid, bound, allowance, weight).
/// Preconditions (std::invalid_argument): one result per member; conditions sized.
FamilyFile make_family_file(std::vector<FamilyFileMember> members, const std::vector<Condition>& conditions,
                            const ModelFamilyResult& result, const ModelFamilyOptions& options);

/// One member as the family analysis takes it, and its fit.
struct FamilyMemberEvidence {
  FamilyMemberModel member;     ///< the model compared (family_member_model) and its response error
  Eigen::VectorXd fit_percent;  ///< per output; empty without a record
};

/// Purpose: a member's evidence from its model file and records (one piece of code
/// for the program and the Python package). A plant: one simulation on its own
/// record (x0 estimated, the file's offsets) gives the response error
/// (family/estimation_error.hpp) and, without a validation record, the fit; a time
/// series (no inputs) is compared through its unit-noise innovation form and
/// fitted by one-step prediction. `own` null: the model alone (no fit, no
/// allowance); `validation` null: the fit is on `own`.
FamilyMemberEvidence family_member_evidence(const ModelFile& file, const IoData* own, const IoData* validation);

/// The family as the house's pretty JSON text (io/model_json.hpp's printer).
/// Preconditions (std::invalid_argument): consistent sizes (conditions per member,
/// mode vectors per member).
std::string family_to_json_string(const FamilyFile& family);

/// Parses family JSON text; `source_name` stands for the file in messages.
FamilyFile family_from_json_string(const std::string& text, const std::string& source_name);

/// The same from a parsed JSON root (for a reader that looked at "type" first).
FamilyFile family_from_json_value(const nlohmann::json& root, const std::string& source_name);

FamilyFile read_family_json(const std::string& path);
void write_family_json(const std::string& path, const FamilyFile& family);

/// True when the JSON root object is a family file ("type": "family").
bool is_family_json(const nlohmann::json& root);

}  // namespace sysid
