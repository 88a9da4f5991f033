// sysid n4sid: subspace identification (N4SID / MOESP / CVA) of a state-space
// model from a CSV log, with validation on held-out data and an order sweep.
#include <sysid/config.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/core/modal_table.hpp>
#include <sysid/io/atomic_file.hpp>
#include <sysid/io/model_json.hpp>
#include <sysid/io/n4sid_model_file.hpp>
#include <sysid/subspace/n4sid.hpp>
#include <sysid/subspace/order_sweep.hpp>
#include <sysid/validate/compare.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "plot.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

struct N4sidArgs {
  std::string log_path;
  LogArgs log;
  std::string method = "n4sid";
  std::string order = "auto";
  // Defaults of --max-order and --order-rule are the library's (N4sidOptions{}).
  int max_order = N4sidOptions{}.max_order;
  std::string order_rule = to_string(N4sidOptions{}.order_rule);
  int horizon = 0;
  bool enforce_stability = false;
  bool allow_unstable = false;
  std::string refine = "auto";
  std::string hankel = "auto";
  std::string validate;
  std::optional<double> split;
  std::optional<double> band_limit_hz;
  int band_limit_order = N4sidOptions{}.band_limit_order;
  std::string decimation = "auto";
  std::string out;
  std::string plot;
  std::string stabilization;
  double noise_shape_level = StabilizationOptions{}.random_shape_level;
  double min_level_ratio = StabilizationOptions{}.min_level_ratio;
};

/// The singular values (and, when present, the canonical correlations of the SVC
/// rule) that chose the order, with the chosen order marked.
void plot_order_choice(const N4sidArgs& a, const N4sidResult& res) {
  auto panel = [&](const Eigen::VectorXd& v, const std::string& title, const std::string& ylabel, bool logy) {
    PlotPanel p;
    p.title = title;
    p.xlabel = "index";
    p.ylabel = ylabel;
    p.logy = logy;
    PlotCurve c, mark;
    c.title = ylabel;
    c.style = "linespoints";
    c.x = Eigen::VectorXd::LinSpaced(v.size(), 1.0, static_cast<double>(v.size()));
    c.y = v;
    if (logy)
      for (Eigen::Index k = 0; k < v.size(); ++k)
        if (!(v(k) > 0.0)) c.y(k) = NAN;  // a log axis has no zero
    p.curves.push_back(std::move(c));
    if (res.order >= 1 && res.order <= v.size()) {
      mark.title = "chosen order " + std::to_string(res.order);
      mark.style = "impulses";
      mark.color = 1;
      mark.x = Eigen::VectorXd::Constant(1, static_cast<double>(res.order));
      mark.y = Eigen::VectorXd::Constant(1, v(res.order - 1));
      if (logy) {  // impulses on a log axis start at the bottom: draw a point instead
        mark.style = "points";
        mark.point_type = 6;
        mark.point_size = 2.5;
      }
      p.curves.push_back(std::move(mark));
    }
    return p;
  };
  PlotFigure fig;
  fig.title = "order choice for " + a.log_path + ": " + res.order_rule;
  fig.panels.push_back(panel(res.singular_values, "singular values of the weighted projection", "singular value", true));
  if (res.canonical_correlations.size() > 0)
    fig.panels.push_back(panel(res.canonical_correlations, "canonical correlations (SVC rule)", "canonical correlation", false));
  fig.height_per_row = 320;
  write_plot(fig, a.plot, "n4sid");
}

/// The stabilisation diagram as a CSV table (.csv: one row per pole, with its level) or a picture
/// (.svg/.png: order over frequency, one symbol per stability class, the physical
/// modes as dashed lines).
void write_stabilization(const std::string& path, const StabilizationDiagram& d, const std::string& log_path) {
  if (path.size() > 4 && path.compare(path.size() - 4, 4, ".csv") == 0) {
    Eigen::MatrixXd table(static_cast<Eigen::Index>(d.poles.size()), 8);
    for (std::size_t k = 0; k < d.poles.size(); ++k) {
      const StabilizationPole& p = d.poles[k];
      table.row(static_cast<Eigen::Index>(k)) << p.order, p.freq_hz, p.damping, p.stable_frequency ? 1.0 : 0.0,
          p.stable_damping ? 1.0 : 0.0, p.stable_shape ? 1.0 : 0.0, static_cast<double>(p.mode + 1), p.level;
    }
    write_csv(path, {"order", "freq_hz", "damping", "stable_frequency", "stable_damping", "stable_shape", "mode", "level"},
              table);
    return;
  }
  PlotPanel panel;
  panel.title = d.criteria();
  panel.xlabel = "frequency [Hz]";
  panel.ylabel = "model order";
  panel.yrange = std::pair<double, double>(d.order_lo - 0.5, d.order_hi + 0.5);
  const std::vector<std::pair<char, std::string>> classes = {
      {'o', "new"}, {'f', "stable frequency"}, {'d', "stable frequency and damping"}, {'v', "stable frequency and shape"},
      {'s', d.with_shapes ? "stable in all" : "stable frequency and damping"}};
  const int point_types[] = {1, 2, 6, 4, 7};
  for (std::size_t c = 0; c < classes.size(); ++c) {
    if (!d.with_shapes && classes[c].first == 'd') continue;  // one output: 'd' is 's'
    std::vector<double> x, y;
    for (const auto& p : d.poles)
      if (p.mark(d.with_shapes) == classes[c].first) {
        x.push_back(p.freq_hz);
        y.push_back(p.order);
      }
    if (x.empty()) continue;
    PlotCurve curve;
    curve.title = classes[c].second;
    curve.style = "points";
    curve.point_type = point_types[c];
    curve.point_size = classes[c].first == 's' ? 0.8 : 0.6;
    curve.color = static_cast<int>(c);
    curve.x = Eigen::Map<const Eigen::VectorXd>(x.data(), static_cast<Eigen::Index>(x.size()));
    curve.y = Eigen::Map<const Eigen::VectorXd>(y.data(), static_cast<Eigen::Index>(y.size()));
    panel.curves.push_back(std::move(curve));
  }
  const auto add_lines = [&](const std::vector<PhysicalMode>& columns, const std::string& title, int color) {
    for (std::size_t k = 0; k < columns.size(); ++k) {
      PlotCurve line;
      line.title = k == 0 ? title : "";
      line.dashed = true;
      line.color = color;
      line.x = Eigen::VectorXd::Constant(2, columns[k].freq_hz);
      line.y = (Eigen::VectorXd(2) << d.order_lo, d.order_hi).finished();
      panel.curves.push_back(std::move(line));
    }
  };
  add_lines(d.modes, "physical modes", 6);
  add_lines(d.noise_columns, "noise columns (not modes)", 7);
  PlotFigure fig;
  fig.title = "stabilization diagram of " + log_path + ": " + std::to_string(d.modes.size()) + " physical modes" +
              (d.chosen_order > 0 ? ", all present from order " + std::to_string(d.chosen_order) : std::string());
  fig.panels.push_back(std::move(panel));
  fig.height_per_row = 600;
  write_plot(fig, path, "n4sid");
}

/// --order: N, auto, or A:B.
struct OrderSpec {
  int fixed = 0;  ///< 0 = auto
  bool sweep = false;
  int lo = 0, hi = 0;
};

/// Parses --order; returns an error text (empty when valid) so it doubles as a CLI11 validator.
std::string parse_order(const std::string& text, OrderSpec& spec) {
  auto parse_int = [](const std::string& s, int& v) {
    if (s.empty() || s.size() > 6 || s.find_first_not_of("0123456789") != std::string::npos) return false;
    v = std::stoi(s);
    return v >= 1;
  };
  spec = {};
  if (text == "auto") return {};
  const auto colon = text.find(':');
  if (colon == std::string::npos) {
    if (!parse_int(text, spec.fixed)) return "expected N >= 1, auto, or A:B, found '" + text + "'";
    return {};
  }
  spec.sweep = true;
  if (!parse_int(text.substr(0, colon), spec.lo) || !parse_int(text.substr(colon + 1), spec.hi) || spec.lo > spec.hi)
    return "expected A:B with 1 <= A <= B, found '" + text + "'";
  return {};
}

/// Channel names for the report: the log's column names.
std::vector<std::string> output_names(const IoData& d) {
  std::vector<std::string> names;
  for (Eigen::Index i = 0; i < d.outputs(); ++i) names.push_back(d.output_name(i));
  return names;
}

std::string format_sweep_table(const std::vector<OrderSweepEntry>& table, const std::vector<std::string>& names) {
  std::ostringstream s;
  char buf[128];
  std::snprintf(buf, sizeof buf, "%6s", "order");
  s << buf;
  for (const auto& n : names) {
    std::snprintf(buf, sizeof buf, "  %14s", ("est " + n).c_str());
    s << buf;
  }
  for (const auto& n : names) {
    std::snprintf(buf, sizeof buf, "  %14s", ("val " + n).c_str());
    s << buf;
  }
  if (names.size() > 1) {
    std::snprintf(buf, sizeof buf, "  %10s", "val mean");
    s << buf;
  }
  s << "\n";
  auto cell = [&](double v, int width) {
    if (std::isnan(v))
      std::snprintf(buf, sizeof buf, "  %*s", width, "failed");
    else
      std::snprintf(buf, sizeof buf, "  %*.2f", width, v);
    s << buf;
  };
  for (const auto& e : table) {
    std::snprintf(buf, sizeof buf, "%6d", e.order);
    s << buf;
    for (Eigen::Index i = 0; i < e.estimation_fit.size(); ++i) cell(e.estimation_fit(i), 14);
    for (Eigen::Index i = 0; i < e.validation_fit.size(); ++i) cell(e.validation_fit(i), 14);
    if (names.size() > 1) cell(e.mean_validation_fit(), 10);
    if (e.ok && e.spectral_radius >= 1.0) s << "  unstable (largest |pole| " << fmt(e.spectral_radius, 4) << ")";
    s << "\n";
  }
  return s.str();
}

/// What identify_n4sid found: the model file (without the data's name), the result
/// the plots need, and the report, notes and warnings to print.
struct N4sidOutcome {
  Identified identified;
  N4sidResult res;
};

/// Loads the log, identifies, builds the report and the model file; prints and
/// writes nothing (run_n4sid does, and `sysid family` calls this per member).
/// keep_estimation: keep a copy of the estimation data in the outcome.
N4sidOutcome identify_n4sid(const N4sidArgs& a, bool keep_estimation) {
  OrderSpec order;
  if (const std::string err = parse_order(a.order, order); !err.empty()) throw CLI::ValidationError("--order", err);
  const bool diagram = !a.stabilization.empty();
  if (diagram && !order.sweep)
    throw CLI::ValidationError("--stabilization", "needs --order LO:HI, the orders the diagram shows (e.g. --order 2:60)");

  N4sidOutcome outcome;
  Identified& identified = outcome.identified;
  const LogOptions log_options =
      make_log_options(a.log, split_names(a.log.inputs, "--inputs"), split_names(a.log.outputs, "--outputs"));
  identified.log_options = log_options;
  // Estimation and validation data.
  std::optional<double> split_fraction = a.split;
  if (order.sweep && !diagram && !split_fraction && a.validate.empty()) {
    split_fraction = 0.7;
    identified.notes.push_back("--order A:B compares orders on validation data; none given, so using --split 0.7");
  }
  EstimationData loaded = load_estimation_data(a.log_path, a.validate, split_fraction, log_options);
  IoData& estimation = loaded.estimation;
  if (keep_estimation) identified.estimation = estimation;
  std::optional<IoData>& validation = loaded.validation;
  const std::string& validation_label = loaded.validation_label;
  // Kept apart from the samples, which are moved into n4sid (peak memory: one copy of the log).
  const std::vector<std::string> names = output_names(estimation), all_input_names = estimation.input_names,
                                 all_output_names = estimation.output_names;

  N4sidOptions options;
  options.weighting = subspace_weighting_from_name(a.method);
  options.order = order.fixed;
  options.max_order = a.max_order;
  options.order_rule = order_rule_from_name(a.order_rule);
  options.horizon = a.horizon;
  options.route = hankel_route_from_name(a.hankel);
  options.enforce_stability = a.enforce_stability;
  options.allow_unstable = a.allow_unstable;
  options.refine_poles = pole_refinement_mode_from_name(a.refine);
  // --band-limit: the Par2 remedy for gain the data do not determine above the
  // excited band (the model comes back in series with the low-pass at its inputs).
  if (a.band_limit_hz) options.band_limit_hz = *a.band_limit_hz;
  options.band_limit_order = a.band_limit_order;
  options.decimation = a.decimation == "auto" ? 0 : std::stoi(a.decimation);

  std::ostringstream report;
  N4sidResult& res = outcome.res;
  Eigen::VectorXd validation_fit;
  nlohmann::json sweep_json = nlohmann::json::array();
  if (diagram) {
    // Every order's poles from one compression; the diagram's rule chooses the model's order.
    options.order = 0;
    options.order_rule = OrderRule::stabilization;
    options.stabilization_order_lo = order.lo;
    options.stabilization.random_shape_level = a.noise_shape_level;
    options.stabilization.min_level_ratio = a.min_level_ratio;
    options.stabilization_order_hi = order.hi;
    res = n4sid(std::move(estimation), options);
    const StabilizationDiagram& d = res.stabilization;
    report << "stabilization diagram, orders " << d.order_lo << ".." << d.order_hi << " (horizon " << res.horizon << "; "
           << d.criteria() << "):\n";
    if (d.modes.empty())
      report << "no physical mode: no column of stable poles\n";
    else
      report << "physical modes (columns of stable poles):\n" << d.modes_table();
    if (!d.noise_columns.empty())
      report << "not modes: columns of noise that the high orders fit (level: the poles' singular-value weight over "
                "the wandering poles' at the same orders, --min-level-ratio 0 does not test it; MPC: shape collinearity, "
                "--noise-shape-level 0 does not test it):\n"
             << d.noise_columns_table();
    report << "\n";
    if (validation) {
      CompareOptions co;
      co.input_offset = res.input_offset;
      co.output_offset = res.output_offset;
      validation_fit = compare_fit(res.model, res.K, *validation, co);
    }
  } else if (order.sweep) {
    const std::vector<OrderSweepEntry> table = n4sid_order_sweep(estimation, *validation, options, order.lo, order.hi);
    const OrderSweepEntry* best = nullptr;
    for (const auto& e : table) {
      nlohmann::json row = {{"order", e.order},
                            {"estimation_fit_percent", json_list_or_null(e.estimation_fit)},
                            {"validation_fit_percent", json_list_or_null(e.validation_fit)}};
      sweep_json.push_back(row);
      if (!e.ok) {
        identified.warnings.insert(identified.warnings.end(), e.warnings.begin(), e.warnings.end());
        continue;
      }
      // Strictly better only: among equal fits the lowest order wins.
      if (best == nullptr || e.mean_validation_fit() > best->mean_validation_fit()) best = &e;
    }
    if (best == nullptr) throw NumericalError("n4sid: identification failed at every order " + a.order);
    report << "order sweep " << order.lo << ".." << order.hi << " (horizon " << best->result.horizon
           << " for all orders, simulation fit [%], validation on " << validation_label << "):\n"
           << format_sweep_table(table, names);
    report << "best mean validation fit: order " << best->order << " (" << fmt(best->mean_validation_fit(), 4)
           << " %); writing that model\n";
    // Extra states that fit only noise add spurious modes: point at the smallest
    // order that is practically as good (within 0.1 fit points), without overriding.
    for (const auto& e : table)
      if (e.ok && e.order < best->order && e.mean_validation_fit() >= best->mean_validation_fit() - 0.1) {
        report << "note: order " << e.order << " is within 0.1 points of it (" << fmt(e.mean_validation_fit(), 4)
               << " %); consider --order " << e.order << " for a model without noise modes\n";
        break;
      }
    report << "\n";
    res = best->result;
    res.order_rule = "best mean validation fit over orders " + std::to_string(order.lo) + ".." + std::to_string(order.hi);
    validation_fit = best->validation_fit;
  } else {
    res = n4sid(std::move(estimation), options);
    if (validation) {
      CompareOptions co;
      co.input_offset = res.input_offset;
      co.output_offset = res.output_offset;
      validation_fit = compare_fit(res.model, res.K, *validation, co);
    }
  }

  // Report.
  report << res.brief_report() << "\n";
  report << "order: " << res.order << " (" << res.order_rule << ")\n";
  if (!res.refinement.empty()) report << "refinement: " << res.refinement << "\n";
  if (res.band_limited)
    report << "band limit: " << fmt(a.band_limit_hz.value_or(0.0), 4) << " Hz Butterworth low-pass in series at the inputs ("
           << res.model.order() << " states in total)\n";
  {
    const Eigen::Index shown = std::min<Eigen::Index>(res.singular_values.size(), 2 * res.order + 2);
    report << "leading singular values (" << shown << " of " << res.singular_values.size() << "):";
    for (Eigen::Index k = 0; k < shown; ++k) report << " " << fmt(res.singular_values(k), 4);
    report << "\n";
  }
  report << "fit on estimation data [%] (simulation, x0 estimated"
         << (split_fraction ? ", first " + fmt(100.0 * *split_fraction, 3) + "% of samples" : std::string()) << "):\n"
         << format_fit_lines(res.fit_percent, names);
  if (validation)
    report << "fit on validation data [%] (simulation, x0 estimated, " << validation_label << "):\n"
           << format_fit_lines(validation_fit, names);
  report << "excited band: " << fmt(res.excited_band_low_hz, 4) << " .. " << fmt(res.excited_band_high_hz, 4) << " Hz";
  if (res.decimation > 1) report << " (subspace step on a grid decimated by " << res.decimation << ")";
  report << "\n";
  report << "conditioning: cond(Gamma_i) " << fmt(res.observability_condition, 3) << ", smallest sin(angle) past/future inputs "
         << fmt(res.past_future_min_sine, 3);
  if (res.oblique_dropped_directions > 0)
    report << " (" << res.oblique_dropped_directions << " past directions below " << fmt(options.oblique_min_sine, 3)
           << " left out of the oblique projection)";
  report << "\n";
  report << "modes:\n" << format_modal_table(modal_table(res.model));
  identified.report = report.str();
  identified.warnings.insert(identified.warnings.end(), res.warnings.begin(), res.warnings.end());

  identified.file = n4sid_model_file(res, options, all_input_names, all_output_names);
  nlohmann::json& p = identified.file.provenance;
  p["data"] = a.log_path;
  if (validation) {
    p["validation_fit_percent"] = json_list_or_null(validation_fit);
    p["validation"] = validation_label;
  }
  if (order.sweep && !diagram) p["order_sweep"] = sweep_json;
  return outcome;
}

void run_n4sid(const N4sidArgs& a) {
  const std::string verb = "n4sid";
  std::vector<std::string> inputs_files{a.log_path};
  if (!a.validate.empty()) inputs_files.push_back(a.validate);
  claim_outputs({a.out, a.plot, a.stabilization}, inputs_files);
  const N4sidOutcome outcome = identify_n4sid(a, false);
  for (const auto& n : outcome.identified.notes) note(verb, n);
  std::cout << outcome.identified.report << std::flush;
  for (const auto& w : outcome.identified.warnings) warn(verb, w);
  if (!a.stabilization.empty()) {
    write_stabilization(a.stabilization, outcome.res.stabilization, a.log_path);
    note(verb, "wrote " + a.stabilization);
  }
  if (!a.out.empty()) {
    write_model_json(a.out, outcome.identified.file);
    note(verb, "wrote " + a.out);
  }
  if (!a.plot.empty()) plot_order_choice(a, outcome.res);
}

}  // namespace

Verb register_n4sid(CLI::App& app) {
  auto args = std::make_shared<N4sidArgs>();
  CLI::App* cmd = app.add_subcommand("n4sid", "Identify a state-space model from a CSV log (N4SID / MOESP / CVA subspace method)");
  cmd->add_option("log", args->log_path, "CSV log with the input and output columns")->required();
  add_log_options(*cmd, args->log, LogOptionSpec{});
  cmd->add_option("--method", args->method, "subspace weighting: n4sid, moesp or cva")
      ->capture_default_str()
      ->check(CLI::IsMember({"n4sid", "moesp", "cva"}));
  cmd->add_option("--order", args->order,
                  "model order: N; auto (from the singular values, see --order-rule); or A:B (identify every order A..B and "
                  "keep the one with the best validation fit)")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& s) {
            OrderSpec spec;
            return parse_order(s, spec);
          },
          "N|auto|A:B"));
  cmd->add_option("--max-order", args->max_order,
                  "largest order the automatic choice considers (0: every order the horizon allows)")
      ->capture_default_str()
      ->check(CLI::Range(0, 10000));
  cmd->add_option("--order-rule", args->order_rule,
                  "automatic order rule: auto (svc, or test where SVC's penalty swamps the modes, as with many outputs), "
                  "svc (Bauer's singular-value criterion), test (canonical correlations above the noise level) or gap "
                  "(largest singular-value gap)")
      ->capture_default_str()
      ->check(CLI::IsMember([] {
        std::vector<std::string> names;
        for (const OrderRule r : kOrderRules) names.emplace_back(to_string(r));
        return names;
      }()));
  cmd->add_option("--horizon", args->horizon, "block rows i of the past/future Hankel matrix (default: automatic)")
      ->check(CLI::Range(2, 100000));
  cmd->add_flag("--enforce-stability", args->enforce_stability, "estimate A so that the model is always stable");
  cmd->add_flag("--allow-unstable", args->allow_unstable,
                "keep an unstable estimate of A (a plant that is itself unstable); by default its unstable poles are "
                "reflected into the unit circle, with a warning");
  cmd->add_option("--refine", args->refine,
                  "re-estimate the poles on the simulation error after the subspace step (B, D, x0 by least squares, "
                  "mode shapes held): auto (when --horizon differs from the automatic horizon, so the model does not "
                  "hinge on it; skipped when one Jacobian would exceed 5e8 flops (large MIMO problems)), always, never")
      ->check(CLI::IsMember({"auto", "always", "never"}))
      ->capture_default_str();
  cmd->add_option("--hankel", args->hankel,
                  "Hankel compression route: qr (Householder), cholesky (structured Gram matrix: fastest, squares the "
                  "condition number), cholesky_double_double (the same Gram matrix in double-double: as accurate as qr "
                  "up to cond 1e15), or auto (cholesky, else cholesky_double_double, else qr)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "qr", "cholesky", "cholesky_double_double"}));
  add_validation_options(*cmd, args->validate, args->split);
  cmd->add_option("--band-limit", args->band_limit_hz,
                  "HZ: low-pass inputs and outputs (Butterworth) before identification and put the filter in series "
                  "with the model, so its gain above the excited band is not arbitrary (Par2 paper remedy)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--band-limit-order", args->band_limit_order, "order of the --band-limit Butterworth filter")
      ->capture_default_str()
      ->check(CLI::Range(1, 20));
  cmd->add_option("--decimation", args->decimation,
                  "subspace step on a decimated grid: auto (when the inputs excite only the lowest quarter of the band), "
                  "1 (never) or an odd factor R")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& s) -> std::string {
            if (s == "auto") return {};
            if (!s.empty() && s.size() < 6 && s.find_first_not_of("0123456789") == std::string::npos) {
              const int r = std::stoi(s);
              if (r == 1 || (r >= 3 && r % 2 == 1)) return {};
            }
            return "expected auto, 1 or an odd factor >= 3, found '" + s + "'";
          },
          "auto|1|R"));
  CLI::Option* stabilization = cmd->add_option("--stabilization", args->stabilization,
                  "FILE (.csv, .svg or .png): the stabilisation diagram of the orders of --order LO:HI, from one "
                  "compression: every pole marked stable in frequency (1 %), damping (5 %) and, with several outputs, "
                  "mode shape (MAC >= 0.98) against the order below; the physical modes are printed and the model's "
                  "order is the lowest that holds them all. The CSV has one row per pole: order, freq_hz, damping, the "
                  "three marks (0/1), mode (1-based column, 0 none) and level (the compression's singular values "
                  "weighted by the pole's eigenvector, which the noise test compares)")
      ->check(CLI::Validator(
          [](std::string& s) -> std::string {
            for (const char* ext : {".csv", ".svg", ".png"})
              if (s.size() > 4 && s.compare(s.size() - 4, 4, ext) == 0) return {};
            return "expected a file name ending in .csv, .svg or .png, found '" + s + "'";
          },
          "FILE.csv|.svg|.png"));
  cmd->add_option("--min-level-ratio", args->min_level_ratio,
                  "with --stabilization: a column whose poles' level (the compression's singular values weighted by "
                  "their eigenvectors) is below this many times that of the poles that wander at the same orders is "
                  "named as noise and not counted as a mode; 0 counts every column")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str()
      ->needs(stabilization);
  cmd->add_option("--noise-shape-level", args->noise_shape_level,
                  "with --stabilization and many outputs (about 17 or more): a column whose mode shapes are no more "
                  "collinear (MPC) than random noise's at this level is named and not counted as a mode; 0 counts every "
                  "column (structures with strongly non-proportional damping have complex modes)")
      ->check(CLI::Range(0.0, 0.5))
      ->capture_default_str()
      ->needs(stabilization);
  cmd->add_option("--out", args->out, "model file to write (JSON, with K, offsets, x0 and provenance)");
  cmd->add_option("--plot", args->plot,
                  "plot of the singular values (and canonical correlations) that chose the order (.svg or .png; needs gnuplot)")
      ->check(plot_path_validator());
  cmd->footer(
      "Prints the order and the rule that chose it, the leading singular values, the\n"
      "simulation fit on estimation and validation data, the excited band and the modes.\n"
      "Warnings go to stderr. The model file is written at the end, atomically.\n"
      "Example:\n"
      "  sysid n4sid log.csv --inputs u --outputs y --order auto --split 0.7 --out model.json\n"
      "  sysid n4sid log.csv --inputs u1,u2 --outputs y1,y2 --order 2:12 --validate run2.csv --out model.json\n"
      "  sysid n4sid modal.csv --inputs f1,f2 --outputs a1,...,a28 --order 2:60 --stabilization stab.svg --out model.json");
  return {cmd, [args] { run_n4sid(*args); },
          [args](const std::string& log_path) {
            N4sidArgs member = *args;
            member.log_path = log_path;
            return identify_n4sid(member, true).identified;
          }};
}

}  // namespace sysid::cli
