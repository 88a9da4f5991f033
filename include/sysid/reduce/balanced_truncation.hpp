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

/// Purpose: balanced truncation / balanced singular perturbation of `sys`, see the
/// file comment. Returns the reduced model and diagnostics (HSV, kept order, ratio,
/// bound, measured error, warnings).
/// Example: `BalancedTruncationOptions o; o.order = 30; auto r = balanced_truncation(model, o);`
ReductionResult balanced_truncation(const StateSpace& sys, const BalancedTruncationOptions& options);

}  // namespace sysid
