// The initial values of pem's iterations (src/pem/detail/pem_starts.hpp; method
// in include/sysid/pem/prediction_error.hpp).
#include <sysid/core/transfer_function.hpp>
#include <sysid/pem/lagged_regression.hpp>
#include <sysid/pem/prediction_error.hpp>
#include <sysid/signal/polynomial_filter.hpp>
#include <sysid/subspace/n4sid.hpp>

#include <algorithm>
#include <exception>
#include <string>
#include <vector>

#include "pem/detail/pem_starts.hpp"
#include "pem/detail/polynomial_utilities.hpp"

namespace sysid::detail::pem_impl {

namespace {

/// The OE start's ARX denominator has roots outside the unit circle: the plant is
/// likely unstable, which an output-error model (a simulation, kept stable during
/// the iterations) cannot represent.
constexpr const char* unstable_plant_warning =
    "pem: the ARX estimate of F is unstable: the plant itself may be unstable, which an output-error model "
    "cannot represent (its simulation diverges; F is kept stable); use arx, armax or n4sid for an unstable plant";

IoData records_as_data(const std::vector<ScaledRecord>& records, double Ts) {
  IoData d;
  d.Ts = Ts;
  for (const auto& r : records) d.experiments.push_back({r.u, r.y, "scaled record"});
  return d;
}

/// [1, p_1..p_n] of det(zI - M), read as a polynomial in q^-1.
Eigen::VectorXd characteristic_polynomial(const Eigen::MatrixXd& M) {
  if (M.rows() == 0) return Eigen::VectorXd::Ones(1);
  return poly_from_roots(M.eigenvalues());
}

/// `p` cut or zero-padded to `size` coefficients.
Eigen::VectorXd resized(const Eigen::VectorXd& p, Eigen::Index size) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(size);
  const Eigen::Index n = std::min(size, p.size());
  out.head(n) = p.head(n);
  return out;
}

}  // namespace

RegressionSolution arx_regression(const std::vector<ScaledRecord>& records, int na, const std::vector<int>& nb,
                                  const std::vector<int>& nk, const std::vector<Eigen::VectorXd>* noise, int nc) {
  const Eigen::Index m = static_cast<Eigen::Index>(nb.size());
  std::vector<Eigen::MatrixXd> signals;
  for (std::size_t e = 0; e < records.size(); ++e) {
    const auto& r = records[e];
    Eigen::MatrixXd s(r.y.size(), 1 + m + (noise ? 1 : 0));
    s.col(0) = r.y;
    if (m > 0) s.middleCols(1, m) = r.u;
    if (noise) s.col(1 + m) = (*noise)[e];
    signals.push_back(std::move(s));
  }
  std::vector<RegressionTerm> terms{{0, 1, na, -1.0}};
  for (Eigen::Index i = 0; i < m; ++i) terms.push_back({1 + i, nk[static_cast<std::size_t>(i)], nb[static_cast<std::size_t>(i)], 1.0});
  if (noise) terms.push_back({1 + m, 1, nc, 1.0});
  return lagged_least_squares(signals, 0, terms);
}

void hannan_rissanen(PolynomialModel& model, const std::vector<ScaledRecord>& records, int high_order) {
  const Eigen::Index m = model.inputs();
  std::vector<int> nb_high(static_cast<std::size_t>(m), high_order);
  for (Eigen::Index i = 0; i < m; ++i)
    if (model.nb(i) == 0) nb_high[static_cast<std::size_t>(i)] = 0;
  const RegressionSolution high = arx_regression(records, high_order, nb_high, model.nk, nullptr, 0);
  PolynomialModel h = model;
  h.A = Eigen::VectorXd(high_order + 1);
  h.A << 1.0, high.theta.head(high_order);
  Eigen::Index at = high_order;
  for (Eigen::Index i = 0; i < m; ++i) {
    const auto k = static_cast<std::size_t>(i);
    h.B[k] = high.theta.segment(at, nb_high[k]);
    at += nb_high[k];
  }
  h.C = Eigen::VectorXd::Ones(1);
  h.D = Eigen::VectorXd::Ones(1);
  std::vector<Eigen::VectorXd> residuals;
  for (const auto& r : records) residuals.push_back(prediction_errors(h, r.u, r.y, false).eps);
  std::vector<int> nb(static_cast<std::size_t>(m));
  for (Eigen::Index i = 0; i < m; ++i) nb[static_cast<std::size_t>(i)] = model.nb(i);
  const RegressionSolution sol = arx_regression(records, model.na(), nb, model.nk, &residuals, model.nc());
  Eigen::VectorXd theta = pack_parameters(model);
  // Same order as pack_parameters for ARMAX (a, b, c) since D and F are trivial here.
  theta.head(sol.theta.size()) = sol.theta;
  unpack_parameters(theta, model);
  model.C = reflect_into_unit_circle(model.C);
}

void output_error_start(PolynomialModel& model, const std::vector<ScaledRecord>& records, int passes,
                        std::vector<std::string>& warnings) {
  const Eigen::Index m = model.inputs();
  std::vector<int> nb(static_cast<std::size_t>(m));
  int nf_max = 0;
  bool equal = true;
  for (Eigen::Index i = 0; i < m; ++i) {
    nb[static_cast<std::size_t>(i)] = model.nb(i);
    if (i > 0 && model.nf(i) != model.nf(0)) equal = false;
    nf_max = std::max(nf_max, model.nf(i));
  }
  if (!equal) {
    // Different denominators: each input's F from its own single-input ARX (the others act as noise).
    for (Eigen::Index i = 0; i < m; ++i) {
      const auto k = static_cast<std::size_t>(i);
      std::vector<ScaledRecord> single;
      for (const auto& r : records) single.push_back({r.u.col(i), r.y});
      const RegressionSolution sol = arx_regression(single, model.nf(i), {model.nb(i)}, {model.nk[k]}, nullptr, 0);
      model.F[k] = Eigen::VectorXd(model.nf(i) + 1);
      model.F[k] << 1.0, sol.theta.head(model.nf(i));
      if (!strictly_stable(model.F[k])) warnings.push_back(unstable_plant_warning);
      model.F[k] = reflect_into_unit_circle(model.F[k]);
      model.B[k] = sol.theta.tail(model.nb(i));
    }
    warnings.push_back("pem: inputs with different nf: OE started from single-input ARX fits (no Steiglitz-McBride passes)");
    return;
  }
  Eigen::VectorXd f = Eigen::VectorXd::Ones(1);
  for (int pass = 0; pass <= passes; ++pass) {
    // Pass 0: plain ARX; later passes: the data filtered by 1 / F of the previous pass.
    std::vector<ScaledRecord> filtered;
    for (const auto& r : records)
      filtered.push_back({filter_polynomial(Eigen::VectorXd::Ones(1), f, r.u), filter_polynomial(Eigen::VectorXd::Ones(1), f, r.y)});
    const RegressionSolution sol = arx_regression(filtered, nf_max, nb, model.nk, nullptr, 0);
    f = Eigen::VectorXd(nf_max + 1);
    f << 1.0, sol.theta.head(nf_max);
    if (pass == 0 && !strictly_stable(f))
      warnings.push_back(unstable_plant_warning);
    f = reflect_into_unit_circle(f);
    Eigen::Index at = nf_max;
    for (Eigen::Index i = 0; i < m; ++i) {
      const auto k = static_cast<std::size_t>(i);
      model.B[k] = sol.theta.segment(at, model.nb(i));
      model.F[k] = f;
      at += model.nb(i);
    }
  }
}

int hannan_rissanen_order(const PemOptions& options, double total) {
  int high = options.initial_arx_order;
  if (high == 0) {
    int max_nb = 0;
    for (int b : options.nb) max_nb = std::max(max_nb, b);
    high = std::max(3 * std::max({options.na, max_nb, options.nc}), 20);
    high = std::min<int>(high, static_cast<int>(total / 20.0));
  }
  if (high <= options.nc) throw std::invalid_argument("pem: too few samples for the Hannan-Rissanen start of these orders");
  return high;
}

bool armax_output_error_start(PolynomialModel& model, const std::vector<ScaledRecord>& records, const PemOptions& options) {
  const Eigen::Index m = model.inputs();
  PemOptions oe;
  oe.nb = options.nb;
  oe.nk = model.nk;
  // F of order min(na, nc), zero-padded into both A and C: C / A = 1 exactly
  // (roots at the origin fill the higher order).
  const int nf = std::min(options.na, options.nc);
  oe.nf.assign(static_cast<std::size_t>(m), nf);
  oe.max_iterations = options.max_iterations;
  oe.steiglitz_mcbride_iterations = options.steiglitz_mcbride_iterations;
  oe.remove_means = false;
  const PemResult fit = pem(records_as_data(records, model.Ts), oe);
  if (fit.status == PemResult::Status::failed) return false;
  const Eigen::VectorXd& f = fit.model.F.front();
  model.A = Eigen::VectorXd::Zero(options.na + 1);
  model.A.head(f.size()) = f;
  model.C = Eigen::VectorXd::Zero(options.nc + 1);
  model.C.head(f.size()) = f;
  model.B = fit.model.B;
  return true;
}

bool armax_subspace_start(PolynomialModel& model, const std::vector<ScaledRecord>& records, const PemOptions& options) {
  N4sidOptions so;
  so.max_order = std::min(options.na, detail::kHorizonNominalMaxOrder);
  so.remove_means = false;
  // MOESP weighting: on the band-limited Par2 log its model is far closer to
  // the truth than the N4SID weighting's (bench/README.md: in-band fit 99.05 %
  // against 88.4 %), and the ARMAX iterations from it end in a better minimum.
  so.weighting = SubspaceWeighting::moesp;
  N4sidResult fit;
  try {
    fit = n4sid(records_as_data(records, model.Ts), so);
  } catch (const std::exception&) {
    return false;
  }
  const StateSpace& ss = fit.model;
  if (!ss.A.allFinite() || !ss.B.allFinite()) return false;
  const Eigen::VectorXd a = characteristic_polynomial(ss.A);
  model.A = resized(a, options.na + 1);
  const Eigen::VectorXd c = fit.K.size() > 0 ? characteristic_polynomial(ss.A - fit.K * ss.C) : a;
  model.C = reflect_into_unit_circle(resized(c, options.nc + 1));
  for (Eigen::Index i = 0; i < model.inputs(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (model.nb(i) == 0) continue;
    const Eigen::VectorXd numerator = characteristic_polynomial(ss.A - ss.B.col(i) * ss.C) + (ss.D(0, i) - 1.0) * a;
    model.B[k] = resized(numerator.tail(std::max<Eigen::Index>(0, numerator.size() - model.nk[k])), model.nb(i));
  }
  return model.A.allFinite() && model.C.allFinite();
}

}  // namespace sysid::detail::pem_impl
