#include "sysid/io/fem_modal_model_file.hpp"

#include <vector>

#include "sysid/config.hpp"

namespace sysid {

ModelFile fem_modal_model_file(const fem::SecondOrderModel& model, const fem::ModalModelResult& result,
                               const fem::ModalModelOptions& options) {
  const Eigen::VectorXd& f = result.modes.natural_frequencies_hz;
  ModelFile out;
  out.model = result.model;
  nlohmann::json& p = out.provenance;
  p["method"] = "fem-modal";
  p["dofs"] = model.dofs();
  p["modes"] = f.size();
  p["static_correction"] = options.static_correction;
  if (options.Ts > 0.0) p["hold"] = options.hold == Hold::foh ? "foh" : "zoh";
  p["natural_frequencies_hz"] = std::vector<double>(f.data(), f.data() + f.size());
  p["sysid_version"] = SYSID_VERSION_STRING;
  return out;
}

}  // namespace sysid
