// sysid arx | ar | armax | arma | oe: polynomial (prediction-error) models from a
// CSV log, one model per output over all inputs ("stacked MISO"), written as a
// "polynomial" model file with its innovation-form state space.
#include <sysid/core/modal_table.hpp>
#include <sysid/core/parallel_for.hpp>
#include <sysid/io/atomic_file.hpp>
#include <sysid/io/polynomial_model_file.hpp>
#include <sysid/pem/arx.hpp>
#include <sysid/pem/order_search.hpp>
#include <sysid/pem/polynomial_fit.hpp>
#include <sysid/pem/prediction_error.hpp>
#include <sysid/validate/compare.hpp>

#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "cli_common.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

using Structure = PolynomialStructure;
const char* name_of(Structure s) { return to_string(s); }

struct PolynomialArgs {
  std::string log_path;
  LogArgs log;
  std::string na = "0", nc = "0";
  std::string nb = "1", nf = "1", nk = "1";
  std::string select;
  std::string ar_method = "ls";
  int max_iterations = PemOptions{}.max_iterations;
  bool write_unconverged = false;
  std::string validate;
  std::optional<double> split;
  std::string out;
};

/// "8" or "8:32" -> an order range, each end >= minimum. Bad orders are bad
/// input (exit 2, std::invalid_argument), as the library reports them.
OrderRange parse_order_range(const std::string& item, const std::string& option, int minimum) {
  const auto colon = item.find(':');
  const auto number = [&](const std::string& t) {
    if (t.empty() || t.size() > 6 || t.find_first_not_of("-0123456789") != std::string::npos)
      throw std::invalid_argument(option + ": expected an integer, a range lo:hi, or a comma-separated list of them, found '" + item + "'");
    const int v = std::stoi(t);
    if (v < minimum)
      throw std::invalid_argument(option + ": expected values >= " + std::to_string(minimum) + ", found " + std::to_string(v) +
                                  (option == "--nk" ? " (a negative delay would make the model non-causal)" : ""));
    return v;
  };
  OrderRange r;
  r.lo = number(item.substr(0, colon));
  r.hi = colon == std::string::npos ? r.lo : number(item.substr(colon + 1));
  if (r.hi < r.lo) throw std::invalid_argument(option + ": range '" + item + "' has hi < lo");
  return r;
}

/// "4" / "4:8" (every input) or "4,2:3,..." (one per input) -> one range per input.
std::vector<OrderRange> per_input_ranges(const std::string& text, Eigen::Index inputs, const std::string& option, int minimum) {
  std::vector<OrderRange> values;
  for (const std::string& item : split_names(text, option)) values.push_back(parse_order_range(item, option, minimum));
  if (values.size() == 1) return std::vector<OrderRange>(static_cast<std::size_t>(inputs), values.front());
  if (static_cast<Eigen::Index>(values.size()) != inputs)
    throw std::invalid_argument(option + ": expected one value or one per input (" + std::to_string(inputs) + "), found " +
                                std::to_string(values.size()));
  return values;
}

/// Per input fixed orders (a range is refused: delays are not searched).
std::vector<int> per_input_orders(const std::string& text, Eigen::Index inputs, const std::string& option, int minimum) {
  std::vector<int> out;
  for (const OrderRange& r : per_input_ranges(text, inputs, option, minimum)) {
    if (r.hi != r.lo) throw std::invalid_argument(option + ": expected a single value, not a range");
    out.push_back(r.lo);
  }
  return out;
}

std::string format_polynomial(const Eigen::VectorXd& p) {
  std::ostringstream s;
  s << "[";
  for (Eigen::Index k = 0; k < p.size(); ++k) s << (k ? ", " : "") << fmt(p(k), 6);
  s << "]";
  return s.str();
}

/// What identify_polynomial found (the model file, report and warnings) and
/// whether the minimisation converged.
struct PolynomialOutcome {
  Identified identified;
  bool converged = true;
};

/// Loads the log, fits, builds the report and the model file; prints and writes
/// nothing (run_polynomial does, and `sysid family` calls this per member).
PolynomialOutcome identify_polynomial(Structure structure, const PolynomialArgs& a, bool keep_estimation) {
  const std::string verb = name_of(structure);
  PolynomialOutcome outcome;
  Identified& identified = outcome.identified;
  const LogOptions log_options = make_log_options(
      a.log, has_inputs(structure) ? split_names(a.log.inputs, "--inputs") : std::vector<std::string>{},
      split_names(a.log.outputs, "--outputs"));
  identified.log_options = log_options;
  EstimationData data = load_estimation_data(a.log_path, a.validate, a.split, log_options);
  const IoData& est = data.estimation;
  if (keep_estimation) identified.estimation = est;
  const Eigen::Index m = est.inputs(), l = est.outputs();

  // Orders: single values fit once; any range (lo < hi) searches the grid.
  PolynomialOrderGrid grid;
  const bool uses_a = structure != Structure::oe, uses_c = structure == Structure::armax || structure == Structure::arma;
  grid.na = uses_a ? parse_order_range(a.na, "--na", structure == Structure::arx ? 0 : 1) : OrderRange{};
  grid.nc = uses_c ? parse_order_range(a.nc, "--nc", 1) : OrderRange{};
  if (has_inputs(structure)) {
    grid.nb = per_input_ranges(a.nb, m, "--nb", 0);
    grid.nk = per_input_orders(a.nk, m, "--nk", 0);
    if (structure == Structure::oe) grid.nf = per_input_ranges(a.nf, m, "--nf", 0);
  }
  OrderSearchOptions search;
  search.fit.structure = structure;
  search.fit.ar_method = ar_method_from_name(a.ar_method);
  search.fit.max_iterations = a.max_iterations;
  const std::vector<PolynomialOrders> combos = order_combinations(grid, structure);
  std::ostringstream report;
  PolynomialFit fit;
  std::vector<std::string>& warnings = identified.warnings;
  if (combos.size() == 1) {
    search.fit.orders = combos.front();
    fit = fit_polynomial(est, search.fit);
  } else {
    const std::string select = a.select.empty() ? (data.validation ? "fit" : "aic") : a.select;
    search.criterion = select == "fit" ? OrderCriterion::validation_fit : select == "bic" ? OrderCriterion::bic
                       : select == "fpe" ? OrderCriterion::fpe : OrderCriterion::aic;
    OrderSearchResult found = search_polynomial_orders(est, data.validation ? &*data.validation : nullptr, grid, search);
    report << verb << ": " << found.table.size() << " order combinations (fit on "
           << (data.validation ? data.validation_label : std::string("no validation data")) << ")\n"
           << format_order_table(found, structure);
    warnings = found.warnings;
    search.fit.orders = found.table[found.best].orders;
    fit = std::move(found.best_fit);
  }
  const std::vector<PolynomialModel>& models = fit.models;
  const Eigen::VectorXd input_offset = fit.input_offset.head(m), output_offset = fit.output_offset;
  outcome.converged = fit.converged;
  warnings.insert(warnings.end(), fit.warnings.begin(), fit.warnings.end());
  for (Eigen::Index r = 0; r < l; ++r)
    report << verb << " output '" << est.output_name(r) << "': " << fit.method_notes[static_cast<std::size_t>(r)]
           << (structure == Structure::ar ? " (" + a.ar_method + ")" : std::string()) << "\n";

  identified.file = polynomial_fit_model_file(fit, search.fit, est.input_names, est.output_names);
  ModelFile& file = identified.file;
  for (Eigen::Index r = 0; r < l; ++r) {
    const PolynomialModel& pm = models[static_cast<std::size_t>(r)];
    report << "output '" << est.output_name(r) << "': noise variance " << fmt(pm.noise_variance, 5) << "\n  A = "
           << format_polynomial(pm.A) << "\n";
    for (Eigen::Index i = 0; i < pm.inputs(); ++i)
      report << "  B(" << est.input_name(i) << ") = " << format_polynomial(pm.B[static_cast<std::size_t>(i)]) << " (nk "
             << pm.nk[static_cast<std::size_t>(i)] << ")"
             << (pm.nf(i) > 0 ? ", F = " + format_polynomial(pm.F[static_cast<std::size_t>(i)]) : std::string()) << "\n";
    if (pm.nc() > 0) report << "  C = " << format_polynomial(pm.C) << "\n";
  }
  CompareOptions co;
  co.input_offset = input_offset;
  co.output_offset = output_offset;
  const std::vector<std::string> names = model_output_names(file);
  // The fits are independent: computed on the cores (core/parallel_for.hpp), printed in order.
  CompareOptions one_step = co;
  one_step.predict_steps = 1;
  const IoData& one_step_data = data.validation ? *data.validation : est;
  Eigen::VectorXd estimation_fit, validation_fit, one_step_fit;
  parallel_invoke([&] { if (m > 0) estimation_fit = compare_fit(file.model, file.K, est, co); },
                  [&] { if (m > 0 && data.validation) validation_fit = compare_fit(file.model, file.K, *data.validation, co); },
                  [&] { one_step_fit = compare_fit(file.model, file.K, one_step_data, one_step); });
  if (m > 0) {
    report << "fit on estimation data [%] (simulation, x0 estimated):\n" << format_fit_lines(estimation_fit, names);
    if (data.validation)
      report << "fit on validation data [%] (simulation, x0 estimated, " << data.validation_label << "):\n"
             << format_fit_lines(validation_fit, names);
  }
  report << "one-step prediction fit [%] on " << (data.validation ? "validation" : "estimation") << " data:\n"
         << format_fit_lines(one_step_fit, names);
  report << "modes:\n" << format_modal_table(modal_table(file.model));
  identified.report = report.str();
  nlohmann::json& p = file.provenance;
  p["data"] = a.log_path;
  if (combos.size() > 1) p["order_selection"] = to_string(search.criterion);
  if (data.validation) p["validation"] = data.validation_label;
  return outcome;
}

void run_polynomial(Structure structure, const PolynomialArgs& a) {
  const std::string verb = name_of(structure);
  std::vector<std::string> inputs_files{a.log_path};
  if (!a.validate.empty()) inputs_files.push_back(a.validate);
  claim_outputs({a.out}, inputs_files);
  const PolynomialOutcome outcome = identify_polynomial(structure, a, false);
  std::cout << outcome.identified.report << std::flush;
  for (const auto& w : outcome.identified.warnings) warn(verb, w);

  if (!outcome.converged && !a.write_unconverged)
    throw NumericalError(verb + ": the prediction-error minimisation did not converge (see above); no model written "
                                "(--write-unconverged writes it anyway)");
  if (!a.out.empty()) {
    write_model_json(a.out, outcome.identified.file);
    note(verb, "wrote " + a.out);
  }
  if (!outcome.converged)
    throw NumericalError(verb + ": the prediction-error minimisation did not converge; model written as asked");
}

/// identify_polynomial for `sysid family`: an unconverged fit is an error unless
/// --write-unconverged was given, then a warning.
Identified identify_polynomial_member(Structure structure, const PolynomialArgs& args, const std::string& log_path) {
  PolynomialArgs member = args;
  member.log_path = log_path;
  PolynomialOutcome outcome = identify_polynomial(structure, member, true);
  if (!outcome.converged) {
    if (!args.write_unconverged)
      throw NumericalError(std::string(name_of(structure)) + ": the prediction-error minimisation did not converge on " +
                           log_path + " (--write-unconverged keeps such members)");
    outcome.identified.warnings.push_back("the prediction-error minimisation did not converge; kept as asked");
  }
  return std::move(outcome.identified);
}

Verb register_structure(CLI::App& app, Structure structure, const std::string& description, const std::string& example) {
  auto args = std::make_shared<PolynomialArgs>();
  const std::string verb = name_of(structure);
  CLI::App* cmd = app.add_subcommand(verb, description);
  cmd->add_option("log", args->log_path, "CSV log with the input and output columns")->required();
  LogOptionSpec spec;
  spec.inputs_required = has_inputs(structure);
  add_log_options(*cmd, args->log, spec);
  if (structure != Structure::oe)
    cmd->add_option("--na", args->na, "order of A (poles); a range lo:hi searches")->required();
  if (has_inputs(structure)) {
    cmd->add_option("--nb", args->nb, "coefficients of B per input (one number or range lo:hi for every input, or a comma-separated list)")
        ->required();
    cmd->add_option("--nk", args->nk, "input delay in samples (one number, or one per input)")->capture_default_str();
  }
  if (structure == Structure::armax || structure == Structure::arma)
    cmd->add_option("--nc", args->nc, "order of C (noise zeros); a range lo:hi searches")->required();
  if (structure == Structure::oe)
    cmd->add_option("--nf", args->nf, "order of F per input (one number or range, or one per input)")->required();
  if (structure == Structure::ar)
    cmd->add_option("--method", args->ar_method,
                    "ls (least squares), burg, yw (Yule-Walker), or myw (modified Yule-Walker: lags na+1..5 na only, "
                    "unbiased when the sensor adds white noise)")
        ->capture_default_str()
        ->check(CLI::IsMember({"ls", "burg", "yw", "myw"}));
  if (structure == Structure::armax || structure == Structure::arma || structure == Structure::oe) {
    cmd->add_option("--max-iterations", args->max_iterations, "Gauss-Newton / Levenberg-Marquardt iterations at most")
        ->capture_default_str()
        ->check(CLI::Range(0, 100000));
    cmd->add_flag("--write-unconverged", args->write_unconverged,
                  "write the model even when the minimisation did not converge (the exit code is still 3)");
  }
  add_validation_options(*cmd, args->validate, args->split);
  cmd->add_option("--select", args->select,
                  "with order ranges: choose by fit (validation fit; the default with --validate/--split), aic (the default "
                  "otherwise), bic or fpe")
      ->check(CLI::IsMember({"fit", "aic", "bic", "fpe"}));
  cmd->add_option("--out", args->out, "model file to write (JSON, type polynomial, with its state space)");
  cmd->footer("Prints the polynomials, the fit on estimation and validation data and the modes. With order ranges\n"
              "(--na 8:32 ...) every combination is fitted and scored by AIC, BIC, FPE and validation fit in a table;\n"
              "the best by --select is written.\nExample:\n  " + example);
  return {cmd, [args, structure] { run_polynomial(structure, *args); },
          [args, structure](const std::string& log_path) { return identify_polynomial_member(structure, *args, log_path); }};
}

}  // namespace

Verb register_arx(CLI::App& app) {
  return register_structure(app, Structure::arx, "ARX model A y = B u + e by least squares (one per output)",
                            "sysid arx log.csv --inputs u --outputs y --na 4 --nb 4 --nk 1 --split 0.7 --out arx.json");
}
Verb register_ar(CLI::App& app) {
  return register_structure(app, Structure::ar, "AR time-series model A y = e (least squares, Burg or Yule-Walker)",
                            "sysid ar disturbance.csv --outputs y --na 16 --method burg --out ar.json");
}
Verb register_armax(CLI::App& app) {
  return register_structure(app, Structure::armax, "ARMAX model A y = B u + C e by prediction-error minimisation",
                            "sysid armax log.csv --inputs u --outputs y --na 10 --nb 10 --nc 10 --nk 0 --out armax.json");
}
Verb register_arma(CLI::App& app) {
  return register_structure(app, Structure::arma, "ARMA time-series model A y = C e by prediction-error minimisation",
                            "sysid arma disturbance.csv --outputs y --na 16 --nc 8 --out arma.json");
}
Verb register_oe(CLI::App& app) {
  return register_structure(app, Structure::oe, "output-error model y = B/F u + e by prediction-error minimisation",
                            "sysid oe log.csv --inputs u --outputs y --nb 4 --nf 4 --nk 1 --out oe.json");
}

}  // namespace sysid::cli
