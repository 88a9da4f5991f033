#pragma once
/// @file
/// Purpose: the reduction of a model file as `sysid reduce` and `sysid.reduce`
/// (Python) perform it, and the model file of the result: balanced truncation,
/// singular perturbation or modal truncation (reduce/), with a time-series model
/// (AR, ARMA: no inputs) reduced through its innovation form
/// y = C (zI - A)^-1 K e + e (the spectral factor whose modes shape the output
/// spectrum), the offsets carried over, and the provenance of the reduction.
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sysid/io/model_json.hpp"
#include "sysid/reduce/reduction_error.hpp"

namespace sysid {

struct ReduceRequest {
  /// "balanced" (truncation), "spa" (singular perturbation) or "modal".
  std::string method = "balanced";
  Eigen::Index order = -1;          ///< >= 0: the reduced order
  double max_error_ratio = 0.0;     ///< > 0: smallest order with that HSV ratio (balanced methods)
  std::optional<std::pair<double, double>> band_hz;  ///< modal truncation: keep the modes in [lo, hi] Hz
  bool keep_dc_gain = false;        ///< modal truncation: add the removed modes' static gain to D
  std::string source;               ///< provenance "source" (the model's file name); empty: not written
};

struct ReducedModelFile {
  ModelFile file;            ///< the reduced model file (provenance: method "reduce", reduction, orders, errors)
  ReductionResult reduction;
  bool time_series = false;  ///< reduced through the innovation form
  std::vector<std::string> warnings;
};

/// Purpose: reduce `file` as `request` says (exactly one of order, max_error_ratio
/// and band_hz; std::invalid_argument otherwise, or for a time-series model without
/// K, or for max_error_ratio with modal truncation).
ReducedModelFile reduce_model_file(const ModelFile& file, const ReduceRequest& request);

}  // namespace sysid
