#pragma once
/// @file
/// Purpose: the model file of a finite-element model reduced to its lowest modes
/// (fem/modal_model.hpp), as `sysid reduce --fem` and `sysid.fem_reduce` (Python)
/// write it: the modal state space (continuous, or sampled with its hold) and the
/// provenance (method "fem-modal", DOFs, modes, static correction, hold, natural
/// frequencies); the caller adds the FE file's name.
#include "sysid/fem/modal_model.hpp"
#include "sysid/io/model_json.hpp"

namespace sysid {

ModelFile fem_modal_model_file(const fem::SecondOrderModel& model, const fem::ModalModelResult& result,
                               const fem::ModalModelOptions& options);

}  // namespace sysid
