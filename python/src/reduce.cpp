// sysid.reduce and sysid.hsv: model reduction as `sysid reduce` performs it
// (io/reduced_model_file.hpp) and the Hankel singular values `sysid hsv` lists.
#include <sysid/io/reduced_model_file.hpp>
#include <sysid/reduce/hankel_singular_values.hpp>

#include <nanobind/stl/pair.h>

#include "bindings.hpp"

namespace sysid::python {

namespace {

ModelFile reduce(const ModelFile& model, std::optional<Eigen::Index> order, std::optional<double> max_error,
                 std::optional<std::pair<double, double>> band, const std::string& method, bool keep_dc) {
  ReduceRequest request;
  request.method = band ? "modal" : method;
  if (order) request.order = *order;
  if (max_error) {
    if (!(*max_error > 0.0 && *max_error < 1.0))
      throw std::invalid_argument("max_error: expected a ratio in (0, 1) such as 0.02");
    request.max_error_ratio = *max_error;
  }
  request.band_hz = band;
  request.keep_dc_gain = keep_dc;
  ReducedModelFile reduced;
  {
    nb::gil_scoped_release release;
    reduced = reduce_model_file(model, request);
  }
  issue_warnings(reduced.warnings);
  return reduced.file;
}

Eigen::VectorXd hsv(const ModelFile& model) {
  HankelSingularValuesResult result;
  {
    nb::gil_scoped_release release;
    result = hankel_singular_values(model.model);
  }
  issue_warnings(result.warnings);
  return result.values;
}

}  // namespace

void bind_reduce(nb::module_& m) {
  m.def("reduce", &reduce, nb::arg("model"), nb::kw_only(), nb::arg("order") = nb::none(), nb::arg("max_error") = nb::none(),
        nb::arg("band") = nb::none(), nb::arg("method") = "balanced", nb::arg("keep_dc") = false,
        "Reduce a model; give exactly one of order, max_error (the HSV ratio (sum all - sum kept) / sum all,\n"
        "for example 0.02) and band ((lo, hi) Hz: modal truncation keeping the modes in the band).\n"
        "method: 'balanced' (square-root balanced truncation), 'spa' (singular perturbation: keeps the DC gain)\n"
        "or 'modal'. keep_dc: modal truncation adds the removed modes' static gain to D. A time-series model\n"
        "(no inputs) is reduced through its innovation form. Returns the reduced Model (provenance: the\n"
        "reduction, orders, HSV ratio, H-infinity bound and measured error), as `sysid reduce` writes it.");
  m.def("hsv", &hsv, nb::arg("model"),
        "Hankel singular values of the model's stable part, descending (`sysid hsv`); unstable states are\n"
        "left out (reduce keeps them whole).");
}

}  // namespace sysid::python
