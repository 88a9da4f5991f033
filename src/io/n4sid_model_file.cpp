#include "sysid/io/n4sid_model_file.hpp"

#include "sysid/config.hpp"

namespace sysid {

ModelFile n4sid_model_file(const N4sidResult& result, const N4sidOptions& options,
                           const std::vector<std::string>& input_names, const std::vector<std::string>& output_names) {
  ModelFile file;
  file.type = "state-space";
  file.model = result.model;
  file.model.input_names = input_names;
  file.model.output_names = output_names;
  file.K = result.K;
  file.noise_covariance = result.noise_covariance;
  file.x0 = result.x0;
  file.input_offset = result.input_offset;
  file.output_offset = result.output_offset;
  nlohmann::json& p = file.provenance;
  p["method"] = to_string(result.weighting);
  p["order"] = result.order;
  p["order_rule"] = result.order_rule;
  p["horizon"] = result.horizon;
  p["fit_percent"] = json_list_or_null(result.fit_percent);
  p["singular_values"] = json_list_or_null(result.singular_values);
  p["excited_band_hz"] = {result.excited_band_low_hz, result.excited_band_high_hz};
  p["hankel_route"] = to_string(result.route_used);
  p["decimation"] = result.decimation;
  p["observability_condition"] = result.observability_condition;
  p["past_future_min_sine"] = result.past_future_min_sine;
  if (!result.refinement.empty())
    p["pole_refinement"] = {{"refined", result.poles_refined},
                            {"fit_before", result.refinement_fit_before},
                            {"fit_after", result.refinement_fit_after},
                            {"note", result.refinement}};
  if (options.enforce_stability) p["enforce_stability"] = true;
  if (options.allow_unstable) p["allow_unstable"] = true;
  if (options.band_limit_hz > 0.0) {
    p["band_limit_hz"] = options.band_limit_hz;
    p["band_limit_order"] = options.band_limit_order;
  }
  p["sysid_version"] = SYSID_VERSION_STRING;
  return file;
}

}  // namespace sysid
