// sysid.diagnose: where a simulation model and a recording disagree, the physics
// the simulation left out, and the augmented model (`sysid diagnose`; the report
// dict is the JSON report of DESIGN.md "diagnose: the report contract").
#include <sysid/core/discretize.hpp>
#include <sysid/diagnose/data_check.hpp>
#include <sysid/diagnose/diagnose.hpp>
#include <sysid/io/augmented_model_file.hpp>

#include <nanobind/stl/pair.h>


#include "bindings.hpp"

namespace sysid::python {

namespace {

std::pair<nb::object, ModelFile> run_diagnose(const ModelFile& nominal_file, const SampleArray& u, const SampleArray& y,
                                              double Ts, int max_findings, double significance, bool refit_nominal,
                                              std::optional<std::pair<SampleArray, SampleArray>> confirm,
                                              std::optional<std::vector<std::string>> output_quantity) {
  if (!(Ts > 0.0)) throw std::invalid_argument("diagnose: Ts must be > 0");
  AugmentedModel nominal = augmented_model_from_file(nominal_file, "nominal");
  nominal.nominal = model_at_sample_time(nominal_file.model, Ts, Hold::zoh, "nominal");  // as the command line does
  // One name for every output or one per output, as --output-quantity.
  if (output_quantity) nominal.output_quantities = parse_output_quantities(*output_quantity, nominal.nominal.outputs());
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

nb::dict channel_dict(const ChannelCheck& c, bool input) {
  nb::dict d;
  d["name"] = c.name;
  d["mean"] = c.mean;
  d["std"] = c.std;
  d["offset_ratio"] = c.offset_ratio;
  d["trend_ratio"] = c.trend_ratio;
  d["clipped_share"] = c.clipped_share;
  if (input) {
    d["excitation_order"] = c.excitation_order;
    d["excitation_singular_values"] = c.excitation_singular_values;
  } else {
    d["snr_db"] = c.snr_db;
  }
  return d;
}

/// The pre-flight check of `sysid check` (diagnose/data_check.hpp) as a dict.
nb::dict check(const std::optional<SampleArray>& u, const SampleArray& y, double Ts, std::optional<Eigen::VectorXd> time,
               Eigen::Index max_order, const std::vector<std::string>& inputs, const std::vector<std::string>& outputs) {
  IoData data = io_data(u, y, Ts, inputs, outputs);
  DataCheckOptions o;
  o.max_excitation_order = max_order;
  DataCheckResult r;
  {
    nb::gil_scoped_release release;
    r = check_data(data, time ? *time : Eigen::VectorXd(), o);
  }
  nb::dict out;
  nb::list in, outs, feedback;
  for (const ChannelCheck& c : r.inputs) in.append(channel_dict(c, true));
  for (const ChannelCheck& c : r.outputs) outs.append(channel_dict(c, false));
  for (const FeedbackCheck& f : r.feedback) {
    nb::dict d;
    d["input"] = f.input;
    d["output"] = f.output;
    d["largest_correlation"] = f.largest_correlation;
    d["at_lag"] = f.at_lag;
    d["bound"] = f.bound;
    d["likely"] = f.likely;
    feedback.append(d);
  }
  out["samples"] = r.samples;
  out["inputs"] = in;
  out["outputs"] = outs;
  out["feedback"] = feedback;
  out["findings"] = nb::cast(r.findings);
  out["report"] = r.report();
  return out;
}

}  // namespace

void bind_diagnose(nb::module_& m) {
  m.def("check", &check, nb::arg("u"), nb::arg("y"), nb::arg("Ts"), nb::kw_only(), nb::arg("time") = nb::none(),
        nb::arg("max_order") = DataCheckOptions{}.max_excitation_order, nb::arg("inputs") = std::vector<std::string>{},
        nb::arg("outputs") = std::vector<std::string>{},
        "The pre-flight check of `sysid check`: per input the excitation order, per output an SNR estimate, offsets,\n"
        "trends, clipping, the sampling (when `time`, the time stamps in seconds, is given) and feedback; `findings`\n"
        "lists each problem with its consequence, most serious first, and `report` is the printed text.");
  const DiagnoseOptions defaults;
  m.def("diagnose", &run_diagnose, nb::arg("nominal"), nb::arg("u"), nb::arg("y"), nb::arg("Ts"), nb::kw_only(),
        nb::arg("max_findings") = defaults.max_findings, nb::arg("significance") = defaults.significance,
        nb::arg("refit_nominal") = defaults.refit_nominal, nb::arg("confirm") = nb::none(),
        nb::arg("output_quantity") = nb::none(),
        "Compare a simulation model (nominal: a Model, continuous models are sampled with a zero-order hold)\n"
        "with a recording (u, y, Ts): where they disagree, the physics the nominal left out, each finding fitted\n"
        "and kept only if it improves the fit on held-out data. confirm=(u2, y2): fit on the whole record and\n"
        "confirm every finding on that independent recording. output_quantity: what the outputs measure\n"
        "(['velocity'], one name for all or one per output: position, velocity, acceleration, other), as\n"
        "--output-quantity; default: the model's own, or inferred. Returns (report, augmented): the JSON report of\n"
        "`sysid diagnose --json` as a dict, and the augmented Model (the nominal when nothing was found).");
}

}  // namespace sysid::python
