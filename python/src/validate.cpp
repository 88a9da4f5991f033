// sysid.fit_percent, sysid.compare and sysid.resid: the fit of DESIGN.md ("Fit and
// validation"), simulation or k-step prediction on a record, and the residual
// analysis `sysid resid` prints (validate/).
#include <sysid/io/polynomial_model_file.hpp>
#include <sysid/validate/compare.hpp>
#include <sysid/validate/fit.hpp>
#include <sysid/validate/residual_analysis.hpp>

#include <nanobind/stl/pair.h>

#include <algorithm>

#include "bindings.hpp"

namespace sysid::python {

namespace {

/// x0: "estimate" (least squares on the record), "zero", "model" (the file's x0).
CompareOptions compare_options(const ModelFile& model, const std::string& x0) {
  CompareOptions o;
  if (x0 != "estimate" && x0 != "zero" && x0 != "model")
    throw std::invalid_argument("x0: expected 'estimate', 'zero' or 'model', found '" + x0 + "'");
  o.estimate_x0 = x0 == "estimate";
  if (x0 == "model") {
    if (model.x0.size() == 0) throw std::invalid_argument("x0='model': the model has no x0");
    o.x0 = model.x0;
  }
  o.input_offset = model.input_offset;
  o.output_offset = model.output_offset;
  return o;
}

Experiment experiment(const ModelFile& model, const std::optional<SampleArray>& u, const SampleArray& y) {
  if (!model.model.is_discrete())
    throw std::invalid_argument("a continuous-time model (Ts = 0): sample it first (it runs only on a sampled record)");
  IoData data = io_data(u, y, model.model.Ts, {}, {});
  if (data.inputs() != model.model.inputs() || data.outputs() != model.model.outputs())
    throw std::invalid_argument("the record has " + std::to_string(data.inputs()) + " input(s) and " +
                                std::to_string(data.outputs()) + " output(s), the model " +
                                std::to_string(model.model.inputs()) + " and " + std::to_string(model.model.outputs()));
  return std::move(data.experiments.front());
}

std::pair<Eigen::VectorXd, Eigen::MatrixXd> compare_model(const ModelFile& model, const std::optional<SampleArray>& u,
                                                          const SampleArray& y, int steps, const std::string& x0) {
  Experiment e = experiment(model, u, y);
  CompareOptions o = compare_options(model, x0);
  o.predict_steps = steps;
  CompareResult r;
  {
    nb::gil_scoped_release release;
    r = compare(model.model, model.K, e, o);
  }
  return {std::move(r.fit_percent), std::move(r.y_hat)};
}

nb::dict residual_analysis(const ModelFile& model, const std::optional<SampleArray>& u, const SampleArray& y,
                           Eigen::Index max_lag, double confidence, std::optional<Eigen::Index> noise_params,
                           const std::string& x0) {
  Experiment e = experiment(model, u, y);
  ResidualAnalysisOptions ro;
  ro.max_lag = max_lag;
  ro.confidence = confidence;
  if (noise_params) {
    ro.noise_parameters = *noise_params;
  } else {  // as `sysid resid`: the noise model's parameters (na + nc + nd) of a polynomial model
    const std::vector<Eigen::Index> counts = noise_model_parameter_counts(model, "model");
    ro.noise_parameters = counts.empty() ? 0 : *std::max_element(counts.begin(), counts.end());
  }
  ro.output_names = model.model.output_names_or_defaults();
  ro.input_names = model.model.input_names_or_defaults();
  Eigen::MatrixXd residuals;
  ResidualAnalysisResult r;
  {
    nb::gil_scoped_release release;
    residuals = model_residuals(model.model, model.K, e, compare_options(model, x0));
    if (!residuals.allFinite())
      throw NumericalError(std::string("the residuals are not finite: the model's ") +
                           (model.K.size() ? "predictor A - K C" : "A") + " is unstable");
    r = analyze_residuals(residuals, e.u, ro);
  }
  nb::dict out;
  out["residuals"] = residuals;
  out["autocorrelation"] = r.autocorrelation;
  out["autocorrelation_bound"] = r.autocorrelation_bound;
  out["input_correlation"] = r.input_correlation;
  out["input_correlation_bound"] = r.input_correlation_bound;
  out["ljung_box_q"] = r.ljung_box_q;
  out["ljung_box_p"] = r.ljung_box_p;
  nb::list white, independent, whiteness, independence;
  for (const ResidualVerdict& v : r.verdicts) {
    white.append(v.white);
    independent.append(nb::cast(v.independent));
    whiteness.append(v.whiteness);
    independence.append(nb::cast(v.independence));
  }
  out["white"] = white;
  out["independent"] = independent;
  out["whiteness"] = whiteness;
  out["independence"] = independence;
  out["warnings"] = nb::cast(r.warnings);
  return out;
}

}  // namespace

void bind_validate(nb::module_& m) {
  m.def(
      "fit_percent",
      [](const SampleArray& y, const SampleArray& y_hat) {
        return Eigen::VectorXd(fit_percent(sample_view(y, "y"), sample_view(y_hat, "y_hat")));
      },
      nb::arg("y"), nb::arg("y_hat"),
      "Per output, 100 (1 - ||y - y_hat|| / ||y - mean(y)||) (DESIGN.md 'Fit and validation').");
  m.def("compare", &compare_model, nb::arg("model"), nb::arg("u"), nb::arg("y"), nb::kw_only(), nb::arg("steps") = 0,
        nb::arg("x0") = "estimate",
        "The model on a record (`sysid compare`): (fit_percent per output, y_hat). steps 0: simulation; k >= 1:\n"
        "k-step prediction (needs K). x0: 'estimate' (least squares on the record), 'zero' or 'model'.");
  m.def("resid", &residual_analysis, nb::arg("model"), nb::arg("u"), nb::arg("y"), nb::kw_only(), nb::arg("max_lag") = 25,
        nb::arg("confidence") = 0.99, nb::arg("noise_params") = nb::none(), nb::arg("x0") = "estimate",
        "Residual analysis (`sysid resid`): one-step prediction errors (simulation errors without K), their\n"
        "autocorrelation and correlation with the inputs with bounds, the Ljung-Box test, and per output the\n"
        "verdicts white / independent with their sentences. A dict.");
}

}  // namespace sysid::python
