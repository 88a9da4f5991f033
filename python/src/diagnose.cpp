// sysid.diagnose: where a simulation model and a recording disagree, the physics
// the simulation left out, and the augmented model (`sysid diagnose`; the report
// dict is the JSON report of DESIGN.md "diagnose: the report contract").
#include <sysid/core/discretize.hpp>
#include <sysid/diagnose/diagnose.hpp>
#include <sysid/io/augmented_model_file.hpp>

#include <nanobind/stl/pair.h>

#include <cmath>

#include "bindings.hpp"

namespace sysid::python {

namespace {

std::pair<nb::object, ModelFile> run_diagnose(const ModelFile& nominal_file, const SampleArray& u, const SampleArray& y,
                                              double Ts, int max_findings, double significance, bool refit_nominal,
                                              std::optional<std::pair<SampleArray, SampleArray>> confirm) {
  if (!(Ts > 0.0)) throw std::invalid_argument("diagnose: Ts must be > 0");
  AugmentedModel nominal = augmented_model_from_file(nominal_file, "nominal");
  if (!nominal_file.model.is_discrete()) {
    nominal.nominal = c2d(nominal_file.model, Ts, Hold::zoh);  // names kept, as the command line does
  } else if (std::abs(nominal_file.model.Ts - Ts) > 1e-6 * nominal_file.model.Ts) {
    throw DataError("the nominal's sample time " + nlohmann::json(nominal_file.model.Ts).dump() + " s differs from Ts " +
                    nlohmann::json(Ts).dump() + " s; a discrete-time model runs only at its own rate");
  }
  DiagnoseOptions o;
  o.max_findings = max_findings;
  o.significance = significance;
  o.refit_nominal = refit_nominal;
  const Eigen::MatrixXd u_samples = sample_view(u, "u"), y_samples = sample_view(y, "y");
  Eigen::MatrixXd u_confirm, y_confirm;
  if (confirm) {
    u_confirm = sample_view(confirm->first, "u (confirm)");
    y_confirm = sample_view(confirm->second, "y (confirm)");
  }
  DiagnoseReport report;
  nlohmann::json j;
  {
    nb::gil_scoped_release release;
    try {
      report = confirm ? diagnose_confirmed(nominal, u_samples, y_samples, u_confirm, y_confirm, o)
                       : diagnose(nominal, u_samples, y_samples, o);
    } catch (const std::invalid_argument& e) {
      throw DataError(e.what());  // too short a record, channel mismatch: the data's fault, as on the command line
    }
    j = diagnose_report_to_json(report, Ts);
  }
  issue_warnings(report.warnings);
  const nlohmann::json provenance = {{"method", "diagnose"}, {"fit_percent", report.fit_after}, {"validation", report.validation}};
  return {to_python(j), augmented_model_to_file(report.augmented, provenance)};
}

}  // namespace

void bind_diagnose(nb::module_& m) {
  const DiagnoseOptions defaults;
  m.def("diagnose", &run_diagnose, nb::arg("nominal"), nb::arg("u"), nb::arg("y"), nb::arg("Ts"), nb::kw_only(),
        nb::arg("max_findings") = defaults.max_findings, nb::arg("significance") = defaults.significance,
        nb::arg("refit_nominal") = defaults.refit_nominal, nb::arg("confirm") = nb::none(),
        "Compare a simulation model (nominal: a Model, continuous models are sampled with a zero-order hold)\n"
        "with a recording (u, y, Ts): where they disagree, the physics the nominal left out, each finding fitted\n"
        "and kept only if it improves the fit on held-out data. confirm=(u2, y2): fit on the whole record and\n"
        "confirm every finding on that independent recording. Returns (report, augmented): the JSON report of\n"
        "`sysid diagnose --json` as a dict, and the augmented Model (the nominal when nothing was found).");
}

}  // namespace sysid::python
