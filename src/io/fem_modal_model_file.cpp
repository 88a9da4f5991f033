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
  // What each output measures (DESIGN.md "Model files"): an FE model knows it, and
  // diagnose's forces inside the plant read the motion accordingly.
  nlohmann::json quantities = nlohmann::json::array();
  for (const auto& o : model.outputs)
    quantities.push_back(o.quantity == fem::Quantity::displacement ? "position" : fem::quantity_name(o.quantity));
  out.extra["output_quantities"] = quantities;
  return out;
}

}  // namespace sysid
