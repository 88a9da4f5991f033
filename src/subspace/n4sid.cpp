// Implementation of subspace/n4sid.hpp (the method and its references are in the header).
// Compiled once into libsysid: the Eigen decompositions below are heavy to instantiate.
#include <sysid/subspace/n4sid.hpp>
#include <sysid/core/identification_warnings.hpp>

#include <Eigen/Dense>
#include <sysid/core/discrete_riccati.hpp>
#include <sysid/core/errors.hpp>
#include <sysid/core/format_number.hpp>
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/interconnect.hpp>
#include <sysid/core/io_data.hpp>
#include <sysid/core/parallel_for.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/core/state_space.hpp>
#include <sysid/hankel/block_hankel.hpp>
#include <sysid/signal/butterworth.hpp>
#include <sysid/signal/resample.hpp>
#include <sysid/signal/sos_filter.hpp>
#include <sysid/spectral/excited_band.hpp>
#include <sysid/spectral/welch.hpp>
#include <sysid/subspace/bdx_least_squares.hpp>
#include <sysid/subspace/pole_refinement.hpp>
#include <sysid/subspace/innovation_model.hpp>
#include <sysid/validate/fit.hpp>

#include <cmath>
#include <complex>
#include <iomanip>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace sysid {

namespace detail {

/// Orthonormal basis (columns) of the row space of `rows` (coefficient rows of L).
inline Eigen::MatrixXd row_space_basis(const Eigen::MatrixXd& rows, double rel_tol) {
  if (rows.rows() == 0) return Eigen::MatrixXd(rows.cols(), 0);
  Eigen::BDCSVD<Eigen::MatrixXd> svd(rows.transpose(), Eigen::ComputeThinU);
  const Eigen::VectorXd& s = svd.singularValues();
  Eigen::Index rank = 0;
  while (rank < s.size() && s(rank) > rel_tol * s(0)) ++rank;
  return svd.matrixU().leftCols(rank);
}

/// Oblique projection of future outputs along future inputs onto the past, in
/// coefficient space (VODM eq. 1.7 with M = W_p Pi_{U_f}^perp):
///   O = Y_f M^+ W_p,   O Pi_{U_f}^perp = Y_f M^+ M.
///
/// O multiplies the regression coefficients Y_f M^+ by W_p, not by M, so a
/// direction of the past that lies almost inside the span of the future inputs
/// (small principal angle theta between row(W_p) and row(U_f)) gets its noise
/// amplified by 1 / sin(theta). Band-limited inputs (a chirp or multisine that
/// leaves part of the Nyquist band empty) produce such directions: past and
/// future inputs are then nearly predictable from each other. This is the
/// ill-conditioning analysed by A. Chiuso & G. Picci, "On the ill-conditioning
/// of subspace identification with inputs", Automatica 40 (2004) 575-589.
/// Here the rows of W_p are orthonormalised (W_p = T W, W W^T = I, which
/// leaves O unchanged), the singular values of W Pi_{U_f}^perp are the sines of
/// those principal angles, and directions with sin(theta) <= min_sine are left
/// out of O: their effect cannot be told apart from that of the future inputs.
/// The amplification of noise into O is then at most 1 / min_sine.
/// O Pi_{U_f}^perp needs no such care: Y_f M^+ M is an orthogonal projection,
/// onto the row space of M = T (W Pi_{U_f}^perp), i.e. that of W Pi_{U_f}^perp,
/// spanned by the right singular vectors of the sines above rel_tol (relative
/// to the largest): the same SVD serves both (M^+ M = V_r V_r^T).
struct ObliqueProjection {
  Eigen::MatrixXd o;          ///< O_i
  Eigen::MatrixXd o_perp;     ///< O_i Pi_{U_f}^perp
  Eigen::MatrixXd yf_perp;    ///< Y_f Pi_{U_f}^perp (for the CVA weight)
  double min_sine = 1;        ///< smallest sin(principal angle) between past data and future inputs
  int dropped_directions = 0;  ///< past directions left out of O (sin(theta) <= min_sine option)
};

inline ObliqueProjection oblique_projection(const Eigen::MatrixXd& yf, const Eigen::MatrixXd& uf, const Eigen::MatrixXd& wp,
                                            double rel_tol, double min_sine) {
  const Eigen::MatrixXd vu = row_space_basis(uf, rel_tol);
  auto perp = [&vu](const Eigen::MatrixXd& x) -> Eigen::MatrixXd { return x - (x * vu) * vu.transpose(); };
  ObliqueProjection p;
  p.yf_perp = perp(yf);
  const Eigen::MatrixXd w = row_space_basis(wp, rel_tol).transpose();
  Eigen::BDCSVD<Eigen::MatrixXd> svd(perp(w), Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd& sines = svd.singularValues();
  Eigen::Index rank = 0;
  while (rank < sines.size() && sines(rank) > rel_tol * sines(0)) ++rank;
  const auto v_r = svd.matrixV().leftCols(rank);
  p.o_perp = (yf * v_r) * v_r.transpose();
  Eigen::VectorXd inv = Eigen::VectorXd::Zero(sines.size());
  for (Eigen::Index k = 0; k < sines.size(); ++k) {
    if (sines(k) > std::max(min_sine, rel_tol))
      inv(k) = 1.0 / sines(k);
    else
      ++p.dropped_directions;
  }
  p.min_sine = sines.size() > 0 ? sines.minCoeff() : 1.0;
  p.o = (yf * svd.matrixV()) * inv.asDiagonal() * (svd.matrixU().transpose() * w);
  return p;
}

inline Eigen::MatrixXd vstack(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  Eigen::MatrixXd s(a.rows() + b.rows(), a.cols());
  s << a, b;
  return s;
}

/// Symmetric square root and inverse square root of a positive semidefinite matrix.
inline std::pair<Eigen::MatrixXd, Eigen::MatrixXd> sqrt_and_inverse_sqrt(const Eigen::MatrixXd& g, double rel_tol) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (g + g.transpose()));
  const Eigen::VectorXd ev = eig.eigenvalues().cwiseMax(0.0);
  const double top = ev.maxCoeff();
  Eigen::VectorXd root = ev.cwiseSqrt(), inv_root(ev.size());
  for (Eigen::Index k = 0; k < ev.size(); ++k) inv_root(k) = ev(k) > rel_tol * top ? 1.0 / root(k) : 0.0;
  const Eigen::MatrixXd& v = eig.eigenvectors();
  return {v * root.asDiagonal() * v.transpose(), v * inv_root.asDiagonal() * v.transpose()};
}

/// Largest singular value of the frequency response over [f0, f1] (grid of `points`).
inline double peak_gain(const StateSpace& sys, double f0, double f1, int points) {
  double peak = 0;
  for (const Eigen::MatrixXcd& g : frequency_response(sys, Eigen::VectorXd::LinSpaced(points, f0, f1)))
    peak = std::max(peak, Eigen::JacobiSVD<Eigen::MatrixXcd>(g).singularValues()(0));
  return peak;
}

}  // namespace detail

namespace detail {

/// Steps 1-5 on mean-free, unit-RMS data: order, A, C, and (from the projections)
/// B, D and the residual covariance.
struct SubspaceCore {
  Eigen::MatrixXd A, B, C, D, covariance;
  Eigen::VectorXd singular_values, canonical_correlations;
  int order = 0, horizon = 0;
  std::string order_rule;
  std::string order_warning;  ///< set when the order rule had to fall back (select_order_when_svc_finds_none)
  HankelRoute route_used = HankelRoute::qr;
  double gram_condition_estimate = 0, observability_condition = 0, past_future_min_sine = 1;
  int oblique_dropped_directions = 0;
  std::vector<std::string> warnings;
  StabilizationDiagram stabilization;
  std::string horizon_rule;
};

/// What the automatic order choice searches and the dimensions of its statistics.
struct OrderSearch {
  int top = 0;                     ///< largest order searched (horizon x outputs - 1, or max_order)
  Eigen::Index columns = 0;        ///< Hankel columns (SVC's N)
  Eigen::Index test_samples = 0;   ///< the columns less the future-input rows projected out
  Eigen::Index future_dims = 0;    ///< future output rows (i l)
  Eigen::Index past_dims = 0;      ///< past rows kept in the oblique projection
  Eigen::Index outputs = 0, inputs = 0;
  double rank_tolerance = 0;

  /// The gap rule's largest order: both singular values of a gap above the rank
  /// tolerance (a drop into the numerical null space is not a model order).
  int gap_top(const Eigen::VectorXd& sv) const {
    int nonzero = 0;
    while (nonzero < sv.size() && sv(nonzero) > rank_tolerance * sv(0)) ++nonzero;
    return std::max(1, std::min(top, nonzero - 1));
  }
  bool test_possible() const { return test_samples > future_dims + past_dims && future_dims >= 1 && past_dims >= 1; }
};

/// The order by `rule` (subspace/order_selection.hpp). An order of 0 from SVC
/// (alone or in the automatic rule) is left to select_order_when_svc_finds_none;
/// from the test it means no dynamics (NumericalError).
inline OrderChoice choose_subspace_order(const SubspaceCore& res, OrderRule rule, const OrderSearch& s) {
  const auto& cc = res.canonical_correlations;
  switch (rule) {
    case OrderRule::gap: return choose_order_by_gap(res.singular_values, s.gap_top(res.singular_values));
    case OrderRule::test: {
      if (!s.test_possible())
        throw std::invalid_argument("n4sid: the canonical-correlation order test needs more Hankel columns (" +
                                    std::to_string(s.test_samples) + ") than past and future dimensions (" +
                                    std::to_string(s.future_dims + s.past_dims) +
                                    "); use --order-rule svc or a shorter --horizon");
      OrderChoice test = choose_order_by_correlation_test(cc, s.top, s.test_samples, s.future_dims, s.past_dims);
      if (test.order < 1)
        throw NumericalError("n4sid: no dynamics to identify: no canonical correlation between past and future stands above "
                             "the noise level (" + test.rule + "); give an order with --order N");
      return test;
    }
    case OrderRule::svc: return choose_order_by_svc(cc, s.top, s.columns, s.outputs, s.inputs);
    case OrderRule::automatic: break;
    case OrderRule::stabilization:
      throw std::invalid_argument("n4sid: the stabilization order rule reads the diagram, not the singular values");
  }
  OrderChoice svc = choose_order_by_svc(cc, s.top, s.columns, s.outputs, s.inputs);
  if (!s.test_possible()) return svc;
  OrderChoice test = choose_order_by_correlation_test(cc, s.top, s.test_samples, s.future_dims, s.past_dims);
  if (test.order <= svc.order || !svc_is_swamped(test.order, s.columns, s.outputs, s.inputs)) return svc;
  std::ostringstream why;
  why << std::setprecision(3) << "; Bauer's SVC (n = " << svc.order << ") is swamped: its penalty for " << test.order
      << " orders, " << svc_penalty_per_order(s.columns, s.outputs, s.inputs) * test.order
      << ", exceeds half the largest possible squared correlation";
  test.rule += why.str();
  return test;
}

/// SVC chose order 0. If the canonical correlations are significant (the past
/// predicts the future), SVC's penalty is what removed every order, not the
/// data: the largest singular-value gap chooses instead, with a warning. If
/// they are not, there are no dynamics to identify (NumericalError).
inline void select_order_when_svc_finds_none(SubspaceCore& res, const OrderSearch& s) {
  const Eigen::Index columns = s.columns, l = s.outputs, m = s.inputs;
  const CanonicalCorrelationTest test = bartlett_zero_correlation_test(
      res.canonical_correlations, std::max<Eigen::Index>(s.test_samples, 1), s.future_dims, std::max<Eigen::Index>(s.past_dims, 1));
  std::ostringstream why;
  why << std::setprecision(4) << "Bauer's SVC chose order 0 (its penalty " << svc_penalty_per_order(columns, l, m)
      << " per order, from " << columns << " Hankel columns, " << l << " output(s) and " << m
      << " input(s), exceeds every drop of the squared canonical correlations " << res.canonical_correlations(0);
  if (res.canonical_correlations.size() > 1) why << ", " << res.canonical_correlations(1);
  why << ", ...)";
  if (!test.valid || test.p_value > 0.01) {
    why << " and ";
    if (test.valid) why << "Bartlett's test finds no significant correlation between past and future (p = " << test.p_value << ")";
    else why << "too few samples for Bartlett's test of past-future correlation";
    throw NumericalError("n4sid: no dynamics to identify: " + why.str() + "; give an order with --order N");
  }
  const OrderChoice gap = choose_order_by_gap(res.singular_values, s.gap_top(res.singular_values));
  why << ", yet the correlations are significant (Bartlett's test p = " << test.p_value << ")";
  res.order = gap.order;
  res.order_rule = gap.rule + "; Bauer's SVC chose 0, see the warning";
  res.order_warning = "n4sid: " + why.str() + ": the order comes from the " + gap.rule +
                      "; compare orders on held-out data with --order LO:HI";
}

/// `low_passed`: the data were low-passed for decimation (the top of their band
/// is empty), so the block-Hankel compression starts at its double-double Gram
/// matrix (BlockHankelOptions::double_gram_first).
/// The horizon subspace_core uses when options.horizon is 0 (before the
/// slowest-mode rule of n4sid's identify step): sized for the order, or for a
/// stabilisation diagram, and shortened to what the record holds.
inline int default_horizon(const N4sidOptions& options, const IoData& data) {
  const Eigen::Index l = data.outputs();
  int horizon = automatic_horizon(options.order, options.max_order, l);
  if (options.stabilization_order_hi > 0 || options.order_rule == OrderRule::stabilization)
    horizon = std::max({horizon, automatic_horizon(0, options.stabilization_order_hi, l), kStabilizationMinHorizon});
  return record_limited_horizon(horizon, data);
}

inline SubspaceCore subspace_core(const IoData& data, const N4sidOptions& options, bool low_passed) {
  const Eigen::Index m = data.inputs(), l = data.outputs();
  SubspaceCore res;
  // Horizon.
  const int n_max = options.order > 0 ? options.order : options.max_order;
  const int horizon = options.horizon > 0 ? options.horizon : default_horizon(options, data);
  if (horizon < 2) throw std::invalid_argument("n4sid: need horizon >= 2");
  // A user-given order must fit under the horizon; an automatic choice is capped by it.
  if (options.order > 0 && static_cast<Eigen::Index>(horizon) * l <= n_max)
    throw std::invalid_argument("n4sid: need horizon * outputs > order (" + std::to_string(horizon) + " * " + std::to_string(l) +
                                " <= " + std::to_string(n_max) + "); increase --horizon");
  res.horizon = horizon;
  const Eigen::Index i = horizon;

  BlockHankelOptions ho;
  ho.horizon = horizon;
  ho.route = options.route;
  ho.double_gram_first = !low_passed;
  const BlockHankelCompression hc = compress_block_hankel(data, ho);
  res.route_used = hc.route_used;
  res.gram_condition_estimate = hc.gram_condition_estimate;
  res.warnings.insert(res.warnings.end(), hc.warnings.begin(), hc.warnings.end());
  const HankelLayout& lay = hc.layout;
  const double tol = options.rank_tolerance;

  // Step 2: oblique projections O_i and O_{i-1} (independent: one per core;
  // O_{i-1} is used in step 5).
  const Eigen::MatrixXd yf = hc.l_rows(lay.y_rows(i, 2 * i - 1));
  const Eigen::MatrixXd uf = hc.l_rows(lay.u_rows(i, 2 * i - 1));
  const Eigen::MatrixXd wp = detail::vstack(hc.l_rows(lay.u_rows(0, i - 1)), hc.l_rows(lay.y_rows(0, i - 1)));
  const Eigen::MatrixXd yf1 = hc.l_rows(lay.y_rows(i + 1, 2 * i - 1));
  const Eigen::MatrixXd uf1 = hc.l_rows(lay.u_rows(i + 1, 2 * i - 1));
  const Eigen::MatrixXd wp1 = detail::vstack(hc.l_rows(lay.u_rows(0, i)), hc.l_rows(lay.y_rows(0, i)));
  detail::ObliqueProjection oi, oi1;
  parallel_invoke([&] { oi = detail::oblique_projection(yf, uf, wp, tol, options.oblique_min_sine); },
                  [&] { oi1 = detail::oblique_projection(yf1, uf1, wp1, tol, options.oblique_min_sine); });
  res.past_future_min_sine = oi.min_sine;
  res.oblique_dropped_directions = oi.dropped_directions;

  // Step 3: weighted SVD. The CVA weight is always formed: its singular values
  // are the canonical correlations between the future outputs (with the future
  // inputs projected out) and the past, which the SVC order rule needs whatever
  // weighting determines Gamma_i.
  // For the N4SID and MOESP weightings the two SVDs are independent: one per core.
  Eigen::MatrixXd cva_root, w1_inv;
  Eigen::BDCSVD<Eigen::MatrixXd> svd;
  auto canonical_correlations = [&] {
    Eigen::MatrixXd cva_inv_root;
    std::tie(cva_root, cva_inv_root) = detail::sqrt_and_inverse_sqrt(oi.yf_perp * oi.yf_perp.transpose(), tol);
    const Eigen::MatrixXd cva_weighted = cva_inv_root * oi.o_perp;
    if (options.weighting == SubspaceWeighting::cva) svd.compute(cva_weighted, Eigen::ComputeThinU);
    else res.canonical_correlations = Eigen::BDCSVD<Eigen::MatrixXd>(cva_weighted).singularValues();
  };
  if (options.weighting == SubspaceWeighting::cva) {
    canonical_correlations();
    w1_inv = cva_root;
    res.canonical_correlations = svd.singularValues();
  } else {
    parallel_invoke(canonical_correlations, [&] {
      svd.compute(options.weighting == SubspaceWeighting::n4sid ? oi.o : oi.o_perp, Eigen::ComputeThinU);
    });
  }
  res.singular_values = svd.singularValues();
  int top = static_cast<int>(i * l) - 1;
  if (options.max_order > 0) top = std::min(top, options.max_order);
  // Step 4 for order n: Gamma_i (first n left singular vectors, scaled), its
  // first block row C and A from its shift equation.
  const auto supported = [&](Eigen::Index n) {
    return n >= 1 && n < res.singular_values.size() && res.singular_values(n - 1) > tol * res.singular_values(0);
  };
  const auto observability = [&](Eigen::Index n) {
    const Eigen::VectorXd s1_root = res.singular_values.head(n).cwiseSqrt();
    Eigen::MatrixXd gamma = svd.matrixU().leftCols(n) * s1_root.asDiagonal();
    if (options.weighting == SubspaceWeighting::cva) gamma = w1_inv * gamma;
    return gamma;
  };
  const auto shift_solution = [&](const Eigen::MatrixXd& gamma) -> Eigen::MatrixXd {
    if (options.enforce_stability) {
      Eigen::MatrixXd shifted = Eigen::MatrixXd::Zero(i * l, gamma.cols());
      shifted.topRows((i - 1) * l) = gamma.bottomRows((i - 1) * l);
      return gamma.completeOrthogonalDecomposition().solve(shifted);
    }
    return gamma.topRows((i - 1) * l).completeOrthogonalDecomposition().solve(gamma.bottomRows((i - 1) * l));
  };
  // The stabilisation diagram: every order's poles from this one SVD.
  if (options.stabilization_order_hi > 0 || (options.order == 0 && options.order_rule == OrderRule::stabilization)) {
    const int lo = std::max(1, options.stabilization_order_lo);
    int hi = options.stabilization_order_hi > 0 ? options.stabilization_order_hi : top;
    if (hi > static_cast<int>(i * l) - 1)
      throw std::invalid_argument("n4sid: the stabilization diagram's highest order " + std::to_string(hi) +
                                  " needs horizon * outputs > " + std::to_string(hi) + " (horizon " + std::to_string(i) + ", " +
                                  std::to_string(l) + " output(s)); lower the highest order, or pass a longer --horizon "
                                  "(the record must hold 8 x horizon x channels samples)");
    while (hi > lo && !supported(hi)) --hi;
    std::vector<OrderPoles> orders;
    for (int n = lo; n <= hi; ++n) {
      const Eigen::MatrixXd gamma = observability(n);
      Eigen::EigenSolver<Eigen::MatrixXd> eig(shift_solution(gamma));
      OrderPoles op;
      op.order = n;
      op.poles = eig.eigenvalues();
      const Eigen::MatrixXcd vectors = eig.eigenvectors();  // built anew by every call: once
      op.shapes = gamma.topRows(l).cast<std::complex<double>>() * vectors;
      // Each pole's level: the singular values weighted by its eigenvector's
      // energy in the state coordinates (state j belongs to singular value j).
      const Eigen::MatrixXd energy = vectors.cwiseAbs2();
      op.levels = (res.singular_values.head(n).transpose() * energy).transpose().cwiseQuotient(
          energy.colwise().sum().transpose());
      orders.push_back(std::move(op));
    }
    res.stabilization = stabilization_diagram(orders, data.Ts, options.stabilization);
  }
  if (options.order > 0) {
    res.order = options.order;
    res.order_rule = "given by the user";
  } else if (options.order_rule == OrderRule::stabilization) {
    if (res.stabilization.chosen_order < 1)
      throw NumericalError("n4sid: " + res.stabilization.rule + "; choose another --order-rule or give --order N" +
                           (res.stabilization.noise_columns.empty() ? std::string()
                                                                    : " (--min-level-ratio 0 and --noise-shape-level 0 count "
                                                                      "the columns named as noise)"));
    res.order = res.stabilization.chosen_order;
    res.order_rule = res.stabilization.rule;
  } else {
    // The correlations are those left after projecting out the future inputs:
    // that regression uses uf.rows() of the columns' degrees of freedom.
    const OrderSearch search{top, hc.columns, hc.columns - uf.rows(), yf.rows(), wp.rows() - oi.dropped_directions, l, m, tol};
    const OrderChoice choice = choose_subspace_order(res, options.order_rule, search);
    res.order = choice.order;
    res.order_rule = choice.rule;
    if (res.order < 1) select_order_when_svc_finds_none(res, search);
  }
  const Eigen::Index n = res.order;
  if (!supported(n))
    throw NumericalError("n4sid: order " + std::to_string(n) +
                         " exceeds the rank of the projection (the data do not support it); choose a lower order");

  const Eigen::MatrixXd gamma = observability(n);
  {
    Eigen::JacobiSVD<Eigen::MatrixXd> gs(gamma);
    const auto& g = gs.singularValues();
    res.observability_condition = g(g.size() - 1) > 0 ? g(0) / g(g.size() - 1) : std::numeric_limits<double>::infinity();
  }
  const Eigen::MatrixXd C = gamma.topRows(l);
  const Eigen::MatrixXd gamma_up = gamma.topRows((i - 1) * l);
  const Eigen::MatrixXd A = shift_solution(gamma);

  // Step 5: states, B and D from the projections, noise covariances, Kalman gain.
  const auto gamma_cod = gamma.completeOrthogonalDecomposition();
  const Eigen::MatrixXd xi = gamma_cod.solve(oi.o);
  const Eigen::MatrixXd xi1 = gamma_up.completeOrthogonalDecomposition().solve(oi1.o);
  const Eigen::MatrixXd uii = hc.l_rows(lay.u_rows(i, i));
  const Eigen::MatrixXd yii = hc.l_rows(lay.y_rows(i, i));
  const Eigen::MatrixXd lhs = detail::vstack(xi1 - A * xi, yii - C * xi);
  // [B; D] = lhs * uii^+ (least squares over the coefficient columns), via QR of uii^T.
  const Eigen::MatrixXd bd = uii.transpose().colPivHouseholderQr().solve(lhs.transpose()).transpose();
  Eigen::MatrixXd B = bd.topRows(n), D = bd.bottomRows(l);
  const Eigen::MatrixXd rho = lhs - bd * uii;
  const Eigen::MatrixXd cov = rho * rho.transpose() / static_cast<double>(hc.columns);

  res.A = A;
  res.B = B;
  res.C = C;
  res.D = D;
  res.covariance = cov;
  return res;
}

/// Odd decimation factor for oversampled data (see N4sidOptions::decimation), 1 = none.
inline int decimation_factor(double fs, double f_high, int requested) {
  if (requested == 1) return 1;
  if (requested > 1) {
    if (requested % 2 == 0) throw std::invalid_argument("n4sid: need an odd decimation factor (real r-th roots of every pole)");
    return requested;
  }
  if (!(f_high > 0)) return 1;
  int r = static_cast<int>(std::floor(fs / (4.0 * f_high)));
  if (r % 2 == 0) --r;
  return r >= 3 ? r : 1;
}

/// The slowest-mode rule of N4sidOptions::horizon: the horizon whose past and
/// future windows (2 i samples at sample time Ts) span one period of the slowest
/// oscillatory mode of A (|damping| <= 0.3, stable or not: an unstable estimate
/// is often a slow mode the horizon could not see), within the record and
/// kSlowestModeMaxHankelRows; 0 when A has no such mode. `slowest_hz` gets its frequency.
inline int horizon_for_slowest_mode(const Eigen::MatrixXd& a, const IoData& data, double& slowest_hz) {
  slowest_hz = 0.0;
  if (a.size() == 0) return 0;
  const Eigen::VectorXcd z = a.eigenvalues();
  for (const auto p : z) {
    if (!(p.imag() > 0.0)) continue;
    const std::complex<double> s = std::log(p) / data.Ts;
    if (std::abs(s.real()) > 0.3 * std::abs(s)) continue;
    const double f = std::abs(s) / (2.0 * std::numbers::pi);
    if (slowest_hz == 0.0 || f < slowest_hz) slowest_hz = f;
  }
  if (slowest_hz == 0.0) return 0;
  const int wanted = static_cast<int>(std::ceil(0.5 / (slowest_hz * data.Ts)));
  const auto channels = static_cast<int>(data.inputs() + data.outputs());
  return record_limited_horizon(std::min(wanted, kSlowestModeMaxHankelRows / (2 * channels)), data);
}

/// Mean simulation fit (%) over the outputs of (A, C) with B, D and x0 fitted by
/// least squares on the simulation error (step 6), on the scaled data; -infinity
/// when the simulation diverges.
inline double mean_simulation_fit(const Eigen::MatrixXd& a, const Eigen::MatrixXd& c, const IoData& data,
                                  Eigen::Index bdx_max_samples) {
  constexpr double diverged = -std::numeric_limits<double>::infinity();
  BdxLeastSquaresOptions bo;
  bo.max_samples = bdx_max_samples;
  FitAccumulator fit(data.outputs());
  try {
    const BdxLeastSquaresResult bdx = bdx_least_squares(a, c, data, bo);
    const StateSpace model(a, bdx.B, c, bdx.D, data.Ts);
    for (std::size_t e = 0; e < data.experiments.size(); ++e) {
      const Experiment& ex = data.experiments[e];
      simulate_blockwise_modal(model, ex.u, bdx.x0[e], [&](Eigen::Index k0, const Eigen::Ref<Eigen::MatrixXd>& yb) {
        const auto y = ex.y.middleRows(k0, yb.rows());
        fit.add_residual(y, y - yb);
      });
    }
  } catch (const std::exception&) {
    return diverged;  // a regression or a simulation that breaks down has diverged
  }
  const Eigen::VectorXd f = fit.fit_percent();
  return f.allFinite() ? f.mean() : diverged;
}

/// V f(Lambda) V^-1 for a diagonalisable real A and a map f of its eigenvalues
/// that keeps conjugate pairs conjugate (so the result is real). NumericalError
/// naming `remedy` if A is defective (eigenvector matrix ill-conditioned).
template <class EigenvalueMap>
Eigen::MatrixXd map_eigenvalues(const Eigen::MatrixXd& a, EigenvalueMap f, const std::string& remedy) {
  Eigen::EigenSolver<Eigen::MatrixXd> eig(a);
  const Eigen::MatrixXcd v = eig.eigenvectors();
  Eigen::VectorXcd lambda = eig.eigenvalues();
  Eigen::JacobiSVD<Eigen::MatrixXcd> vs(v);
  const auto& sv = vs.singularValues();
  if (!(sv(sv.size() - 1) > 1e-10 * sv(0))) throw NumericalError("n4sid: the identified A is defective; " + remedy);
  for (Eigen::Index k = 0; k < lambda.size(); ++k) lambda(k) = f(lambda(k));
  const Eigen::MatrixXcd mapped = v * lambda.asDiagonal() * v.inverse();
  return mapped.real();
}

/// Principal real r-th root of A (r odd): the discrete poles at the original
/// rate, z = z_d^(1/r) for complex poles (same continuous-time s = log(z)/Ts),
/// the real root for real poles.
inline Eigen::MatrixXd principal_root(const Eigen::MatrixXd& a, int r) {
  return map_eigenvalues(
      a,
      [r](std::complex<double> z) {
        if (std::abs(z.imag()) <= 1e-14 * std::abs(z)) return std::complex<double>(std::copysign(std::pow(std::abs(z.real()), 1.0 / r), z.real()));
        return std::pow(z, 1.0 / r);  // principal branch, conjugates stay conjugate
      },
      "the decimated model cannot be mapped back: rerun with --decimation 1");
}

/// A with every pole on or outside the unit circle reflected to 1 / conj(z):
/// the same frequency, the mirrored damping (continuous s = log z / Ts goes to
/// -conj(s)). A pole exactly on the circle moves in to 1 - 1e-6 of it.
inline Eigen::MatrixXd reflect_unstable_poles(const Eigen::MatrixXd& a) {
  return map_eigenvalues(
      a,
      [](std::complex<double> z) {
        const double r = std::abs(z);
        if (r < 1.0) return z;
        return z / (r * std::max(r, 1.0 + 1e-6));
      },
      "pass --allow-unstable to keep the unstable estimate, or --enforce-stability");
}

}  // namespace detail

namespace {

/// Whether n4sid refines the poles of a model of this order (N4sidOptions::refine_poles).
bool will_refine_poles(const N4sidOptions& options, int order, const IoData& data) {
  if (options.refine_poles == PoleRefinementMode::never || order < 1) return false;
  if (options.refine_poles == PoleRefinementMode::always) return true;
  return options.horizon > 0 && refinement_cost(order, data, options.bdx_max_samples) <= kPoleRefinementBudget;
}

/// The pole refinement step on the scaled data at the original rate, from the
/// subspace model and `extra_starts` (the automatic horizon's, when the user gave
/// another): the simulation error has local minima, and which start reaches the
/// lower one depends on where the horizon left the weakly determined poles, so
/// the starts are raced (subspace/pole_refinement.hpp). core.A (and core.C when
/// another start won) replaced when that lowered the error.
void refine_subspace_poles(detail::SubspaceCore& core, std::vector<PoleRefinementStart> extra_starts, const IoData& data,
                           const N4sidOptions& options, N4sidResult& res) {
  if (!(core.A.eigenvalues().cwiseAbs().maxCoeff() < 1.0)) {
    res.refinement = "poles not refined: the model is unstable (kept by --allow-unstable)";
    return;
  }
  std::vector<PoleRefinementStart> starts{{core.A, core.C}};
  for (PoleRefinementStart& s : extra_starts) starts.push_back({detail::reflect_unstable_poles(s.A), std::move(s.C)});
  PoleRefinementOptions ro;
  ro.max_samples = options.bdx_max_samples;
  const PoleRefinementResult r = refine_poles(starts, data, ro);
  core.A = r.A;
  core.C = r.C;
  res.poles_refined = r.refined || r.start != 0;
  res.refinement_fit_before = r.initial_fit;
  res.refinement_fit_after = r.final_fit;
  const std::string start = r.start == 0 ? "the subspace poles at horizon " + std::to_string(core.horizon)
                                         : std::string("the subspace poles at the automatic horizon (the lower of the raced starts)");
  res.refinement = res.poles_refined ? "poles refined on the simulation error from " + start + " (" +
                                           std::to_string(r.iterations) + " iterations): estimation fit " +
                                           format_number(r.initial_fit, 4) + " -> " + format_number(r.final_fit, 4) + " %"
                                     : "poles kept from the subspace step (" + r.termination + ")";
}

}  // namespace

N4sidResult n4sid(IoData data, const N4sidOptions& options) {
  data.validate();
  const Eigen::Index m = data.inputs(), l = data.outputs();
  if (m < 1) throw std::invalid_argument("n4sid: need at least one input");
  if (options.order < 0) throw std::invalid_argument("n4sid: need order >= 0 (0 = automatic)");
  if (options.order == 0 && options.max_order < 0) throw std::invalid_argument("n4sid: need max_order >= 0 (0 = no cap)");

  N4sidResult res;
  res.weighting = options.weighting;
  res.input_offset = Eigen::VectorXd::Zero(m);
  res.output_offset = Eigen::VectorXd::Zero(l);
  if (options.remove_means) {
    const ChannelOffsets off = remove_means(data);
    res.input_offset = off.input;
    res.output_offset = off.output;
  }
  std::optional<SecondOrderSections> band_limit;
  if (options.band_limit_hz > 0) {
    if (options.band_limit_order < 1) throw std::invalid_argument("n4sid: need band_limit_order >= 1");
    band_limit = butterworth(options.band_limit_order, BandType::lowpass, options.band_limit_hz, 0.0, 1.0 / data.Ts);
    for (auto& e : data.experiments) {
      e.u = sos_filter(*band_limit, e.u);
      e.y = sos_filter(*band_limit, e.y);
    }
  }
  // Excitation check and unit-RMS scaling.
  const double total = static_cast<double>(data.total_samples());
  Eigen::VectorXd su = Eigen::VectorXd::Zero(m), sy = Eigen::VectorXd::Zero(l);
  for (const auto& e : data.experiments) {
    su += e.u.colwise().squaredNorm().transpose();
    sy += e.y.colwise().squaredNorm().transpose();
  }
  su = (su / total).cwiseSqrt();
  sy = (sy / total).cwiseSqrt();
  for (Eigen::Index q = 0; q < m; ++q)
    if (!(su(q) > options.constant_input_tolerance * std::max(1.0, std::abs(res.input_offset(q)))))
      throw DataError("input '" + data.input_name(q) + "' is constant: it does not excite the system");
  for (Eigen::Index r = 0; r < l; ++r)
    if (!(sy(r) > 0)) throw DataError("output '" + data.output_name(r) + "' is constant: nothing to identify");
  for (auto& e : data.experiments) {
    e.u = e.u * su.cwiseInverse().asDiagonal();
    e.y = e.y * sy.cwiseInverse().asDiagonal();
  }

  const double nyquist = 0.5 / data.Ts;
  // The excited band decides the grid; the model-free data checks need only
  // the data: one core each.
  double band_lo = 0, band_hi = 0;
  IoData decimated;
  ModelFreeDataWarnings data_checks;
  parallel_invoke(
      [&] {
        std::tie(band_lo, band_hi) = excited_band(data.experiments.front().u, 1.0 / data.Ts);
        res.decimation = detail::decimation_factor(1.0 / data.Ts, band_hi, options.decimation);
        // Zero-phase 8th-order Butterworth at 0.8 x the new Nyquist frequency on
        // inputs and outputs alike (their relation is unchanged), then every r-th sample.
        if (res.decimation > 1) decimated = decimate(data, res.decimation);
      },
      [&] { data_checks = model_free_data_warnings(data, "n4sid"); });
  res.excited_band_low_hz = band_lo;
  res.excited_band_high_hz = band_hi;
  detail::SubspaceCore core;
  // The order is chosen at a horizon sized for max_order; the model of that
  // order is then identified at the horizon sized for it (unless the user fixed one).
  auto identify = [](const IoData& d, bool low_passed, const N4sidOptions& options) {
    detail::SubspaceCore c = detail::subspace_core(d, options, low_passed);
    // With a stabilisation diagram the model comes from the diagram's compression.
    const bool diagram = options.stabilization_order_hi > 0 || options.order_rule == OrderRule::stabilization;
    if (options.order == 0 && options.horizon == 0 && !diagram &&
        detail::automatic_horizon(c.order, options.max_order, d.outputs()) != c.horizon) {
      N4sidOptions second = options;
      second.order = c.order;
      detail::SubspaceCore fixed = detail::subspace_core(d, second, low_passed);
      fixed.order_rule = c.order_rule + " at horizon " + std::to_string(c.horizon);
      fixed.singular_values = c.singular_values;
      fixed.canonical_correlations = c.canonical_correlations;
      fixed.order_warning = c.order_warning;
      c = std::move(fixed);
    }
    if (options.horizon > 0) {
      c.horizon_rule = "given by the user";
      return c;
    }
    c.horizon_rule = "automatic";
    if (diagram) return c;
    double slowest_hz = 0.0;
    const int spanning = detail::horizon_for_slowest_mode(c.A, d, slowest_hz);
    if (spanning > c.horizon) {
      N4sidOptions longer = options;
      longer.order = c.order;
      longer.horizon = spanning;
      detail::SubspaceCore spanned = detail::subspace_core(d, longer, low_passed);
      spanned.order_rule = c.order_rule;
      spanned.singular_values = c.singular_values;
      spanned.canonical_correlations = c.canonical_correlations;
      spanned.order_warning = c.order_warning;
      spanned.horizon_rule = "past and future span a period of the slowest mode, " + format_number(slowest_hz, 4) +
                             " Hz, seen at horizon " + std::to_string(c.horizon);
      c = std::move(spanned);
    }
    return c;
  };
  // The pole refinement (refine_subspace_poles): whether it runs, and its second
  // start, the subspace model of the automatic horizon for the same order. In
  // automatic mode it runs only for a horizon the user gave that differs from
  // the one the tool would choose (detail::default_horizon, lengthened to span
  // the slowest mode as identify does): the automatic path is left as it is.
  bool refine = false;
  std::vector<PoleRefinementStart> extra_starts;
  auto prepare_refinement = [&](const IoData& d, bool low_passed) {
    if (!will_refine_poles(options, core.order, data) || core.A.size() == 0) return;
    N4sidOptions automatic = options;  // this order at the automatic horizon, without a diagram
    automatic.horizon = 0;
    automatic.order = core.order;
    automatic.stabilization_order_lo = automatic.stabilization_order_hi = 0;
    if (automatic.order_rule == OrderRule::stabilization) automatic.order_rule = OrderRule::automatic;
    if (options.refine_poles == PoleRefinementMode::automatic) {
      double slowest_hz = 0.0;
      const int tool_horizon =
          std::max(detail::default_horizon(automatic, d), detail::horizon_for_slowest_mode(core.A, d, slowest_hz));
      if (tool_horizon == core.horizon) return;
    }
    refine = true;
    if (options.horizon == 0) return;  // the automatic horizon is the start already
    detail::SubspaceCore c = identify(d, low_passed, automatic);
    if (c.horizon != core.horizon && c.A.size() > 0) extra_starts.push_back({std::move(c.A), std::move(c.C)});
  };
  if (res.decimation > 1) {
    core = identify(decimated, true, options);
    prepare_refinement(decimated, true);
    decimated = IoData();  // the rest runs at the original rate: free the copy
    core.A = detail::principal_root(core.A, res.decimation);
    for (PoleRefinementStart& start : extra_starts) start.A = detail::principal_root(start.A, res.decimation);
    res.warnings.push_back("n4sid: the inputs excite only 0.." + format_number(band_hi) + " Hz of " + format_number(nyquist) +
                           " Hz: identified on a grid decimated by " + std::to_string(res.decimation) +
                           " (A mapped back by its principal root, B, D, x0 fitted at the original rate)");
  } else {
    core = identify(data, false, options);
    prepare_refinement(data, false);
  }
  // An unstable A from a stable plant's data is an estimation artefact (a
  // horizon or an order the data do not support): its poles are reflected into
  // the unit circle and B, D, x0 fitted to the reflected A below, unless the user
  // keeps it (a plant that is itself unstable) or asked for the stable shift.
  // Which of the two the data are: a growing record is fitted by the unstable
  // model only (the reflected one cannot follow the growth: tens of fit points
  // apart), while from a stationary record the two fit alike or the unstable
  // model's simulation diverges. So the unstable estimate is kept only when it
  // fits the estimation data by kUnstableFitMargin points better.
  if (!options.allow_unstable && !options.enforce_stability && core.A.size() > 0) {
    const double radius = core.A.eigenvalues().cwiseAbs().maxCoeff();
    if (radius >= 1.0) {
      const Eigen::MatrixXd reflected = detail::reflect_unstable_poles(core.A);
      const double fit_unstable = detail::mean_simulation_fit(core.A, core.C, data, options.bdx_max_samples);
      const double fit_reflected = detail::mean_simulation_fit(reflected, core.C, data, options.bdx_max_samples);
      constexpr double kUnstableFitMargin = 5.0;
      if (!(fit_unstable > fit_reflected + kUnstableFitMargin)) {
        core.A = reflected;
        res.reflected_spectral_radius = radius;
        res.warnings.push_back(
            "n4sid: the least-squares A was unstable (spectral radius " + format_number(radius, 6) +
            "): its unstable poles were reflected into the unit circle (z -> 1/conj(z): the same frequency, the damping's "
            "sign mirrored) and B, D, x0 fitted to the reflected A (estimation fit " +
            (std::isfinite(fit_unstable) ? format_number(fit_unstable, 4) + " %" : std::string("diverging")) + " -> " +
            format_number(fit_reflected, 4) + " %). From a stable plant's data this is a horizon or an order the data "
            "do not support: compare --horizon values or --order LO:HI on held-out data; --allow-unstable keeps the "
            "unstable estimate");
      } else {
        res.warnings.push_back("n4sid: the unstable estimate (spectral radius " + format_number(radius, 6) +
                               ") is kept: it fits the estimation data better than with its poles reflected (" +
                               format_number(fit_unstable, 4) + " % against " + format_number(fit_reflected, 4) +
                               " %): the record grows as an unstable plant's does");
      }
    }
  }
  if (refine) refine_subspace_poles(core, extra_starts, data, options, res);
  res.singular_values = core.singular_values;
  res.canonical_correlations = core.canonical_correlations;
  res.stabilization = std::move(core.stabilization);
  res.order = core.order;
  res.horizon = core.horizon;
  res.horizon_rule = core.horizon_rule;
  res.order_rule = core.order_rule;
  res.route_used = core.route_used;
  res.gram_condition_estimate = core.gram_condition_estimate;
  res.observability_condition = core.observability_condition;
  res.past_future_min_sine = core.past_future_min_sine;
  res.oblique_dropped_directions = core.oblique_dropped_directions;
  res.warnings.insert(res.warnings.end(), core.warnings.begin(), core.warnings.end());
  if (!core.order_warning.empty()) res.warnings.push_back(core.order_warning);
  for (auto& w : identification_data_warnings(data, 2 * res.order, "a state-space model of order " + std::to_string(res.order),
                                              "n4sid", std::move(data_checks)))
    res.warnings.push_back(std::move(w));
  const Eigen::Index n = res.order;
  const Eigen::MatrixXd& A = core.A;
  const Eigen::MatrixXd& C = core.C;
  Eigen::MatrixXd B = core.B, D = core.D;
  const Eigen::MatrixXd& cov = core.covariance;

  // The subspace step's covariances belong to its own A: with refined poles the
  // noise model comes from the residuals, as on a decimated grid.
  const bool noise_model_from_residuals = options.estimate_kalman_gain && (res.decimation > 1 || res.poles_refined);
  Eigen::MatrixXd K, innovation = cov.bottomRightCorner(l, l);
  if (options.estimate_kalman_gain && !noise_model_from_residuals) {
    const KalmanFilterResult kf =
        steady_state_kalman_filter(A, C, cov.topLeftCorner(n, n), cov.bottomRightCorner(l, l), cov.topRightCorner(n, l));
    res.kalman_iterations = kf.iterations;
    if (kf.status == KalmanFilterResult::Status::converged) {
      K = kf.K;
      innovation = kf.innovation_covariance;
    } else {
      res.warnings.push_back("n4sid: Kalman gain not computed: " + kf.message);
    }
  }

  // Step 6: B, D, x0 on the simulation error.
  std::vector<Eigen::VectorXd> x0(data.experiments.size(), Eigen::VectorXd::Zero(n));
  if (options.refine_bdx || res.poles_refined) {  // refined poles need their own B, D, x0
    BdxLeastSquaresOptions bo;
    bo.max_samples = options.bdx_max_samples;
    const BdxLeastSquaresResult bdx = bdx_least_squares(A, C, data, bo);
    B = bdx.B;
    D = bdx.D;
    x0 = bdx.x0;
    res.bdx_samples_used = bdx.samples_used;
    res.bdx_samples_without_initial_response = bdx.rows_without_initial_response;
    if (bdx.samples_used < data.total_samples())
      res.warnings.push_back("n4sid: B, D and x0 were fitted on the first " + std::to_string(options.bdx_max_samples) +
                             " samples of each experiment (bdx_max_samples)");
    if (bdx.condition > 1e10)
      res.warnings.push_back("n4sid: the B/D/x0 regression is ill-conditioned (condition " + format_number(bdx.condition, 3) +
                             " after column scaling); some input directions are poorly excited");
  }

  // Back to original units: u_s = u / su, y_s = y / sy. The model's checks
  // below need only A, B, C, D: they run beside the estimation fit.
  const Eigen::MatrixXd su_inv = su.cwiseInverse().asDiagonal();
  res.model = StateSpace(A, B * su_inv, sy.asDiagonal() * C, sy.asDiagonal() * D * su_inv, data.Ts);
  res.model.input_names = data.input_names;
  res.model.output_names = data.output_names;
  res.x0 = x0.front();
  if (band_limit) {
    // Filter at the inputs: one copy per input channel. The filtered data's x0
    // belongs to the unfiltered model states; the filter starts at rest.
    const StateSpace filter = sos_to_state_space(*band_limit);
    const StateSpace filters = block_diagonal(std::vector<StateSpace>(static_cast<std::size_t>(m), filter));
    StateSpace limited = series(filters, res.model);
    limited.input_names = res.model.input_names;
    limited.output_names = res.model.output_names;
    Eigen::VectorXd x0_all = Eigen::VectorXd::Zero(limited.order());
    x0_all.tail(res.model.order()) = res.x0;
    res.model = limited;
    res.x0 = x0_all;
    res.band_limited = true;
  }
  if (!A.allFinite() || !res.model.B.allFinite() || !res.model.D.allFinite())
    throw NumericalError("n4sid: the identified matrices contain NaN or Inf");

  // Fit on the estimation data (scaled units: fit % is scale-invariant). The
  // data are mean-free after scaling only when remove_means is on, so the
  // spread is accumulated about the overall mean; the simulation is consumed
  // block by block unless its residuals are needed for the noise model.
  // On a decimated grid the projections give K at the wrong rate: the noise
  // model comes from the residuals at the original rate instead
  // (subspace/innovation_model.hpp).
  std::vector<std::string> fit_warnings, model_warnings;
  auto fit_and_noise_model = [&] {
    std::vector<Eigen::MatrixXd> residuals;
    const StateSpace scaled(A, B, C, D, data.Ts);
    FitAccumulator fit(l);
    for (std::size_t e = 0; e < data.experiments.size(); ++e) {
      const Experiment& ex = data.experiments[e];
      if (noise_model_from_residuals) residuals.emplace_back(ex.samples(), l);
      // Block by block: without the noise model no copy of the record's outputs
      // is held (10^6 x 8 samples: 128 MB less).
      simulate_blockwise_modal(scaled, ex.u, x0[e], [&](Eigen::Index k0, const Eigen::Ref<Eigen::MatrixXd>& yb) {
        const auto y = ex.y.middleRows(k0, yb.rows());
        const Eigen::MatrixXd residual = y - yb;
        fit.add_residual(y, residual);
        if (noise_model_from_residuals) residuals.back().middleRows(k0, yb.rows()) = residual;
      });
    }
    res.fit_percent = fit.fit_percent();
    if (!noise_model_from_residuals) return;
    const InnovationModelResult nm = innovation_model(A, C, residuals);
    res.kalman_iterations = nm.iterations;
    innovation = nm.innovation_covariance;
    if (nm.status == InnovationModelResult::Status::converged)
      K = nm.K;
    else
      fit_warnings.push_back("n4sid: Kalman gain not computed: " + nm.message);
  };
  // Stability and band checks.
  auto check_model = [&] {
    model_warnings = unstable_model_warnings(res.model, "n4sid",
                                             "kept by --allow-unstable; --enforce-stability forces a stable A");
    const double lo = band_lo, hi = band_hi;
    if (hi < 0.8 * nyquist) {
      const double in_band = detail::peak_gain(res.model, std::max(lo, 0.0), hi, 200);
      const double out_band = detail::peak_gain(res.model, std::min(1.2 * hi, nyquist), nyquist, 200);
      res.out_of_band_gain_ratio = in_band > 0 ? out_band / in_band : 0.0;
      if (res.out_of_band_gain_ratio > 0.5) {
        std::ostringstream w;
        w.precision(3);
        w << "n4sid: the inputs excite only " << lo << ".." << hi << " Hz, but the model's gain above " << 1.2 * hi
          << " Hz reaches " << res.out_of_band_gain_ratio
          << " x its in-band peak: that gain is not determined by the data. Remedy (Par2 paper): band-limit the data and "
             "the model with a Butterworth low-pass (--band-limit)";
        model_warnings.push_back(w.str());
      }
    }
  };
  parallel_invoke(fit_and_noise_model, check_model);
  for (auto* list : {&fit_warnings, &model_warnings})
    for (auto& w : *list) res.warnings.push_back(std::move(w));

  if (K.size() > 0) {
    res.K = K * sy.cwiseInverse().asDiagonal();
    if (res.band_limited) {  // the filter states have no innovation input
      Eigen::MatrixXd k_all = Eigen::MatrixXd::Zero(res.model.order(), l);
      k_all.bottomRows(n) = res.K;
      res.K = k_all;
    }
  }
  res.noise_covariance = sy.asDiagonal() * innovation * sy.asDiagonal();
  return res;
}

}  // namespace sysid
