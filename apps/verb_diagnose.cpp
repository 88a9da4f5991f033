// sysid diagnose: where a simulation model and a recording disagree, which
// physics the simulation left out, the augmented model, and the held-out proof.
#include <sysid/diagnose/diagnose.hpp>
#include <sysid/io/atomic_file.hpp>
#include <sysid/io/augmented_model_file.hpp>
#include <sysid/spectral/welch.hpp>
#include <sysid/validate/fit.hpp>

#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "cli_common.hpp"
#include "plot.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

struct DiagnoseArgs {
  std::string model_path, log_path, json_path, out, validate, plot;
  std::vector<std::string> output_quantities;
  LogArgs log;
  int max_findings = 4;
  double significance = 0.01;
  int substeps = 0;
  bool refit_nominal = false, confirm = false;
  double fit_fraction = 0.5, selection_fraction = 0.2;
  Eigen::Index min_segment = 200;
};

std::string describe_finding(std::size_t rank, const Finding& f) {
  std::ostringstream s;
  s << "  " << rank << ". " << f.candidate.block.kind << ": " << f.summary << "\n"
    << "     validation fit " << fmt(f.fit_before, 4) << " -> " << fmt(f.fit_after, 4) << " %; selection gain "
    << fmt(f.selection_gain, 3) << " points (t = " << fmt(f.t_statistic, 3) << ")\n";
  return s.str();
}

/// Outputs drawn at most.
constexpr Eigen::Index kDiagnosePlotOutputs = 4;

/// Per output: the residual spectrum before and after on the held-out part with
/// the located bands shaded, the residual energy by time window against its
/// threshold, and measured / nominal / augmented over the held-out samples.
void plot_diagnose(const DiagnoseArgs& a, const LoadedLog& log, const DiagnoseReport& r, const std::vector<std::string>& outputs) {
  const Experiment& e = log.data.experiments.front();
  const Eigen::Index N = e.samples(), start = r.estimation_rows, V = N - start;
  const double fs = 1.0 / log.data.Ts;
  PlotFigure fig;
  fig.title = "diagnose " + a.model_path + " on " + a.log_path + ": held-out fit " + fmt(r.fit_before, 4) + " -> " +
              fmt(r.fit_after, 4) + " %";
  fig.columns = 1;
  for (Eigen::Index i = 0; i < std::min<Eigen::Index>(e.y.cols(), kDiagnosePlotOutputs); ++i) {
    const std::string name = outputs[static_cast<std::size_t>(i)];
    WelchOptions wo;
    wo.nfft = 1024;
    const PowerSpectrum before = welch_psd(e.y.col(i).tail(V) - r.simulated_before.col(i).tail(V), fs, wo);
    const PowerSpectrum after = welch_psd(e.y.col(i).tail(V) - r.simulated_after.col(i).tail(V), fs, wo);
    PlotPanel spectrum;
    spectrum.title = name + ": residual spectrum on the held-out samples (located bands shaded)";
    spectrum.xlabel = "frequency [Hz]";
    spectrum.ylabel = "PSD [units^2/Hz]";
    spectrum.logy = true;
    const Eigen::Index bins = before.freq_hz.size() - 1;  // DC left out (log axis)
    PlotCurve b, f;
    b.title = "nominal";
    b.x = before.freq_hz.tail(bins);
    b.y = before.psd.col(0).tail(bins);
    f.title = "augmented";
    f.x = after.freq_hz.tail(bins);
    f.y = after.psd.col(0).tail(bins);
    f.dashed = true;
    const double lo = std::max(before.psd.col(0).tail(bins).minCoeff(), 1e-300), hi = before.psd.col(0).tail(bins).maxCoeff();
    if (i < static_cast<Eigen::Index>(r.location.outputs.size()))
      for (const auto& band : r.location.outputs[static_cast<std::size_t>(i)].bands) {
        PlotCurve shade;
        shade.x = Eigen::Vector2d(band.lo_hz, std::max(band.hi_hz, band.lo_hz + fs / 1024));
        shade.y = shade.hi = Eigen::Vector2d(hi, hi);
        shade.lo = Eigen::Vector2d(lo, lo);
        shade.color = 3;
        spectrum.curves.push_back(shade);
      }
    spectrum.curves.push_back(b);
    spectrum.curves.push_back(f);
    fig.panels.push_back(spectrum);

    if (i < static_cast<Eigen::Index>(r.location.outputs.size())) {
      const auto& ch = r.location.outputs[static_cast<std::size_t>(i)];
      PlotPanel windows;
      windows.title = name + ": nominal residual energy by time window (estimation part) / noise floor";
      windows.xlabel = "time [s]";
      windows.ylabel = "energy ratio";
      const auto W = static_cast<Eigen::Index>(ch.windows.size());
      PlotCurve energy, threshold;
      energy.title = "window";
      energy.style = "impulses";
      threshold.title = "threshold";
      threshold.dashed = true;
      energy.x = energy.y = threshold.x = threshold.y = Eigen::VectorXd(W);
      for (Eigen::Index w = 0; w < W; ++w) {
        const auto& win = ch.windows[static_cast<std::size_t>(w)];
        energy.x(w) = threshold.x(w) = 0.5 * (win.t0_s + win.t1_s);
        energy.y(w) = win.energy_ratio;
        threshold.y(w) = ch.window_threshold;
      }
      windows.curves = {energy, threshold};
      if (W > 0) fig.panels.push_back(windows);
    }

    const Eigen::Index stride = plot_stride(V, 4000), np = (V + stride - 1) / stride;
    PlotPanel overlay;
    overlay.title = name + ": held-out samples";
    overlay.xlabel = "time [s]";
    overlay.ylabel = name;
    PlotCurve measured, nominal, augmented;
    measured.title = "measured";
    nominal.title = "nominal";
    augmented.title = "augmented";
    augmented.dashed = true;
    for (PlotCurve* c : {&measured, &nominal, &augmented}) {
      c->x.resize(np);
      c->y.resize(np);
    }
    for (Eigen::Index k = 0; k < np; ++k) {
      const Eigen::Index row = start + k * stride;
      measured.x(k) = nominal.x(k) = augmented.x(k) = log.seconds_at(row);
      measured.y(k) = e.y(row, i);
      nominal.y(k) = r.simulated_before(row, i);
      augmented.y(k) = r.simulated_after(row, i);
    }
    overlay.curves = {measured, nominal, augmented};
    fig.panels.push_back(overlay);
  }
  write_plot(fig, a.plot, "diagnose");
}

void run_diagnose(const DiagnoseArgs& a) {
  const std::string verb = "diagnose";
  std::vector<std::string> sources{a.model_path, a.log_path};
  if (!a.validate.empty()) sources.push_back(a.validate);
  claim_outputs({a.json_path, a.out, a.plot}, sources);

  const ModelFile file = load_model(a.model_path, /*allow_augmented=*/true);
  const auto [inputs, outputs] = model_channels(a.log, file, true);
  const LoadedLog log = load_log(a.log_path, make_log_options(a.log, inputs, outputs));
  AugmentedModel nominal = augmented_model_from_file(file, a.model_path);
  nominal.nominal = model_for_sample_time(file, log.data.Ts, a.model_path, verb);
  const Experiment& e = log.data.experiments.front();
  if (!a.output_quantities.empty()) {
    try {
      nominal.output_quantities = parse_output_quantities(a.output_quantities, e.y.cols());
    } catch (const std::invalid_argument& ex) {
      throw CLI::ValidationError("--output-quantity", ex.what());
    }
  }

  DiagnoseOptions o;
  o.max_findings = a.max_findings;
  o.significance = a.significance;
  o.detection.feedback_substeps = a.substeps;
  o.refit_nominal = a.refit_nominal;
  o.fit_fraction = a.fit_fraction;
  o.selection_fraction = a.selection_fraction;
  o.min_segment_samples = a.min_segment;
  std::optional<LoadedLog> other;
  if (!a.validate.empty()) {
    other = load_log(a.validate, make_log_options(a.log, inputs, outputs));
    if (std::abs(other->data.Ts - log.data.Ts) > 1e-6 * log.data.Ts)
      throw DataError(a.validate, 0, 0, "sample time differs from " + a.log_path + "'s");
  }
  DiagnoseReport report;
  try {
    if (a.confirm) {
      const Experiment& v = other->data.experiments.front();
      report = diagnose_confirmed(nominal, e.u, e.y, v.u, v.y, o);
    } else {
      report = diagnose(nominal, e.u, e.y, o);
    }
  } catch (const std::invalid_argument& ex) {
    throw DataError(a.log_path, 0, 0, ex.what());  // too short a record, channel mismatch
  }
  nlohmann::json j = diagnose_report_to_json(report, log.data.Ts);
  j["data"] = a.log_path;
  j["nominal"] = a.model_path;

  if (a.confirm) {
    // The library measured every fit on the confirming recording.
    j["validation"] = a.validate + " (initial state estimated; it confirmed each finding)";
    j["validation_file"] = a.validate;
  } else if (other) {
    // An independent recording, when given, is the validation the report leads with.
    const Experiment& v = other->data.experiments.front();
    AugmentedModel plain = report.augmented;
    plain.blocks = nominal.blocks;
    const RecordingValidation fits = validate_on_recording(plain, report.augmented, v.u, v.y);
    j["held_out_segment"] = {{"validation", report.validation}, {"fit_before", report.fit_before}, {"fit_after", report.fit_after}};
    j["validation"] = a.validate + " (initial state estimated)";
    j["validation_file"] = a.validate;
    j["fit_before"] = fits.fit_before.mean();
    j["fit_after"] = fits.fit_after.mean();
  }

  std::ostringstream s;
  s << "diagnose " << a.model_path << " against " << a.log_path << " (" << e.samples() << " samples)\n";
  s << "mismatch tests on the estimation part: "
    << (report.location.any_mismatch ? "mismatch (" + join(report.location.fired) + ")" : "no significant mismatch") << "\n";
  s << "validation (" << j["validation"].get<std::string>() << "): fit " << fmt(j["fit_before"].get<double>(), 4) << " -> "
    << fmt(j["fit_after"].get<double>(), 4) << " %\n";
  if (report.findings.empty() && !report.location.any_mismatch)
    s << "findings: none — the simulation is consistent with the recording\n";
  else if (report.findings.empty())
    s << "findings: none that the library's kinds of physics explain — but the recording disagrees with the simulation ("
      << join(report.location.fired) << "): what is missing is not among the kinds diagnose knows\n";
  else s << "findings (most important first):\n";
  for (std::size_t k = 0; k < report.findings.size(); ++k) s << describe_finding(k + 1, report.findings[k]);
  for (const auto& w : report.warnings) warn(verb, w);
  std::cout << s.str();

  if (!a.json_path.empty()) {
    write_file_atomically(a.json_path, j.dump(2) + "\n");
    note(verb, "wrote the report to " + a.json_path);
  }
  if (!a.plot.empty()) plot_diagnose(a, log, report, outputs);
  if (!a.out.empty()) {
    nlohmann::json provenance = {{"method", "diagnose"}, {"nominal", a.model_path}, {"data", a.log_path},
                                 {"fit_percent", report.fit_after},
                                 {"validation", a.confirm ? j["validation"].get<std::string>() : report.validation}};
    write_model_json(a.out, augmented_model_to_file(report.augmented, provenance));
    note(verb, "wrote the " + std::string(report.findings.empty() ? "(unchanged) nominal" : "augmented") + " model to " + a.out);
  }
}

}  // namespace

Verb register_diagnose(CLI::App& app) {
  auto args = std::make_shared<DiagnoseArgs>();
  CLI::App* cmd = app.add_subcommand(
      "diagnose", "Find where a simulation model and a recording disagree, name the missing physics, model it");
  cmd->add_option("--model", args->model_path, "the simulation (nominal) model: state-space, polynomial or augmented JSON")
      ->required();
  cmd->add_option("log", args->log_path, "CSV log recorded on the real machine")->required();
  LogOptionSpec spec;
  spec.inputs_required = false;
  spec.outputs_required = false;
  spec.inputs_help = "input columns, in the model's input order (default: the model's input names)";
  spec.outputs_help = "output columns, in the model's output order (default: the model's output names)";
  add_log_options(*cmd, args->log, spec);
  cmd->add_option("--json", args->json_path, "write the report (DESIGN.md report contract) to this JSON file");
  cmd->add_option("--out", args->out, "write the augmented model (\"type\": \"augmented\") to this JSON file");
  cmd->add_option("--plot", args->plot,
                  "residual spectra before/after with the located bands, residual energy by window, and held-out "
                  "time series (.svg or .png; needs gnuplot)")
      ->check(plot_path_validator());
  cmd->add_option("--output-quantity", args->output_quantities,
                  "what each output measures: position, velocity, acceleration or other (one for all outputs, or one per "
                  "output, comma-separated); overrides the model file's output_quantities. Forces inside the plant "
                  "(friction, springs, constant forces) act on the actuator's position and velocity, which each quantity "
                  "gives differently; when it is not known diagnose tries each reading and says which it used")
      ->delimiter(',')
      ->check(CLI::IsMember({"position", "velocity", "acceleration", "other"}));
  CLI::Option* validate = cmd->add_option("--validate", args->validate, "an independent recording (same columns) to report the fit on");
  cmd->add_option("--max-findings", args->max_findings, "at most this many effects are added")
      ->capture_default_str()
      ->check(CLI::Range(1, 13));
  cmd->add_option("--significance", args->significance, "level of the acceptance test per round (Bonferroni over the candidates)")
      ->capture_default_str()
      ->check(CLI::Range(1e-9, 0.5));
  cmd->add_option("--substeps", args->substeps,
                  "simulation steps per sample for forces inside the plant (0: 4 when the model has no direct "
                  "feedthrough D, else 1 with the feedthrough solved implicitly)")
      ->capture_default_str()
      ->check(CLI::Range(0, 64));
  cmd->add_flag("--refit-nominal", args->refit_nominal,
               "refit the nominal's linear dynamics together with each candidate (for a nominal identified from this "
               "machine, whose poles hold a compromise of the nonlinearity); candidates are then judged against the "
               "linear dynamics refitted alone");
  cmd->add_flag("--confirm", args->confirm,
               "with --validate: fit and rank the candidates on the whole log and accept each round's best only if "
               "the --validate recording confirms it (one test per round at --significance); for a short log whose "
               "effect shows in few episodes. --fit-fraction and --selection-fraction are then not used")
      ->needs(validate);
  cmd->add_option("--fit-fraction", args->fit_fraction, "leading part of the record that fits the candidates")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 0.9));
  cmd->add_option("--selection-fraction", args->selection_fraction, "next part, which ranks and accepts them; the rest is held out")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 0.9));
  cmd->add_option("--min-segment", args->min_segment, "fewest samples in each of the three parts")
      ->capture_default_str()
      ->check(CLI::Range(50, 1000000000));
  cmd->footer(
      "The record is split in time: the first 50 % fits the candidate physics, the next 20 %\n"
      "ranks and accepts them (a paired test on the simulation errors), the last 30 % is\n"
      "held out from every fit and gives fit_before / fit_after (--fit-fraction,\n"
      "--selection-fraction). A record whose effect shows in few episodes needs one in each\n"
      "of the first two parts, or a second recording: --validate FILE --confirm.\n"
      "Example:\n"
      "  sysid diagnose --model nominal.json log.csv --inputs u --outputs y --json report.json --out augmented.json");
  add_hold_option(*cmd);
  return {cmd, [args] { run_diagnose(*args); }};
}

}  // namespace sysid::cli
