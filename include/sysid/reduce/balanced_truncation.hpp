#pragma once
/// @file
/// Purpose: reduce a model to a lower order with a known error bound, by balanced
/// truncation or balanced singular perturbation of its stable part (the unstable
/// part, if any, is kept whole).
///
/// Method:
///  1. A balanced by a power-of-two diagonal similarity; G = G_s + G_u split by the
///     ordered Schur form and a Sylvester equation (hankel_singular_values.hpp).
///  2. Square-root method (A. J. Laub, M. T. Heath, C. C. Paige, R. C. Ward,
///     "Computation of system balancing transformations and other applications of
///     simultaneous diagonalization algorithms", IEEE TAC 32(2):115-122, 1987;
///     M. S. Tombs, I. Postlethwaite, "Truncated balanced realization of a stable
///     non-minimal state-space system", Int. J. Control 46(4):1319-1330, 1987):
///     Gramian factors Wc = Lc Lc^T, Wo = Lo Lo^T (Hammarling, gramians.hpp), SVD
///     Lo^T Lc = U Sigma V^T; the HSV are diag(Sigma). For k kept directions
///       T_r = Lc V_k Sigma_k^-1/2,   T_l = Sigma_k^-1/2 U_k^T Lo^T   (T_l T_r = I),
///     and (T_l A T_r, T_l B, C T_r, D) is the balanced realisation truncated to k.
///  3. truncation: k = r. singular_perturbation: k = the numerical minimal order
///     (HSV > n eps sigma_1), then the balanced (A, B, C, D) is partitioned r / k-r and
///     the fast states are set to steady state (Y. Liu, B. D. O. Anderson, "Singular
///     perturbation approximation of balanced systems", Int. J. Control
///     50(4):1379-1405, 1989):
///       continuous: A_r = A11 - A12 A22^-1 A21,   B_r = B1 - A12 A22^-1 B2,
///                   C_r = C1 - C2 A22^-1 A21,     D_r = D - C2 A22^-1 B2;
///       discrete:   the same with -A22^-1 replaced by (I - A22)^-1:
///                   A_r = A11 + A12 (I - A22)^-1 A21, ..., D_r = D + C2 (I - A22)^-1 B2,
///     which matches G at s = 0 (z = 1) exactly: the DC gain is kept.
///  4. Both satisfy sigma_{r+1} <= ||G - G_r||_inf <= 2 sum_{i>r} sigma_i (Enns 1984,
///     Glover 1984; Liu & Anderson 1989 for the singular perturbation, both time
///     domains; SLICOT AB09AD/AB09BD). The error is also measured on a frequency grid
///     (reduction_error.hpp) unless `measure_error` is false.
///
/// Order choice (first that applies): `order` >= 0 (total order, unstable states
/// included); else the smallest order whose `max_error_ratio` (sum of discarded HSV /
/// sum of all HSV) is met; else the smallest whose bound 2 sum(discarded HSV) <=
/// `max_hinf_bound`. The order never exceeds the numerical minimal order (directions
/// with HSV <= n eps sigma_1 are unobservable or uncontrollable to working precision;
/// keeping them would divide by rounding noise).
///
/// Preconditions: a valid StateSpace; exactly one order criterion given
/// (order >= unstable states, 0 <= max_error_ratio < 1, or max_hinf_bound > 0).
/// Violations throw std::invalid_argument.
/// Numerical aspects: O(n^3) (Schur ~25 n^3, SVD ~ 20 n^3 flops) plus the error grid,
/// O(n^2 m) per point. The square-root method never inverts an ill-conditioned
/// Gramian; it divides by sigma_k^1/2 only, so keeping tiny HSV is avoided above.
#include <sysid/core/state_space.hpp>
#include <sysid/reduce/gramians.hpp>
#include <sysid/reduce/hankel_singular_values.hpp>
#include <sysid/reduce/reduction_error.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

namespace sysid {

enum class BalancedMethod { truncation, singular_perturbation };

struct BalancedTruncationOptions {
  /// Total order of the reduced model (unstable states included); -1 = choose by
  /// max_error_ratio or max_hinf_bound.
  Eigen::Index order = -1;
  /// If order < 0 and > 0: smallest order with (sum all HSV - sum kept HSV) / sum all HSV <= this.
  double max_error_ratio = 0.0;
  /// If order < 0 and max_error_ratio == 0: smallest order with 2 sum(discarded HSV) <= this.
  double max_hinf_bound = 0.0;
  BalancedMethod method = BalancedMethod::truncation;
  double stability_tolerance = 1e-8;  ///< see HankelSingularValuesOptions
  bool measure_error = true;          ///< measure ||G - G_r||_inf on the grid (reduction_error.hpp)
  ErrorGridOptions grid;              ///< the grid for that measurement
  /// Warn when the cut falls between sigma_r and sigma_{r+1} with
  /// (sigma_r - sigma_{r+1}) / sigma_r below this: a near-equal pair (typically the
  /// two states of one lightly damped mode) is split, and the kept half is poorly
  /// determined.
  double pair_gap_warning = 0.02;
};

namespace detail {

/// Block-diagonal sum of two models with the same Ts, inputs and outputs.
inline StateSpace parallel_sum(const StateSpace& a, const StateSpace& b) {
  const Eigen::Index na = a.order(), nb = b.order();
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(na + nb, na + nb), B(na + nb, a.inputs()), C(a.outputs(), na + nb);
  A.topLeftCorner(na, na) = a.A;
  A.bottomRightCorner(nb, nb) = b.A;
  B << a.B, b.B;
  C << a.C, b.C;
  StateSpace s(A, B, C, a.D + b.D, a.Ts);
  s.input_names = a.input_names;
  s.output_names = a.output_names;
  return s;
}

}  // namespace detail

/// Purpose: balanced truncation / balanced singular perturbation of `sys`, see the
/// file comment. Returns the reduced model and diagnostics (HSV, kept order, ratio,
/// bound, measured error, warnings).
/// Example: `BalancedTruncationOptions o; o.order = 30; auto r = balanced_truncation(model, o);`
inline ReductionResult balanced_truncation(const StateSpace& sys, const BalancedTruncationOptions& options) {
  sys.validate();
  if (options.order < 0 && !(options.max_error_ratio > 0.0) && !(options.max_hinf_bound > 0.0))
    throw std::invalid_argument("balanced_truncation: need order >= 0, max_error_ratio > 0 or max_hinf_bound > 0");
  if (options.order < 0 && options.max_error_ratio > 0.0 && !(options.max_error_ratio < 1.0))
    throw std::invalid_argument("balanced_truncation: need max_error_ratio < 1");
  ReductionResult res;
  res.method = options.method == BalancedMethod::truncation ? "balanced truncation" : "singular perturbation";
  res.original_order = sys.order();
  detail::ComplexSchurForm schur;
  const StabilitySplit split =
      detail::stable_unstable_split(detail::balanced_realisation(sys), options.stability_tolerance, schur);
  const Eigen::Index nu = split.unstable.order(), ns = split.stable.order();
  res.unstable_states = nu;
  if (options.order >= 0 && options.order < nu)
    throw std::invalid_argument("balanced_truncation: need order >= unstable states (" + std::to_string(options.order) +
                                " < " + std::to_string(nu) + ")");
  if (split.decoupling_norm > 1e8)
    res.warnings.push_back("stable and unstable poles are poorly separated (||X|| = " +
                           std::to_string(split.decoupling_norm) + ")");

  StateSpace reduced_stable = split.stable;
  if (ns > 0) {
    const detail::SquareRootBalancing srb = detail::square_root_balancing(split.stable, schur, true);
    const Eigen::VectorXd& hsv = srb.hsv;
    res.hsv = hsv;
    // tail(i) = sum_{j >= i} sigma_j, summed from the smallest so small tails are exact.
    Eigen::VectorXd tail(ns + 1);
    tail(ns) = 0.0;
    for (Eigen::Index i = ns - 1; i >= 0; --i) tail(i) = tail(i + 1) + hsv(i);
    const double total = tail(0);
    const double eps = std::numeric_limits<double>::epsilon();
    Eigen::Index n_min = 0;
    while (n_min < ns && hsv(n_min) > static_cast<double>(ns) * eps * hsv(0)) ++n_min;

    Eigen::Index r = 0;
    if (options.order >= 0) {
      r = std::min<Eigen::Index>(options.order - nu, ns);
    } else if (options.max_error_ratio > 0.0) {
      while (r < ns && tail(r) > options.max_error_ratio * total) ++r;
    } else {
      while (r < ns && 2.0 * tail(r) > options.max_hinf_bound) ++r;
    }
    if (r > n_min) {
      res.warnings.push_back("order reduced from " + std::to_string(r + nu) + " to " + std::to_string(n_min + nu) +
                             ": the remaining Hankel singular values are at rounding level (non-minimal model)");
      r = n_min;
    }
    if (r > 0 && r < ns && hsv(r - 1) > 0.0 && (hsv(r - 1) - hsv(r)) / hsv(r - 1) < options.pair_gap_warning) {
      char buf[256];
      std::snprintf(buf, sizeof buf,
                    "the cut splits near-equal Hankel singular values sigma_%ld = %.6g and sigma_%ld = %.6g "
                    "(probably the two states of one lightly damped mode); consider order %ld or %ld",
                    static_cast<long>(r), hsv(r - 1), static_cast<long>(r + 1), hsv(r), static_cast<long>(r - 1 + nu),
                    static_cast<long>(r + 1 + nu));
      res.warnings.emplace_back(buf);
    }
    res.error_ratio = total > 0.0 ? tail(r) / total : 0.0;
    res.hinf_bound = 2.0 * tail(r);

    const bool spa = options.method == BalancedMethod::singular_perturbation;
    const Eigen::Index k = spa ? n_min : r;
    const Eigen::VectorXd s_isqrt = hsv.head(k).cwiseSqrt().cwiseInverse();
    const Eigen::MatrixXd Tr = srb.Lc * srb.V.leftCols(k) * s_isqrt.asDiagonal();
    const Eigen::MatrixXd Tl = s_isqrt.asDiagonal() * srb.U.leftCols(k).transpose() * srb.Lo.transpose();
    const StateSpace& g = split.stable;
    Eigen::MatrixXd Ab = Tl * g.A * Tr, Bb = Tl * g.B, Cb = g.C * Tr, Db = g.D;
    if (spa && r < k) {
      const Eigen::Index q = k - r;
      // Discrete: x2 = (I - A22)^-1 (A21 x1 + B2 u); continuous: x2 = -A22^-1 (A21 x1 + B2 u).
      Eigen::MatrixXd M = -Ab.bottomRightCorner(q, q);
      if (g.is_discrete()) M.diagonal().array() += 1.0;
      const Eigen::PartialPivLU<Eigen::MatrixXd> lu(M);
      Eigen::MatrixXd rhs(q, r + g.inputs());
      rhs << Ab.bottomLeftCorner(q, r), Bb.bottomRows(q);
      const Eigen::MatrixXd Y = lu.solve(rhs);  // [X21 XB]: x2 = X21 x1 + XB u
      if (!Y.allFinite()) throw NumericalError("balanced_truncation: singular perturbation system is singular");
      const Eigen::MatrixXd A11 = Ab.topLeftCorner(r, r) + Ab.topRightCorner(r, q) * Y.leftCols(r);
      const Eigen::MatrixXd B1 = Bb.topRows(r) + Ab.topRightCorner(r, q) * Y.rightCols(g.inputs());
      const Eigen::MatrixXd C1 = Cb.leftCols(r) + Cb.rightCols(q) * Y.leftCols(r);
      const Eigen::MatrixXd D1 = Db + Cb.rightCols(q) * Y.rightCols(g.inputs());
      Ab = A11;
      Bb = B1;
      Cb = C1;
      Db = D1;
    }
    reduced_stable = StateSpace(Ab, Bb, Cb, Db, g.Ts);
    reduced_stable.input_names = sys.input_names;
    reduced_stable.output_names = sys.output_names;
    if (options.measure_error) {
      // G - G_r = G_s - G_sr: the unstable part cancels exactly, so measure on the stable parts.
      const HinfErrorEstimate e = reduction_error(split.stable, reduced_stable, options.grid);
      res.hinf_error = e.value;
      res.hinf_error_freq_hz = e.freq_hz;
      res.dc_error = e.dc;
      res.grid_points = e.grid_points;
    }
  } else {
    res.error_ratio = 0.0;
    res.hinf_bound = 0.0;
    if (options.measure_error) {
      res.hinf_error = 0.0;
      res.dc_error = 0.0;
    }
  }
  res.model = nu > 0 ? detail::parallel_sum(reduced_stable, split.unstable) : reduced_stable;
  res.model.input_names = sys.input_names;
  res.model.output_names = sys.output_names;
  res.order = res.model.order();
  return res;
}

}  // namespace sysid
