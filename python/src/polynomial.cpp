// sysid.arx, armax, oe, ar, arma: polynomial (prediction-error) models, one per
// output over all inputs, the same fit and the same model file as `sysid arx` ...
// (pem/polynomial_fit.hpp, io/polynomial_model_file.hpp).
#include <sysid/io/polynomial_model_file.hpp>
#include <sysid/pem/polynomial_fit.hpp>

#include <nanobind/stl/variant.h>

#include <variant>

#include "bindings.hpp"

namespace sysid::python {

namespace {

using PerInput = std::variant<int, std::vector<int>>;

/// One value for every input, or one per input.
std::vector<int> per_input(const PerInput& value, Eigen::Index inputs, const char* name) {
  if (const int* v = std::get_if<int>(&value)) return std::vector<int>(static_cast<std::size_t>(inputs), *v);
  const auto& list = std::get<std::vector<int>>(value);
  if (static_cast<Eigen::Index>(list.size()) != inputs)
    throw std::invalid_argument(std::string(name) + ": expected one value or one per input (" + std::to_string(inputs) +
                                "), found " + std::to_string(list.size()));
  return list;
}

/// Fits `options` on the data and returns the model file; a minimisation that did
/// not converge raises NumericalError unless `allow_unconverged` (the command
/// line's --write-unconverged). Warnings are RuntimeWarnings.
ModelFile fit(const std::optional<SampleArray>& u, const SampleArray& y, double Ts, PolynomialFitOptions options,
              bool allow_unconverged, const std::vector<std::string>& inputs, const std::vector<std::string>& outputs) {
  IoData data = io_data(u, y, Ts, inputs, outputs);
  ModelFile file;
  PolynomialFit result;
  {
    nb::gil_scoped_release release;
    result = fit_polynomial(data, options);
    file = polynomial_fit_model_file(result, options, data.input_names, data.output_names);
  }
  issue_warnings(result.warnings);
  if (!result.converged && !allow_unconverged) {
    std::string notes;
    for (const std::string& n : result.method_notes) notes += (notes.empty() ? "" : "; ") + n;
    throw NumericalError(std::string(to_string(options.structure)) + ": the prediction-error minimisation did not converge (" +
                         notes + "); allow_unconverged=True returns the model anyway");
  }
  return file;
}

PolynomialFitOptions with_inputs(PolynomialStructure structure, const std::optional<SampleArray>& u, const PerInput& nb,
                                 const PerInput& nk, int max_iterations) {
  if (!u) throw std::invalid_argument(std::string(to_string(structure)) + ": needs the inputs u (ar and arma take none)");
  const Eigen::Index m = u->ndim() == 2 ? static_cast<Eigen::Index>(u->shape(1)) : 1;
  PolynomialFitOptions options;
  options.structure = structure;
  options.orders.nb = per_input(nb, m, "nb");
  options.orders.nk = per_input(nk, m, "nk");
  options.max_iterations = max_iterations;
  return options;
}

const char* const kNamesDoc = "\ninputs/outputs: channel names (None: u1.., y1..).";

}  // namespace

void bind_polynomial(nb::module_& m) {
  const int iterations = PolynomialFitOptions{}.max_iterations;
  m.def(
      "arx",
      [](const std::optional<SampleArray>& u, const SampleArray& y, double Ts, int na, const PerInput& nb,
         const PerInput& nk, const std::vector<std::string>& inputs, const std::vector<std::string>& outputs) {
        PolynomialFitOptions o = with_inputs(PolynomialStructure::arx, u, nb, nk, PolynomialFitOptions{}.max_iterations);
        o.orders.na = na;
        return fit(u, y, Ts, o, false, inputs, outputs);
      },
      nb::arg("u"), nb::arg("y"), nb::arg("Ts"), nb::kw_only(), nb::arg("na"), nb::arg("nb"), nb::arg("nk") = 1,
      nb::arg("inputs") = std::vector<std::string>{}, nb::arg("outputs") = std::vector<std::string>{},
      (std::string("ARX model A(q) y = B(q) u + e by linear least squares (QR), one per output over all inputs.\n"
                   "na: order of A; nb, nk: numerator order and delay, one value or one per input.") + kNamesDoc)
          .c_str());
  m.def(
      "armax",
      [](const std::optional<SampleArray>& u, const SampleArray& y, double Ts, int na, const PerInput& nb, int nc,
         const PerInput& nk, int max_iterations, bool allow_unconverged, const std::vector<std::string>& inputs,
         const std::vector<std::string>& outputs) {
        PolynomialFitOptions o = with_inputs(PolynomialStructure::armax, u, nb, nk, max_iterations);
        o.orders.na = na;
        o.orders.nc = nc;
        return fit(u, y, Ts, o, allow_unconverged, inputs, outputs);
      },
      nb::arg("u"), nb::arg("y"), nb::arg("Ts"), nb::kw_only(), nb::arg("na"), nb::arg("nb"), nb::arg("nc"),
      nb::arg("nk") = 1, nb::arg("max_iterations") = iterations, nb::arg("allow_unconverged") = false,
      nb::arg("inputs") = std::vector<std::string>{}, nb::arg("outputs") = std::vector<std::string>{},
      (std::string("ARMAX model A y = B u + C e by prediction-error minimisation (Levenberg-Marquardt).\n"
                   "Raises sysid.NumericalError when it does not converge unless allow_unconverged.") + kNamesDoc)
          .c_str());
  m.def(
      "oe",
      [](const std::optional<SampleArray>& u, const SampleArray& y, double Ts, const PerInput& nb, const PerInput& nf,
         const PerInput& nk, int max_iterations, bool allow_unconverged, const std::vector<std::string>& inputs,
         const std::vector<std::string>& outputs) {
        PolynomialFitOptions o = with_inputs(PolynomialStructure::oe, u, nb, nk, max_iterations);
        o.orders.nf = per_input(nf, static_cast<Eigen::Index>(o.orders.nb.size()), "nf");
        return fit(u, y, Ts, o, allow_unconverged, inputs, outputs);
      },
      nb::arg("u"), nb::arg("y"), nb::arg("Ts"), nb::kw_only(), nb::arg("nb"), nb::arg("nf"), nb::arg("nk") = 1,
      nb::arg("max_iterations") = iterations, nb::arg("allow_unconverged") = false,
      nb::arg("inputs") = std::vector<std::string>{}, nb::arg("outputs") = std::vector<std::string>{},
      (std::string("Output-error model y = B/F u + e by prediction-error minimisation.\n"
                   "nb, nf, nk: one value or one per input.") + kNamesDoc)
          .c_str());
  m.def(
      "ar",
      [](const SampleArray& y, double Ts, int na, const std::string& method, const std::vector<std::string>& outputs) {
        PolynomialFitOptions o;
        o.structure = PolynomialStructure::ar;
        o.orders.na = na;
        o.ar_method = ar_method_from_name(method);
        return fit(std::nullopt, y, Ts, o, false, {}, outputs);
      },
      nb::arg("y"), nb::arg("Ts"), nb::kw_only(), nb::arg("na"), nb::arg("method") = "ls",
      nb::arg("outputs") = std::vector<std::string>{},
      "AR time-series model A(q) y = e, one per output. method: 'ls' (least squares), 'yw' (Yule-Walker),\n"
      "'burg', 'myw' (modified Yule-Walker: unbiased under white measurement noise).");
  m.def(
      "arma",
      [](const SampleArray& y, double Ts, int na, int nc, int max_iterations, bool allow_unconverged,
         const std::vector<std::string>& outputs) {
        PolynomialFitOptions o;
        o.structure = PolynomialStructure::arma;
        o.orders.na = na;
        o.orders.nc = nc;
        o.max_iterations = max_iterations;
        return fit(std::nullopt, y, Ts, o, allow_unconverged, {}, outputs);
      },
      nb::arg("y"), nb::arg("Ts"), nb::kw_only(), nb::arg("na"), nb::arg("nc"), nb::arg("max_iterations") = iterations,
      nb::arg("allow_unconverged") = false, nb::arg("outputs") = std::vector<std::string>{},
      "ARMA time-series model A(q) y = C(q) e by prediction-error minimisation, one per output.");
}

}  // namespace sysid::python
