#include "sysid/io/reduced_model_file.hpp"

#include <cmath>
#include <stdexcept>

#include "sysid/config.hpp"
#include "sysid/reduce/balanced_truncation.hpp"
#include "sysid/reduce/modal_truncation.hpp"

namespace sysid {

ReducedModelFile reduce_model_file(const ModelFile& file, const ReduceRequest& request) {
  const int chosen = (request.order >= 0) + (request.max_error_ratio > 0.0) + request.band_hz.has_value();
  if (chosen != 1) throw std::invalid_argument("reduce: give exactly one of the order, the largest error ratio, the band");
  if (request.method != "balanced" && request.method != "spa" && request.method != "modal")
    throw std::invalid_argument("reduce: method must be 'balanced', 'spa' or 'modal', found '" + request.method + "'");
  ReducedModelFile out;
  StateSpace sys = named_model(file);
  out.time_series = sys.inputs() == 0;
  if (out.time_series) {
    if (file.K.size() == 0) throw std::invalid_argument("reduce: the model has no inputs and no noise gain K: nothing to reduce");
    sys.B = file.K;
    sys.D = Eigen::MatrixXd::Identity(sys.outputs(), sys.outputs());
    sys.input_names.clear();
    for (Eigen::Index i = 0; i < sys.outputs(); ++i) sys.input_names.push_back("e_" + sys.output_name(i));
  }
  ReductionResult& r = out.reduction;
  if (request.band_hz || request.method == "modal") {
    if (request.max_error_ratio > 0.0)
      throw std::invalid_argument("reduce: the largest error ratio (--max-error) needs a balanced method (balanced or spa)");
    ModalTruncationOptions o;
    if (request.band_hz) std::tie(o.f_lo_hz, o.f_hi_hz) = *request.band_hz;
    if (request.order >= 0) o.order = request.order;
    o.keep_dc_gain = request.keep_dc_gain;
    r = modal_truncation(sys, o);
  } else {
    BalancedTruncationOptions o;
    o.order = request.order;
    o.max_error_ratio = request.max_error_ratio;
    o.method = request.method == "spa" ? BalancedMethod::singular_perturbation : BalancedMethod::truncation;
    r = balanced_truncation(sys, o);
  }
  ModelFile& reduced = out.file;
  reduced.model = r.model;
  if (out.time_series) {
    reduced.K = r.model.B;
    reduced.model.B = Eigen::MatrixXd::Zero(r.model.order(), 0);
    reduced.model.D = Eigen::MatrixXd::Zero(r.model.outputs(), 0);
    reduced.model.input_names.clear();
    reduced.noise_covariance = file.noise_covariance;
  } else if (file.K.rows() == file.model.order() && file.K.size() > 0 && request.band_hz) {
    // Modal truncation keeps the modes' coordinates only up to a basis change:
    // K cannot follow; the reduced model is deterministic.
    out.warnings.push_back("the noise gain K is not carried over to the reduced model");
  }
  reduced.input_offset = file.input_offset;
  reduced.output_offset = file.output_offset;
  nlohmann::json& p = reduced.provenance;
  p["method"] = "reduce";
  p["reduction"] = r.method;
  if (!request.source.empty()) p["source"] = request.source;
  p["original_order"] = r.original_order;
  p["order"] = r.order;
  if (!std::isnan(r.error_ratio)) p["hsv_ratio"] = r.error_ratio;
  if (!std::isnan(r.hinf_bound)) p["hinf_bound"] = r.hinf_bound;
  if (!std::isnan(r.hinf_error)) p["hinf_error"] = r.hinf_error;
  p["sysid_version"] = SYSID_VERSION_STRING;
  return out;
}

}  // namespace sysid
