#pragma once
/// @file
/// Purpose: the model file (DESIGN.md "Model files") of a subspace identification:
/// the identified state space with its Kalman gain, noise covariance, initial
/// state and offsets, and the provenance every reader of an n4sid/moesp/cva model
/// finds (method, order and the rule that chose it, horizon, fits, singular values,
/// excited band, conditioning, the options that change the model). One function,
/// so that the command line (apps/verb_n4sid.cpp) and the Python package
/// (python/src/) write the very same file for the same identification; the caller
/// adds what only it knows (the log's file name, validation data, an order sweep).
#include <string>
#include <vector>

#include "sysid/io/model_json.hpp"
#include "sysid/subspace/n4sid.hpp"

namespace sysid {

/// The "state-space" model file of `result`, identified with `options`, whose
/// channels are called `input_names` and `output_names` (empty: u1.., y1..).
/// Provenance keys: method, order, order_rule, horizon, fit_percent,
/// singular_values, excited_band_hz, hankel_route, decimation,
/// observability_condition, past_future_min_sine, sysid_version, and
/// enforce_stability / allow_unstable / band_limit_hz + band_limit_order when
/// those options were used.
ModelFile n4sid_model_file(const N4sidResult& result, const N4sidOptions& options,
                           const std::vector<std::string>& input_names, const std::vector<std::string>& output_names);

}  // namespace sysid
