// sysid compare: fit % of a model on a log, by simulation or k-step prediction.
#include <sysid/fem/sparse_frf.hpp>
#include <sysid/io/atomic_file.hpp>
#include <sysid/io/fem_model_file.hpp>
#include <sysid/validate/compare.hpp>
#include <sysid/validate/frequency_compare.hpp>

#include <iostream>
#include <limits>
#include <memory>
#include <numbers>

#include "cli_common.hpp"
#include "plot.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

struct CompareArgs {
  std::string model_path, log_path;
  LogArgs log;
  int predict = 0;
  std::string x0 = "estimate";
  std::string band;  ///< LO:HI: frequency-domain comparison against the data's H1
  Eigen::Index nfft = 1024;
  std::string plot;
  std::string fem_path;  ///< --fem: a finite-element model compared in the band (no time-domain fit)
};

/// Outputs drawn in the time-series plot at most.
constexpr Eigen::Index kMaxPlotOutputs = 6;
/// Pairs drawn in the Bode overlay at most.
constexpr Eigen::Index kMaxPlotPairs = 4;

/// Time-series overlay (measured vs model) per output, and with the band the Bode
/// overlay of the model and the data's estimate.
void plot_compare(const CompareArgs& a, const LoadedLog& log, const CompareResult* r, const std::vector<std::string>& inputs,
                  const std::vector<std::string>& outputs, const FrequencyCompareResult* fc, const std::string& how) {
  const Experiment& e = log.data.experiments.front();
  const Eigen::Index n = e.samples(), stride = plot_stride(n);
  const Eigen::Index np = (n + stride - 1) / stride;
  Eigen::VectorXd t(np);
  for (Eigen::Index k = 0; k < np; ++k) t(k) = log.seconds_at(k * stride);
  PlotFigure fig;
  fig.title = (a.fem_path.empty() ? a.model_path : a.fem_path) + " on " + a.log_path + " (" + how +
              (stride > 1 && r != nullptr ? ", every " + std::to_string(stride) + "th sample drawn" : "") + ")";
  for (Eigen::Index i = 0; r != nullptr && i < std::min<Eigen::Index>(e.y.cols(), kMaxPlotOutputs); ++i) {
    PlotPanel p;
    p.title = outputs[static_cast<std::size_t>(i)] + ": fit " + fmt(r->fit_percent(i), 4) + " %";
    p.xlabel = "time [s]";
    p.ylabel = outputs[static_cast<std::size_t>(i)];
    PlotCurve meas, sim;
    meas.title = "measured";
    sim.title = "model";
    sim.dashed = true;
    meas.x = sim.x = t;
    meas.y.resize(np);
    sim.y.resize(np);
    for (Eigen::Index k = 0; k < np; ++k) {
      meas.y(k) = e.y(k * stride, i);
      sim.y(k) = r->y_hat(k * stride, i);
    }
    p.curves = {meas, sim};
    fig.panels.push_back(std::move(p));
  }
  if (fc != nullptr) {
    std::vector<BodeCurve> curves;
    const FrfResult& h = fc->data_frf;
    std::vector<Eigen::Index> in_band;
    for (Eigen::Index k = 0; k < h.freq_hz.size(); ++k)
      if (h.freq_hz(k) > 0.0 && h.freq_hz(k) >= fc->f_lo_hz && h.freq_hz(k) <= fc->f_hi_hz) in_band.push_back(k);
    const auto nb = static_cast<Eigen::Index>(in_band.size());
    int color = 0;
    for (std::size_t q = 0; q < fc->pairs.size() && static_cast<Eigen::Index>(q) < kMaxPlotPairs; ++q, ++color) {
      const auto& pr = fc->pairs[q];
      BodeCurve data, model;
      const std::string name = outputs[static_cast<std::size_t>(pr.output)] + " <- " + inputs[static_cast<std::size_t>(pr.input)];
      data.title = name + " data (H1)";
      model.title = name + " model";
      data.color = model.color = color;
      model.dashed = true;
      data.f = model.f = Eigen::VectorXd(nb);
      data.h = model.h = Eigen::VectorXcd(nb);
      data.mag_lo = data.mag_hi = data.phase_halfwidth_deg = Eigen::VectorXd(nb);
      for (Eigen::Index k = 0; k < nb; ++k) {
        const auto b = static_cast<std::size_t>(in_band[static_cast<std::size_t>(k)]);
        data.f(k) = h.freq_hz(in_band[static_cast<std::size_t>(k)]);
        data.h(k) = h.H[b](pr.output, pr.input);
        model.h(k) = fc->model_frf[b](pr.output, pr.input);
        data.mag_lo(k) = h.magnitude_lower[b](pr.output, pr.input);
        data.mag_hi(k) = h.magnitude_upper[b](pr.output, pr.input);
        data.phase_halfwidth_deg(k) = h.phase_halfwidth_rad[b](pr.output, pr.input) * 180.0 / std::numbers::pi;
      }
      model.f = data.f;
      curves.push_back(std::move(data));
      curves.push_back(std::move(model));
    }
    for (PlotPanel& p : bode_panels(curves, "model vs data " + fmt(fc->f_lo_hz) + ".." + fmt(fc->f_hi_hz) + " Hz"))
      fig.panels.push_back(std::move(p));
  }
  write_plot(fig, a.plot, "compare");
}

void print_frequency_compare(const FrequencyCompareResult& fc, const std::vector<std::string>& inputs,
                             const std::vector<std::string>& outputs) {
  std::cout << "in-band FRF error of the model against the data's H1 (" << fmt(fc.f_lo_hz) << ".." << fmt(fc.f_hi_hz)
            << " Hz, " << fc.bins_in_band << " frequencies, nfft " << fc.data_frf.nfft
            << "; relative, coherence-weighted; 0 = perfect):\n";
  for (const auto& p : fc.pairs)
    std::cout << "  " << outputs[static_cast<std::size_t>(p.output)] << " <- " << inputs[static_cast<std::size_t>(p.input)]
              << ": " << fmt(p.relative_error, 3) << " (noise floor " << fmt(p.noise_floor, 2) << "), worst mismatch at "
              << fmt(p.worst_freq_hz, 5) << " Hz (" << fmt(p.worst_mismatch, 3) << "), mean coherence "
              << fmt(p.mean_coherence, 3) << "\n";
  for (const auto& w : fc.warnings) warn("compare", w);
}

/// --fem: the FE model's response by sparse solves (continuous time) against the
/// log's H1 in the band; channels default to the FE model's force and output names.
void run_fem_compare(const CompareArgs& a) {
  if (a.band.empty()) throw CLI::ValidationError("--band", "--fem compares frequency responses: give --band LO:HI");
  if (a.predict > 0) throw CLI::ValidationError("--predict", "an FE model has no noise model to predict with");
  claim_outputs({a.plot}, {a.fem_path, a.log_path});
  const auto [lo, hi] = parse_range(a.band, "--band");
  if (lo < 0.0) throw CLI::ValidationError("--band", "need LO >= 0, found '" + a.band + "'");
  const fem::SecondOrderModel model = read_fem_model(a.fem_path);
  std::vector<std::string> inputs = split_names(a.log.inputs, "--inputs"), outputs = split_names(a.log.outputs, "--outputs");
  if (inputs.empty())
    for (const auto& in : model.inputs) inputs.push_back(in.name);
  if (outputs.empty())
    for (const auto& out : model.outputs) outputs.push_back(out.name);
  if (inputs.size() != model.inputs.size() || outputs.size() != model.outputs.size())
    throw CLI::ValidationError("--inputs/--outputs", "the FE model " + a.fem_path + " has " +
                                                         std::to_string(model.inputs.size()) + " input(s) and " +
                                                         std::to_string(model.outputs.size()) + " output(s)");
  const LoadedLog log = load_log(a.log_path, make_log_options(a.log, inputs, outputs));
  FrequencyCompareOptions fo;
  fo.frf.welch.nfft = a.nfft;
  fo.f_lo_hz = lo;
  fo.f_hi_hz = hi;
  std::vector<std::string> fe_warnings;
  // Only the band's frequencies are solved; the rest are NaN and skipped.
  const auto response = [&](const Eigen::VectorXd& f) {
    std::vector<Eigen::Index> in_band;
    for (Eigen::Index k = 0; k < f.size(); ++k)
      if (f(k) >= fo.f_lo_hz && f(k) <= fo.f_hi_hz) in_band.push_back(k);  // not lo/hi: clang 14 cannot capture bindings
    Eigen::VectorXd fb(static_cast<Eigen::Index>(in_band.size()));
    for (std::size_t q = 0; q < in_band.size(); ++q) fb(static_cast<Eigen::Index>(q)) = f(in_band[q]);
    const fem::SparseFrfResult r = fem::sparse_frf(model, fb);
    fe_warnings = r.warnings;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    std::vector<Eigen::MatrixXcd> h(static_cast<std::size_t>(f.size()),
                                    Eigen::MatrixXcd::Constant(static_cast<Eigen::Index>(outputs.size()),
                                                               static_cast<Eigen::Index>(inputs.size()), {nan, nan}));
    for (std::size_t q = 0; q < in_band.size(); ++q) h[static_cast<std::size_t>(in_band[q])] = r.H[q];
    return h;
  };
  const FrequencyCompareResult fc = frequency_compare_response(response, log.data, fo);
  std::cout << "FE model " << a.fem_path << " (" << model.dofs() << " DOFs, sparse solves) on " << a.log_path << "\n";
  for (const auto& w : fe_warnings) warn("compare", w);
  print_frequency_compare(fc, inputs, outputs);
  if (!a.plot.empty()) plot_compare(a, log, nullptr, inputs, outputs, &fc, "frequency response");
}

void run_compare(const CompareArgs& a) {
  if (!a.fem_path.empty()) {
    CompareArgs fe = a;
    // One positional given: it is the log (CLI11 fills "model" first).
    if (fe.log_path.empty()) std::swap(fe.model_path, fe.log_path);
    if (!fe.model_path.empty()) throw CLI::ValidationError("--fem", "give either a model file or --fem MODEL.json, not both");
    run_fem_compare(fe);
    return;
  }
  if (a.log_path.empty()) throw CLI::ValidationError("log", "give the model file and the CSV log");
  const std::string verb = "compare";
  claim_outputs({a.plot}, {a.model_path, a.log_path});
  std::optional<std::pair<double, double>> band;
  if (!a.band.empty()) band = parse_range(a.band, "--band");
  if (band && band->first < 0.0) throw CLI::ValidationError("--band", "need LO >= 0, found '" + a.band + "'");
  const ModelFile file = load_model(a.model_path);
  if (a.predict > 0 && file.K.size() == 0)
    throw DataError(a.model_path, 0, 0,
                    "--predict needs the model's Kalman gain K, and this model file has none (identify an innovation "
                    "model, e.g. with sysid n4sid)");
  const auto [inputs, outputs] = model_channels(a.log, file, true);
  const LoadedLog log = load_log(a.log_path, make_log_options(a.log, inputs, outputs));
  const StateSpace model = model_for_sample_time(file, log.data.Ts, a.model_path, verb);

  CompareOptions o = compare_options_for(file, a.x0, a.model_path);
  o.predict_steps = a.predict;
  const CompareResult r = compare(model, file.K, log.data.experiments.front(), o);

  const std::string how = a.predict == 0 ? std::string("simulation") : std::to_string(a.predict) + "-step-ahead prediction";
  std::cout << "fit [%] of " << a.model_path << " on " << a.log_path << " (" << how << ", x0 "
            << (a.x0 == "estimate" ? "estimated" : a.x0 == "model" ? "from the model file" : "zero") << ", "
            << log.data.total_samples() << " samples):\n"
            << format_fit_lines(r.fit_percent, outputs);

  std::optional<FrequencyCompareResult> fc;
  if (band) {
    FrequencyCompareOptions fo;
    fo.frf.welch.nfft = a.nfft;
    fo.f_lo_hz = band->first;
    fo.f_hi_hz = band->second;
    fc = frequency_compare(model, log.data, fo);
    print_frequency_compare(*fc, inputs, outputs);
  }
  if (!a.plot.empty()) plot_compare(a, log, &r, inputs, outputs, fc ? &*fc : nullptr, how);
}

}  // namespace

Verb register_compare(CLI::App& app) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand("compare", "Fit % of a model on a log (simulation, or k-step-ahead prediction)");
  cmd->add_option("model", args->model_path, "model file (JSON); with --fem omit it")->required();
  cmd->add_option("log", args->log_path, "CSV log with the input and output columns");
  LogOptionSpec spec;
  spec.inputs_required = false;
  spec.outputs_required = false;
  spec.inputs_help = "input columns of the log, in the model's input order (default: the model's input names)";
  spec.outputs_help = "output columns of the log, in the model's output order (default: the model's output names)";
  add_log_options(*cmd, args->log, spec);
  cmd->add_option("--predict", args->predict,
                  "K >= 1: fit of the K-step-ahead Kalman predictor (needs the model's K) instead of simulation")
      ->check(CLI::Range(1, 1000000000));
  cmd->add_option("--x0", args->x0, "initial state: estimate (least squares on this log), zero, model (stored x0)")
      ->capture_default_str()
      ->check(CLI::IsMember({"estimate", "zero", "model"}));
  cmd->add_option("--band", args->band,
                  "LO:HI in Hz: also compare the model's frequency response with the data's H1 estimate in this band")
      ->check(range_validator());
  cmd->add_option("--nfft", args->nfft, "segment length of the H1 estimate for --band")
      ->capture_default_str()
      ->check(CLI::Range(Eigen::Index{8}, Eigen::Index{1} << 26));
  cmd->add_option("--plot", args->plot,
                  "measured vs model output over time; with --band also the Bode overlay (.svg or .png; needs gnuplot)")
      ->check(plot_path_validator());
  cmd->add_option("--fem", args->fem_path,
                  "finite-element model (JSON naming Matrix Market M, K, C and the force/output DOFs) compared with the "
                  "log's H1 over --band by sparse solves");
  cmd->footer(
      "Fit % = 100 (1 - |y - y_hat| / |y - mean(y)|) per output; 100 is perfect, 0 is as good as the mean.\n"
      "--band: per output-input pair, sqrt(sum g |G - H|^2 / sum g |H|^2) over the band's frequencies,\n"
      "with G the model's response, H the data's H1 and g its coherence, and the frequency where\n"
      "g |G - H| / |H| is largest. The noise floor is the value a perfect model would get.\n"
      "Example:\n"
      "  sysid compare model.json fresh.csv --inputs u --outputs y\n"
      "  sysid compare model.json fresh.csv --predict 10\n"
      "  sysid compare model.json fresh.csv --band 0:100 --nfft 4096 --plot compare.svg\n"
      "  sysid compare --fem beam.json measured.csv --band 5:400 --nfft 4096");
  add_hold_option(*cmd);
  return {cmd, [args] { run_compare(*args); }};
}

}  // namespace sysid::cli
