// The extension module sysid._sysid: errors, conversions, and the registration of
// each part (model.cpp, data.cpp, subspace.cpp ...). The package sysid re-exports it.
#include <sysid/config.hpp>
#include <sysid/core/errors.hpp>

#include "bindings.hpp"

namespace sysid::python {

StridedMap sample_view(const SampleArray& a, const char* name) {
  if (a.ndim() != 1 && a.ndim() != 2)
    throw std::invalid_argument(std::string(name) + ": expected a 1-D array (one channel) or a 2-D array (samples x channels), found " +
                                std::to_string(a.ndim()) + "-D");
  const auto rows = static_cast<Eigen::Index>(a.shape(0));
  const auto cols = a.ndim() == 2 ? static_cast<Eigen::Index>(a.shape(1)) : Eigen::Index{1};
  const auto row_stride = static_cast<Eigen::Index>(a.stride(0));
  const auto col_stride = a.ndim() == 2 ? static_cast<Eigen::Index>(a.stride(1)) : rows * row_stride;
  return StridedMap(a.data(), rows, cols, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>(col_stride, row_stride));
}

IoData io_data(const std::optional<SampleArray>& u, const SampleArray& y, double Ts,
               const std::vector<std::string>& inputs, const std::vector<std::string>& outputs) {
  Eigen::MatrixXd y_samples = sample_view(y, "y");
  Eigen::MatrixXd u_samples = u ? Eigen::MatrixXd(sample_view(*u, "u")) : Eigen::MatrixXd(y_samples.rows(), 0);
  if (u_samples.rows() != y_samples.rows())
    throw std::invalid_argument("u has " + std::to_string(u_samples.rows()) + " samples, y has " +
                                std::to_string(y_samples.rows()) + ": they must be samples of the same record");
  if (!inputs.empty() && static_cast<Eigen::Index>(inputs.size()) != u_samples.cols())
    throw std::invalid_argument(std::to_string(inputs.size()) + " input names for " + std::to_string(u_samples.cols()) +
                                " input channels");
  if (!outputs.empty() && static_cast<Eigen::Index>(outputs.size()) != y_samples.cols())
    throw std::invalid_argument(std::to_string(outputs.size()) + " output names for " + std::to_string(y_samples.cols()) +
                                " output channels");
  return IoData(std::move(u_samples), std::move(y_samples), Ts, inputs, outputs, "NumPy arrays");
}

nb::object to_python(const nlohmann::json& value) {
  return nb::module_::import_("json").attr("loads")(value.dump());
}

nlohmann::json from_python(const nb::handle& value) {
  const std::string text = nb::cast<std::string>(nb::module_::import_("json").attr("dumps")(value));
  return nlohmann::json::parse(text);
}

void issue_warnings(const std::vector<std::string>& warnings) {
  for (const std::string& w : warnings)
    if (PyErr_WarnEx(PyExc_RuntimeWarning, w.c_str(), 1) != 0) throw nb::python_error();
}

void bind_errors(nb::module_& m) {
  // DESIGN.md "Python": bad data is sysid.DataError, a ValueError; a numerical
  // failure (rank deficiency, no convergence) is sysid.NumericalError.
  nb::exception<DataError>(m, "DataError", PyExc_ValueError);
  nb::exception<NumericalError>(m, "NumericalError", PyExc_RuntimeError);
}

}  // namespace sysid::python

NB_MODULE(_sysid, m) {
  using namespace sysid::python;
  m.doc() = "sysid: system identification for vibration and motion engineers (the C++ library's bindings)";
  m.attr("__version__") = SYSID_VERSION_STRING;
  bind_errors(m);
  bind_model(m);
  bind_data(m);
  bind_subspace(m);
  bind_polynomial(m);
  bind_realization(m);
  bind_adaptive(m);
  bind_reduce(m);
  bind_spectral(m);
  bind_signal(m);
  bind_validate(m);
  bind_diagnose(m);
  bind_fem(m);
  bind_family(m);
}
