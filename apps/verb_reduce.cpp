// sysid hsv | reduce: Hankel singular values of a model, and its reduction by
// balanced truncation, singular perturbation or modal truncation
// (reduce/balanced_truncation.hpp, reduce/modal_truncation.hpp).
#include <sysid/config.hpp>
#include <sysid/fem/modal_model.hpp>
#include <sysid/io/atomic_file.hpp>
#include <sysid/io/fem_modal_model_file.hpp>
#include <sysid/io/fem_model_file.hpp>
#include <sysid/io/model_json.hpp>
#include <sysid/io/reduced_model_file.hpp>
#include <sysid/reduce/balanced_truncation.hpp>
#include <sysid/reduce/hankel_singular_values.hpp>
#include <sysid/reduce/modal_truncation.hpp>

#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "cli_common.hpp"
#include "plot.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

struct HsvArgs {
  std::string model_path, plot;
};

/// Two panels over the cut r: the Hankel singular values relative to the first,
/// and the reduction-error figures of cutting there (the isolator paper's ratio and
/// the H-inf bound relative to the largest HSV), with the paper's 0.4 % and 2 %
/// marked.
PlotFigure hsv_figure(const Eigen::VectorXd& values, const std::string& model_path) {
  const Eigen::Index n = values.size();
  const double total = values.sum();
  Eigen::VectorXd r = Eigen::VectorXd::LinSpaced(n, 1.0, static_cast<double>(n)), ratio(n), bound(n);
  double kept = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    kept += values(k);
    ratio(k) = std::max(0.0, total - kept) / total;
    bound(k) = 2.0 * std::max(0.0, total - kept) / values(0);
  }
  PlotPanel sv;
  sv.title = "Hankel singular values";
  sv.xlabel = "state";
  sv.ylabel = "hsv / hsv_1";
  sv.logy = true;
  auto curve = [](std::string title, Eigen::VectorXd x, Eigen::VectorXd y, std::string style) {
    PlotCurve c;
    c.title = std::move(title);
    c.x = std::move(x);
    c.y = std::move(y);
    c.style = std::move(style);
    return c;
  };
  sv.curves.push_back(curve("hsv / hsv_1", r, values / values(0), "linespoints"));
  // A cut at r = n discards nothing (zero error, off a log axis): plot r < n.
  PlotPanel cut;
  cut.title = "error of the reduced model of order r";
  cut.xlabel = "kept order r";
  cut.ylabel = "relative error";
  cut.logy = true;
  const Eigen::Index m = std::max<Eigen::Index>(n - 1, 1);
  cut.curves.push_back(curve("ratio (sum all - sum kept) / sum all", r.head(m), ratio.head(m), "linespoints"));
  cut.curves.push_back(curve("H-inf bound 2 sum discarded / hsv_1", r.head(m), bound.head(m), "lines"));
  for (double level : {0.004, 0.02}) {
    PlotCurve line = curve(fmt(100.0 * level, 2) + " %", Eigen::Vector2d(1.0, static_cast<double>(n)),
                           Eigen::Vector2d(level, level), "lines");
    line.dashed = true;
    line.color = 7;
    cut.curves.push_back(std::move(line));
  }
  PlotFigure fig;
  fig.title = "Hankel singular values of " + model_path;
  fig.panels = {std::move(sv), std::move(cut)};
  return fig;
}

void run_hsv(const HsvArgs& a) {
  claim_outputs({a.plot}, {a.model_path});
  const ModelFile file = load_model(a.model_path);
  const HankelSingularValuesResult r = hankel_singular_values(named_model(file));
  const double total = r.values.sum();
  std::ostringstream s;
  s << "Hankel singular values of " << a.model_path << " (order " << file.model.order() << ", stable part "
    << r.values.size() << " states" << (r.unstable_states > 0 ? ", " + std::to_string(r.unstable_states) + " unstable states kept whole by reduce" : "")
    << "):\n";
  s << "   r  " << std::setw(14) << "hsv" << std::setw(12) << "hsv/hsv1" << std::setw(16) << "ratio if cut" << std::setw(16)
    << "H-inf bound\n";
  double kept = 0;
  for (Eigen::Index k = 0; k < r.values.size(); ++k) {
    kept += r.values(k);
    const double discarded = total - kept;
    s << std::setw(4) << k + 1 << "  " << std::setw(14) << std::setprecision(6) << r.values(k) << std::setw(12)
      << std::setprecision(4) << r.values(k) / r.values(0) << std::setw(16) << std::setprecision(4)
      << (total > 0 ? std::max(0.0, discarded) / total : 0.0) << std::setw(16) << std::setprecision(4) << 2.0 * std::max(0.0, discarded)
      << "\n";
  }
  s << "(ratio if cut: (sum of all HSV - sum of the first r) / sum of all, the isolator paper's figure; "
       "H-inf bound: 2 x sum of the discarded HSV)\n";
  std::cout << s.str();
  for (const auto& w : r.warnings) warn("hsv", w);
  if (!a.plot.empty()) {
    if (r.values.size() == 0 || !(r.values(0) > 0.0))
      warn("hsv", "no plot: the model has no stable part with a nonzero Hankel singular value");
    else
      write_plot(hsv_figure(r.values, a.model_path), a.plot, "hsv");
  }
}

struct ReduceArgs {
  std::string model_path;
  Eigen::Index order = -1;
  std::string max_error;
  std::string band;
  std::string method = "balanced";
  bool keep_dc = false;
  std::string out;
  // --fem: modal reduction of a finite-element model.
  std::string fem_path;
  int modes = 0;
  double ts = 0.0;
  bool static_correction = false;
};

/// The lowest --modes modes of an FE model as a state-space model
/// (fem/modal_model.hpp), continuous or sampled at --ts.
void run_fem_reduce(const ReduceArgs& a) {
  const std::string verb = "reduce";
  if (!a.model_path.empty()) throw std::invalid_argument("reduce: give either a model file or --fem MODEL.json, not both");
  if (a.modes < 1) throw std::invalid_argument("reduce: --fem needs --modes N (the number of lowest modes to keep)");
  if (a.order >= 0 || !a.max_error.empty() || !a.band.empty())
    throw std::invalid_argument("reduce: --order, --max-error and --band apply to state-space models; with --fem use --modes");
  const Hold hold = selected_hold();
  if (hold != Hold::zoh && !(a.ts > 0.0)) throw CLI::ValidationError("--hold", "applies to a sampled model: give --ts too");
  claim_outputs({a.out}, {a.fem_path});
  const fem::SecondOrderModel model = read_fem_model(a.fem_path);
  fem::ModalAnalysisOptions analysis;
  analysis.modes = a.modes;
  fem::ModalModelOptions options;
  options.Ts = a.ts;
  options.hold = hold;
  options.static_correction = a.static_correction;
  const fem::ModalModelResult r = fem::modal_model(model, analysis, options);
  const fem::ModalAnalysisResult& m = r.modes;
  std::cout << "modal reduction of " << a.fem_path << ": " << model.dofs() << " DOFs -> " << a.modes << " modes, order "
            << r.model.order() << (a.ts > 0.0 ? ", sampled at Ts = " + fmt(a.ts) + " s (" + (hold == Hold::foh ? "FOH" : "ZOH") + ")" : ", continuous")
            << (a.static_correction ? ", static correction" : "") << "\n"
            << "Lanczos (shift-invert, CHOLMOD): " << m.operator_applications << " solves, " << m.restarts
            << " restarts, largest eigen backward error " << fmt(m.max_relative_residual, 2) << "\n"
            << "  mode   f [Hz]          zeta\n";
  for (Eigen::Index i = 0; i < m.natural_frequencies_hz.size(); ++i)
    std::cout << "  " << std::setw(4) << i + 1 << "   " << std::setw(14) << std::left << fmt(m.natural_frequencies_hz(i))
              << std::right << "  " << (std::isnan(m.damping_ratios(i)) ? std::string("rigid body") : fmt(m.damping_ratios(i), 4))
              << "\n";
  for (const auto& w : r.warnings) warn(verb, w);
  ModelFile out = fem_modal_model_file(model, r, options);
  out.provenance["source"] = a.fem_path;
  write_model_json(a.out, out);
  note(verb, "wrote " + a.out);
}

/// "2%" -> 0.02, "0.02" -> 0.02.
double parse_ratio(const std::string& text) {
  std::string t = text;
  double scale = 1.0;
  if (!t.empty() && t.back() == '%') {
    t.pop_back();
    scale = 0.01;
  }
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(t, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != t.size() || t.empty() || !(v > 0) || v * scale >= 1.0)
    throw std::invalid_argument("--max-error: expected a ratio in (0, 1) such as 0.02 or 2%, found '" + text + "'");
  return v * scale;
}

void run_reduce(const ReduceArgs& a) {
  if (!a.fem_path.empty()) {
    run_fem_reduce(a);
    return;
  }
  if (a.model_path.empty()) throw std::invalid_argument("reduce: give the model file (or --fem MODEL.json --modes N)");
  if (selected_hold() != Hold::zoh) throw CLI::ValidationError("--hold", "samples a finite-element model: it needs --fem and --ts");
  if (a.modes > 0 || a.ts > 0.0 || a.static_correction)
    throw std::invalid_argument("reduce: --modes, --ts and --static-correction need --fem");
  claim_outputs({a.out}, {a.model_path});
  ReduceRequest request;
  request.method = !a.band.empty() ? "modal" : a.method;
  request.order = a.order;
  if (!a.max_error.empty()) request.max_error_ratio = parse_ratio(a.max_error);
  if (!a.band.empty()) request.band_hz = parse_range(a.band, "--band");
  request.keep_dc_gain = a.keep_dc;
  request.source = a.model_path;
  const ReducedModelFile reduced = reduce_model_file(load_model(a.model_path), request);
  const ReductionResult& r = reduced.reduction;
  if (reduced.time_series) std::cout << "time-series model: reducing its innovation form (input = the innovation e)\n";
  std::cout << r.brief_report();
  if (!r.kept_modes.empty()) std::cout << "kept modes:\n" << format_modal_table(r.kept_modes);
  for (const auto& w : reduced.warnings) warn("reduce", w);
  const ModelFile& out = reduced.file;
  write_model_json(a.out, out);
  note("reduce", "wrote " + a.out);
}

}  // namespace

Verb register_hsv(CLI::App& app) {
  auto args = std::make_shared<HsvArgs>();
  CLI::App* cmd = app.add_subcommand("hsv", "Hankel singular values of a model, with the reduction error of every cut");
  cmd->add_option("model", args->model_path, "model file (JSON)")->required();
  cmd->add_option("--plot", args->plot,
                  "plot of the HSV and of the error figures of every cut, with 0.4 % and 2 % marked (.svg or .png; "
                  "needs gnuplot)")
      ->check(plot_path_validator());
  cmd->footer("Example:\n  sysid hsv avi112.json --plot hsv.svg");
  return {cmd, [args] { run_hsv(*args); }};
}

Verb register_reduce(CLI::App& app) {
  auto args = std::make_shared<ReduceArgs>();
  CLI::App* cmd = app.add_subcommand("reduce", "reduce a model: balanced truncation, singular perturbation or modal truncation");
  cmd->add_option("model", args->model_path, "model file (JSON; not with --fem)");
  cmd->add_option("--order", args->order, "order of the reduced model (unstable states included)")->check(CLI::Range(0, 100000));
  cmd->add_option("--max-error", args->max_error,
                  "smallest order whose discarded-HSV ratio (sum discarded / sum all) is at most this, e.g. 2% or 0.02");
  cmd->add_option("--band", args->band, "modal truncation: keep the modes with natural frequency in lo:hi Hz")->check(range_validator());
  cmd->add_option("--method", args->method, "balanced (square-root balanced truncation), spa (singular perturbation: keeps the DC gain) or modal")
      ->capture_default_str()
      ->check(CLI::IsMember({"balanced", "spa", "modal"}));
  cmd->add_flag("--keep-dc", args->keep_dc, "modal truncation: add the removed modes' static gain to D");
  cmd->add_option("--out", args->out, "reduced model file to write (JSON)")->required();
  cmd->add_option("--fem", args->fem_path,
                  "finite-element model (JSON naming Matrix Market M, K, C and the force/output DOFs): keep its lowest "
                  "--modes modes (shift-invert Lanczos)");
  cmd->add_option("--modes", args->modes, "with --fem: number of lowest modes to keep")->check(CLI::Range(1, 100000));
  cmd->add_option("--ts", args->ts, "with --fem: sample the reduced model at Ts seconds (with --hold); default continuous")
      ->check(CLI::PositiveNumber);
  add_hold_option(*cmd);
  cmd->add_flag("--static-correction", args->static_correction,
                "with --fem: add the truncated modes' static contribution to displacement outputs");
  cmd->footer(
      "Prints the order, the discarded-HSV ratio, the H-inf bound 2 x sum(discarded HSV) and the H-inf error measured on a dense grid.\n"
      "Examples:\n  sysid reduce avi112.json --max-error 2% --out avi_r.json\n"
      "  sysid reduce ar16.json --band 20:40 --method modal --keep-dc --out ar4.json\n"
      "  sysid reduce --fem beam.json --modes 12 --ts 5e-4 --out beam12.json\n"
      "  sysid reduce --fem beam.json --modes 8 --ts 5e-4 --hold foh --out beam8.json   (smoothly sampled logs)");
  return {cmd, [args] { run_reduce(*args); }};
}

}  // namespace sysid::cli
