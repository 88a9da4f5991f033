// Implementation of pem/polynomial_fit.hpp and pem/order_search.hpp (methods and references in the headers).
#include <sysid/core/errors.hpp>
#include <sysid/core/identification_warnings.hpp>
#include <sysid/pem/order_search.hpp>
#include <sysid/pem/polynomial_fit.hpp>
#include <sysid/pem/residual_whiteness.hpp>
#include <sysid/core/format_number.hpp>
#include <sysid/validate/compare.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace sysid {

const char* to_string(PolynomialStructure s) {
  switch (s) {
    case PolynomialStructure::arx: return "arx";
    case PolynomialStructure::ar: return "ar";
    case PolynomialStructure::armax: return "armax";
    case PolynomialStructure::arma: return "arma";
    case PolynomialStructure::oe: return "oe";
  }
  return "?";
}

bool has_inputs(PolynomialStructure s) {
  return s == PolynomialStructure::arx || s == PolynomialStructure::armax || s == PolynomialStructure::oe;
}

namespace {

/// The data warnings (core/identification_warnings.hpp) for a structure other than
/// ARX (arx() gives its own): the input must excite the numerator plus the
/// denominator orders (Söderström & Stoica 1989, sec. 5.4).
std::vector<std::string> data_warnings(const IoData& data, PolynomialStructure s, const PolynomialOrders& o) {
  int nb = 0, nf = 0;
  for (int v : o.nb) nb = std::max(nb, v);
  for (int v : o.nf) nf = std::max(nf, v);
  std::string model;
  int required = 0;
  switch (s) {
    case PolynomialStructure::oe:
      required = nb + nf;
      model = "OE(nb " + std::to_string(nb) + ", nf " + std::to_string(nf) + ")";
      break;
    case PolynomialStructure::armax:
      required = o.na + nb;
      model = "ARMAX(na " + std::to_string(o.na) + ", nb " + std::to_string(nb) + ")";
      break;
    default: break;  // AR, ARMA: no input, only the output checks apply
  }
  return identification_data_warnings(data, has_inputs(s) ? required : 0, model, to_string(s));
}

/// Level of the residual whiteness test, over all outputs (Bonferroni): a
/// warning, so false alarms on records the model describes must be rare.
constexpr double kWhitenessLevel = 1e-3;

const char* ar_method_words(ArMethod method) {
  switch (method) {
    case ArMethod::least_squares: return "least squares";
    case ArMethod::yule_walker: return "Yule-Walker";
    case ArMethod::burg: return "Burg's method";
    case ArMethod::modified_yule_walker: return "modified Yule-Walker";
  }
  return "?";
}

/// The warning of a time-series model whose one-step residual is not white
/// (pem/residual_whiteness.hpp): what it means, and what to fit instead.
std::string residual_correlation_warning(PolynomialStructure s, ArMethod method, const PolynomialModel& model,
                                         const LjungBoxTest& test, const std::string& output) {
  const std::string na = std::to_string(model.na()), nc = std::to_string(model.nc());
  const std::string p = test.p_value < 1e-12 ? "p < 1e-12" : "p = " + format_number(test.p_value, 2);
  std::string w = std::string(to_string(s)) + ": output '" + output + "': the one-step residuals of the " +
                  (s == PolynomialStructure::ar ? "AR(" + na + ")" : "ARMA(" + na + ", " + nc + ")") +
                  " are not white (Ljung-Box Q = " + format_number(test.statistic, 4) + " over " + std::to_string(test.lags) +
                  " lags, " + format_number(test.degrees_of_freedom, 4) + " degrees of freedom, " + p +
                  "): the model leaves correlation in the record, and its poles are biased. ";
  if (s == PolynomialStructure::ar)
    return w + "Measurement noise on the record does this: " + ar_method_words(method) +
           " then puts resonances too lightly damped and loses weak ones. Fit again with the modified Yule-Walker method "
           "(method myw), which white measurement noise does not bias, or an ARMA(" + na + ", " + na +
           ") model, and compare the modes; if the order is too low, raise na.";
  return w + "An AR(na) process seen through white measurement noise is an ARMA(na, na) process: " +
         (model.nc() < model.na() ? "fit with nc >= na (" + na + ")" : std::string("raise na and nc")) +
         ", and compare the modes.";
}

}  // namespace


PolynomialFit fit_polynomial(const IoData& data, const PolynomialFitOptions& options) {
  const PolynomialStructure s = options.structure;
  const PolynomialOrders& o = options.orders;
  const Eigen::Index m = has_inputs(s) ? data.inputs() : 0, l = data.outputs();
  PolynomialFit fit;
  fit.samples = data.total_samples();
  fit.input_offset = Eigen::VectorXd::Zero(data.inputs());
  fit.output_offset = Eigen::VectorXd::Zero(l);
  if (s == PolynomialStructure::arx || s == PolynomialStructure::ar) {
    LinearPolynomialResult r;
    if (s == PolynomialStructure::arx) {
      ArxOptions a;
      a.na = o.na;
      a.nb = o.nb;
      a.nk = o.nk;
      r = arx(data, a);
    } else {
      ArOptions a;
      a.na = o.na;
      a.method = options.ar_method;
      r = ar(data, a);
    }
    fit.models = std::move(r.models);
    if (m > 0) fit.input_offset = r.input_offset;
    fit.output_offset = r.output_offset;
    fit.warnings = std::move(r.warnings);
    fit.method_notes.assign(static_cast<std::size_t>(l), "linear least squares");
    if (s == PolynomialStructure::ar)
      for (auto& w : data_warnings(data, s, o)) fit.warnings.push_back(std::move(w));
  } else {
    fit.warnings = data_warnings(data, s, o);
    PemOptions p;
    p.na = s == PolynomialStructure::oe ? 0 : o.na;
    p.nc = s == PolynomialStructure::oe ? 0 : o.nc;
    p.nb = m > 0 ? o.nb : std::vector<int>{};
    p.nk = m > 0 ? o.nk : std::vector<int>{};
    if (s == PolynomialStructure::oe) p.nf = o.nf;
    p.max_iterations = options.max_iterations;
    IoData target = data;
    if (m == 0)
      for (auto& e : target.experiments) e.u.resize(e.y.rows(), 0);
    if (m == 0) target.input_names.clear();
    for (Eigen::Index r = 0; r < l; ++r) {
      p.output = r;
      PemResult res = pem(target, p);
      if (m > 0) fit.input_offset = res.input_offset;
      fit.output_offset(r) = res.output_offset(r);
      std::ostringstream note;
      note << res.iterations << " iterations, " << (res.status == PemResult::Status::converged ? "converged" : "NOT converged")
           << " (" << res.termination << "), cost " << res.initial_cost << " -> " << res.final_cost << ", condition "
           << std::setprecision(3) << res.condition << (res.start.empty() ? "" : ", from the " + res.start + " start");
      fit.method_notes.push_back(note.str());
      if (res.status != PemResult::Status::converged) fit.converged = false;
      fit.warnings.insert(fit.warnings.end(), res.warnings.begin(), res.warnings.end());
      fit.models.push_back(std::move(res.model));
    }
  }
  for (Eigen::Index r = 0; r < l; ++r) {
    const PolynomialModel& pm = fit.models[static_cast<std::size_t>(r)];
    fit.parameters += pack_parameters(pm).size();
    // Each method's own residual variance (from its QR factor or its cost:
    // re-filtering the data would add the rounding of high-order polynomial
    // coefficients), made the maximum-likelihood RSS / N.
    const double p = static_cast<double>(pack_parameters(pm).size()), n = static_cast<double>(fit.samples);
    fit.loss.push_back(pm.noise_variance * std::max(0.0, n - p) / n);
    for (auto& w : unstable_model_warnings(to_innovation_state_space(pm).model, to_string(s)))
      fit.warnings.push_back(data.outputs() > 1 ? w + " (output " + data.output_name(r) + ")" : w);
    if (s == PolynomialStructure::ar || s == PolynomialStructure::arma) {
      const std::optional<LjungBoxTest> test = one_step_residual_whiteness(pm, data, r, fit.output_offset(r));
      fit.residual_whiteness.push_back(test.value_or(LjungBoxTest{}));
      const bool tested = !(s == PolynomialStructure::ar && options.ar_method == ArMethod::modified_yule_walker);
      if (tested && test && test->p_value < kWhitenessLevel / static_cast<double>(l))
        fit.warnings.push_back(residual_correlation_warning(s, options.ar_method, pm, *test, data.output_name(r)));
    }
  }
  return fit;
}

const char* to_string(OrderCriterion c) {
  switch (c) {
    case OrderCriterion::validation_fit: return "fit";
    case OrderCriterion::aic: return "aic";
    case OrderCriterion::bic: return "bic";
    case OrderCriterion::fpe: return "fpe";
  }
  return "?";
}

std::vector<PolynomialOrders> order_combinations(const PolynomialOrderGrid& grid, PolynomialStructure structure) {
  // The varying dimensions: na, nc, nb_i, nf_i (those the structure uses).
  std::vector<OrderRange> dims;
  const bool uses_a = structure != PolynomialStructure::oe, uses_c = structure == PolynomialStructure::armax || structure == PolynomialStructure::arma;
  const bool uses_b = has_inputs(structure), uses_f = structure == PolynomialStructure::oe;
  dims.push_back(uses_a ? grid.na : OrderRange{0, 0});
  dims.push_back(uses_c ? grid.nc : OrderRange{0, 0});
  const std::size_t m = uses_b ? grid.nb.size() : 0;
  for (std::size_t i = 0; i < m; ++i) dims.push_back(grid.nb[i]);
  for (std::size_t i = 0; i < m; ++i) dims.push_back(uses_f && i < grid.nf.size() ? grid.nf[i] : OrderRange{0, 0});
  for (const auto& d : dims)
    if (d.lo < 0 || d.hi < d.lo)
      throw std::invalid_argument("order search: need 0 <= lo <= hi in every range, found " + std::to_string(d.lo) + ":" + std::to_string(d.hi));
  std::vector<PolynomialOrders> out;
  std::vector<int> at(dims.size());
  for (std::size_t k = 0; k < dims.size(); ++k) at[k] = dims[k].lo;
  while (true) {
    PolynomialOrders o;
    o.na = at[0];
    o.nc = at[1];
    for (std::size_t i = 0; i < m; ++i) o.nb.push_back(at[2 + i]);
    if (uses_f)
      for (std::size_t i = 0; i < m; ++i) o.nf.push_back(at[2 + m + i]);
    o.nk = grid.nk;
    out.push_back(std::move(o));
    // Odometer increment, the last dimension fastest.
    std::size_t k = dims.size();
    while (k > 0) {
      --k;
      if (at[k] < dims[k].hi) {
        ++at[k];
        break;
      }
      at[k] = dims[k].lo;
      if (k == 0) return out;
    }
    if (dims.empty()) return out;
  }
}

OrderSearchResult search_polynomial_orders(const IoData& estimation, const IoData* validation, const PolynomialOrderGrid& grid,
                                           const OrderSearchOptions& options) {
  if (options.criterion == OrderCriterion::validation_fit && !validation)
    throw std::invalid_argument("order search: choosing by validation fit needs validation data (--validate or --split)");
  const PolynomialStructure s = options.fit.structure;
  const std::vector<PolynomialOrders> combos = order_combinations(grid, s);
  if (combos.size() > options.max_combinations)
    throw std::invalid_argument("order search: " + std::to_string(combos.size()) + " order combinations exceed the limit of " +
                                std::to_string(options.max_combinations) + "; narrow the ranges");
  OrderSearchResult result;
  result.criterion = options.criterion;
  const double n = static_cast<double>(estimation.total_samples());
  double best_score = std::numeric_limits<double>::infinity();
  bool any = false;
  for (const auto& orders : combos) {
    PolynomialFitOptions fo = options.fit;
    fo.orders = orders;
    PolynomialFit fit = fit_polynomial(estimation, fo);
    OrderScore row;
    row.orders = orders;
    row.parameters = fit.parameters;
    row.converged = fit.converged;
    for (std::size_t r = 0; r < fit.models.size(); ++r) {
      const double p = static_cast<double>(pack_parameters(fit.models[r]).size());
      const double v = fit.loss[r];
      row.aic += n * std::log(v) + 2.0 * p;
      row.bic += n * std::log(v) + p * std::log(n);
      row.fpe += p < n ? v * (1.0 + p / n) / (1.0 - p / n) : std::numeric_limits<double>::infinity();
    }
    row.validation_fit = std::numeric_limits<double>::quiet_NaN();
    if (validation) {
      const InnovationStateSpace ss = to_innovation_state_space(fit.models);
      CompareOptions co;
      co.input_offset = fit.input_offset.head(ss.model.inputs());
      co.output_offset = fit.output_offset;
      row.validation_fit = compare_fit(ss.model, ss.K, *validation, co).mean();
    }
    const double score = options.criterion == OrderCriterion::validation_fit ? -row.validation_fit
                         : options.criterion == OrderCriterion::aic        ? row.aic
                         : options.criterion == OrderCriterion::bic        ? row.bic
                                                                            : row.fpe;
    if (row.converged && std::isfinite(score) && score < best_score) {
      best_score = score;
      result.best = result.table.size();
      result.best_fit = std::move(fit);
      any = true;
    }
    result.table.push_back(std::move(row));
  }
  if (!any) throw NumericalError("order search: no order combination converged to a finite score");
  const std::size_t not_converged =
      static_cast<std::size_t>(std::count_if(result.table.begin(), result.table.end(), [](const OrderScore& r) { return !r.converged; }));
  if (not_converged > 0)
    result.warnings.push_back("order search: " + std::to_string(not_converged) + " of " + std::to_string(result.table.size()) +
                              " combinations did not converge (marked '!', never chosen)");
  return result;
}

namespace {
std::string join_orders(const std::vector<int>& v) {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + std::to_string(v[i]);
  return s;
}
}  // namespace

std::string format_order_table(const OrderSearchResult& result, PolynomialStructure structure) {
  std::ostringstream s;
  const bool a = structure != PolynomialStructure::oe, c = structure == PolynomialStructure::armax || structure == PolynomialStructure::arma;
  const bool b = has_inputs(structure), f = structure == PolynomialStructure::oe;
  s << "  ";
  if (a) s << std::setw(5) << "na";
  if (b) s << std::setw(8) << "nb";
  if (c) s << std::setw(5) << "nc";
  if (f) s << std::setw(8) << "nf";
  s << std::setw(7) << "p" << std::setw(16) << "AIC" << std::setw(16) << "BIC" << std::setw(14) << "FPE" << std::setw(10) << "fit [%]\n";
  for (std::size_t k = 0; k < result.table.size(); ++k) {
    const OrderScore& r = result.table[k];
    s << (k == result.best ? '*' : r.converged ? ' ' : '!') << ' ';
    if (a) s << std::setw(5) << r.orders.na;
    if (b) s << std::setw(8) << join_orders(r.orders.nb);
    if (c) s << std::setw(5) << r.orders.nc;
    if (f) s << std::setw(8) << join_orders(r.orders.nf);
    s << std::setw(7) << r.parameters << std::setw(16) << std::setprecision(8) << r.aic << std::setw(16) << r.bic << std::setw(14)
      << std::setprecision(5) << r.fpe << std::setw(9);
    if (std::isnan(r.validation_fit))
      s << "-";
    else
      s << std::fixed << std::setprecision(2) << r.validation_fit << std::defaultfloat;
    s << "\n";
  }
  s << "(* chosen by " << to_string(result.criterion) << "; ! did not converge)\n";
  return s.str();
}

}  // namespace sysid
