// sysid resid: residual analysis of a model on a log (whiteness, independence of
// the inputs, Ljung-Box), verdicts in words, correlations to CSV.
#include <sysid/io/atomic_file.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/io/polynomial_model_file.hpp>
#include <sysid/core/format_lags.hpp>
#include <sysid/validate/residual_analysis.hpp>

#include <algorithm>
#include <functional>
#include <iostream>
#include <memory>
#include <sstream>

#include "cli_common.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

struct ResidArgs {
  std::string model_path, log_path, out;
  LogArgs log;
  int max_lag = 25;
  double confidence = 0.99;
  int noise_params = -1;  ///< -1: from the model file (noise_model_parameter_counts)
  std::string x0 = "estimate";
};

std::string lag_list(const std::vector<Eigen::Index>& lags) { return lags.empty() ? "none" : detail::format_lags(lags); }

/// The --out table: lag, acf_<y>..., bound, xcf_<y>_<u>, bound_<y>_<u> ..., then
/// ccf_<yi>_<yj> (i < j) for MIMO models; one row per lag -M..M.
void write_correlations(const std::string& path, const ResidualAnalysisResult& r, const std::vector<std::string>& outputs,
                        const std::vector<std::string>& inputs) {
  const Eigen::Index M = r.max_lag, l = static_cast<Eigen::Index>(outputs.size()),
                     m = static_cast<Eigen::Index>(inputs.size()), rows = 2 * M + 1;
  std::vector<std::string> names{"lag"};
  std::vector<Eigen::VectorXd> cols{Eigen::VectorXd::LinSpaced(rows, static_cast<double>(-M), static_cast<double>(M))};
  for (Eigen::Index i = 0; i < l; ++i) {
    Eigen::VectorXd c(rows);
    for (Eigen::Index tau = -M; tau <= M; ++tau) c(tau + M) = r.autocorrelation(tau < 0 ? -tau : tau, i);  // even
    names.push_back("acf_" + outputs[static_cast<std::size_t>(i)]);
    cols.push_back(c);
  }
  names.push_back("bound");
  cols.push_back(Eigen::VectorXd::Constant(rows, r.autocorrelation_bound));
  for (Eigen::Index i = 0; i < l; ++i)
    for (Eigen::Index j = 0; j < m; ++j) {
      const std::string pair = outputs[static_cast<std::size_t>(i)] + "_" + inputs[static_cast<std::size_t>(j)];
      names.push_back("xcf_" + pair);
      cols.push_back(r.input_correlation.col(i * m + j));
      names.push_back("bound_" + pair);
      cols.push_back(Eigen::VectorXd::Constant(rows, r.input_correlation_bound(i * m + j)));
    }
  for (Eigen::Index i = 0; i < l; ++i)
    for (Eigen::Index j = i + 1; j < l; ++j) {
      // corr(e_i(t + tau), e_j(t)); for tau < 0 that is corr(e_j(t + |tau|), e_i(t)).
      Eigen::VectorXd c(rows);
      for (Eigen::Index tau = -M; tau <= M; ++tau)
        c(tau + M) = tau >= 0 ? r.output_correlation[static_cast<std::size_t>(tau)](i, j)
                              : r.output_correlation[static_cast<std::size_t>(-tau)](j, i);
      names.push_back("ccf_" + outputs[static_cast<std::size_t>(i)] + "_" + outputs[static_cast<std::size_t>(j)]);
      cols.push_back(c);
    }
  Eigen::MatrixXd table(rows, static_cast<Eigen::Index>(cols.size()));
  for (std::size_t k = 0; k < cols.size(); ++k) table.col(static_cast<Eigen::Index>(k)) = cols[k];
  write_csv(path, names, table);
}

void run_resid(const ResidArgs& a) {
  const std::string verb = "resid";
  if (a.noise_params >= a.max_lag)
    throw CLI::ValidationError("--noise-params", "need --noise-params < --max-lag (the Ljung-Box degrees of freedom are "
                                                 "max-lag - noise-params)");
  claim_outputs({a.out}, {a.model_path, a.log_path});
  const ModelFile file = load_model(a.model_path);
  int noise_params = a.noise_params;
  if (noise_params < 0) {
    const std::vector<Eigen::Index> counts = noise_model_parameter_counts(file, a.model_path);
    noise_params = counts.empty() ? 0 : static_cast<int>(*std::max_element(counts.begin(), counts.end()));
    if (!counts.empty()) {
      if (noise_params >= a.max_lag)
        throw CLI::ValidationError("--max-lag", "the model's noise model has " + std::to_string(noise_params) +
                                                    " parameters (na + nc + nd): the Ljung-Box test needs --max-lag above "
                                                    "that, or give --noise-params");
      note(verb, "Ljung-Box degrees of freedom: " + std::to_string(a.max_lag) + " lags - " + std::to_string(noise_params) +
                     " noise-model parameters (na + nc + nd of " + a.model_path +
                     (std::adjacent_find(counts.begin(), counts.end(), std::not_equal_to<>()) != counts.end()
                          ? ", the largest over the outputs" : std::string()) +
                     "; --noise-params overrides)");
    }
  }
  const auto [inputs, outputs] = model_channels(a.log, file, true);
  const LoadedLog log = load_log(a.log_path, make_log_options(a.log, inputs, outputs));
  const StateSpace model = model_for_sample_time(file, log.data.Ts, a.model_path, verb);
  const Experiment& data = log.data.experiments.front();
  if (data.samples() <= a.max_lag)
    throw DataError(a.log_path, 0, 0,
                    "too few samples (" + std::to_string(data.samples()) + ") for --max-lag " + std::to_string(a.max_lag));

  const bool has_k = file.K.size() != 0;
  if (!has_k)
    note(verb, a.model_path +
                   " has no Kalman gain K (no noise model): the residuals are the simulation errors y - G u, white only "
                   "if the disturbance on the outputs is white");
  const CompareOptions o = compare_options_for(file, a.x0, a.model_path);
  const Eigen::MatrixXd residuals = model_residuals(model, file.K, data, o);
  if (!residuals.allFinite())
    throw NumericalError("the residuals of " + a.model_path + " are not finite: its " +
                         (has_k ? std::string("predictor A - K C") : std::string("A")) + " is unstable");

  ResidualAnalysisOptions ro;
  ro.max_lag = a.max_lag;
  ro.confidence = a.confidence;
  ro.noise_parameters = noise_params;
  ro.output_names = outputs;
  ro.input_names = inputs;
  const ResidualAnalysisResult r = analyze_residuals(residuals, data.u, ro);

  const std::string pct = detail::percent(a.confidence);
  std::ostringstream s;
  s << "residual analysis of " << a.model_path << " on " << a.log_path << " ("
    << (has_k ? "one-step prediction errors" : "simulation errors: the model has no K") << ", " << r.samples
    << " samples, lags up to " << r.max_lag << ", " << pct << " bounds)\n";
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const ResidualVerdict& v = r.verdicts[i];
    const auto ii = static_cast<Eigen::Index>(i);
    s << outputs[i] << ":\n";
    s << "  whiteness: " << v.whiteness << "\n";
    s << "  Ljung-Box Q = " << fmt(r.ljung_box_q(ii), 5) << " (" << r.ljung_box_lags << " lags, " << fmt(r.ljung_box_dof)
      << " dof), p = " << fmt(r.ljung_box_p(ii), 3) << "\n";
    s << "  autocorrelation: bound +-" << fmt(r.autocorrelation_bound, 3) << ", lags outside: " << lag_list(v.lags_outside)
      << "\n";
    for (std::size_t j = 0; j < outputs.size(); ++j)
      if (j != i)
        s << "  correlation with the earlier residual of " << outputs[j]
          << ": lags outside: " << lag_list(v.output_lags_outside[j]) << "\n";
    for (std::size_t j = 0; j < inputs.size(); ++j) {
      const Eigen::Index col = ii * static_cast<Eigen::Index>(inputs.size()) + static_cast<Eigen::Index>(j);
      s << "  input " << inputs[j] << ": " << v.independence[j] << "\n";
      s << "    cross-correlation: bound +-" << fmt(r.input_correlation_bound(col), 3) << " (coloured-signal factor "
        << fmt(std::sqrt(r.input_variance_factor(col)), 3) << " x z/sqrt(N)), lags outside: "
        << lag_list(v.input_lags_outside[j]) << "\n";
    }
  }
  for (const auto& w : r.warnings) warn(verb, w);
  std::cout << s.str();
  if (!a.out.empty()) {
    write_correlations(a.out, r, outputs, inputs);
    note(verb, "wrote " + a.out);
  }
}

}  // namespace

Verb register_resid(CLI::App& app) {
  auto args = std::make_shared<ResidArgs>();
  CLI::App* cmd = app.add_subcommand(
      "resid", "Residual analysis of a model on a log: whiteness, independence of the inputs, Ljung-Box test");
  cmd->add_option("model", args->model_path, "model file (JSON; state-space or polynomial)")->required();
  cmd->add_option("log", args->log_path, "CSV log with the input and output columns")->required();
  LogOptionSpec spec;
  spec.inputs_required = false;
  spec.outputs_required = false;
  spec.inputs_help = "input columns of the log, in the model's input order (default: the model's input names)";
  spec.outputs_help = "output columns of the log, in the model's output order (default: the model's output names)";
  add_log_options(*cmd, args->log, spec);
  cmd->add_option("--max-lag", args->max_lag,
                  "largest lag M: autocorrelations at 0..M, residual-input cross-correlations at -M..M; also the "
                  "Ljung-Box lags")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  cmd->add_option("--confidence", args->confidence, "confidence level of the bounds and tests")
      ->capture_default_str()
      ->check(CLI::Range(0.5, 0.999999));
  cmd->add_option("--noise-params", args->noise_params,
                  "number of estimated noise-model parameters, subtracted from the Ljung-Box degrees of freedom "
                  "(default: na + nc + nd of a polynomial model file, the largest over its outputs; 0 for a "
                  "state-space model)")
      ->check(CLI::Range(0, 1000000));
  cmd->add_option("--x0", args->x0, "initial state: estimate (least squares on this log), zero, model (stored x0)")
      ->capture_default_str()
      ->check(CLI::IsMember({"estimate", "zero", "model"}));
  cmd->add_option("--out", args->out,
                  "CSV of the correlations, one row per lag -M..M, columns: lag; acf_<y> per output (autocorrelation, "
                  "even in the lag); bound (+- bound of the acf, z/sqrt(N)); per output y and input u: xcf_<y>_<u> "
                  "(correlation of the residual at t+lag with the input at t) and bound_<y>_<u> (its coloured-signal "
                  "bound); for several outputs, ccf_<yi>_<yj> (residual of yi at t+lag with yj at t)");
  cmd->footer(
      "Residuals: the one-step-ahead prediction errors e(t) = y(t) - y^(t|t-1) of the model's innovation form\n"
      "x(t+1) = A x + B u + K (y - C x - D u); a model without K gives the simulation errors y - G u instead.\n"
      "A good model leaves residuals that are white (no autocorrelation at lags >= 1) and independent of the\n"
      "inputs. Lags > 0 of the cross-correlation (input leads residual) mean input dynamics the model misses;\n"
      "lags < 0 (residual leads input) mean feedback from the output to the input.\n"
      "Bounds: +-z/sqrt(N) for the autocorrelation; +-z sqrt(sum_k r_e(k) r_u(k) / N) for the cross-correlation\n"
      "(valid for coloured inputs and residuals). The verdicts use the Ljung-Box test and simultaneous\n"
      "(Bonferroni) bounds over all lags, so a single lag just outside a pointwise bound is not a rejection.\n"
      "Example:\n"
      "  sysid resid model.json log.csv\n"
      "  sysid resid model.json fresh.csv --inputs u --outputs y --max-lag 40 --out resid.csv");
  add_hold_option(*cmd);
  return {cmd, [args] { run_resid(*args); }};
}

}  // namespace sysid::cli
