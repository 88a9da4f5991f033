#pragma once
/// @file
/// Purpose: controllability and observability Gramians of a stable linear system,
/// returned as square-root (Cholesky-like) factors, which is what balanced
/// truncation and the Hankel singular values need:
///
///   discrete (Ts > 0):   A Wc A^T - Wc + B B^T = 0,    A^T Wo A - Wo + C^T C = 0
///   continuous (Ts = 0): A Wc + Wc A^T + B B^T = 0,    A^T Wo + Wo A + C^T C = 0
///
/// with Wc = Lc Lc^T and Wo = Lo Lo^T, Lc and Lo real, n x n, lower triangular.
///
/// Method: Hammarling's method (S. J. Hammarling, "Numerical solution of the stable,
/// non-negative definite Lyapunov equation", IMA J. Numer. Anal. 2:303-323, 1982),
/// in its complex triangular form:
///  1. A = U T U^H with T upper triangular (complex Schur form), obtained from the
///     real Schur form (Eigen::RealSchur: Hessenberg reduction + Francis QR) by one
///     2x2 unitary rotation per 2x2 diagonal block (the first column of the rotation
///     is the block's eigenvector), which is cheaper than a complex QR iteration.
///  2. With B~ = U^H B the factor X = R R^H of T X + X T^H + B~ B~^H = 0 (or
///     T X T^H - X + B~ B~^H = 0) is computed column by column from the bottom
///     right: partition T = [T1 t; 0 tau], R = [R1 r; 0 rho], B~ = [B1; b]; then
///       continuous: rho = |b| / sqrt(-2 Re tau),
///                   (T1 + conj(tau) I) r = -(rho t + B1 b^H / rho),
///                   B1 <- B1 - r b / rho                  (Hammarling sec. 5),
///       discrete:   rho = |b| / sqrt(1 - |tau|^2),
///                   (conj(tau) T1 - I) r = -(conj(tau) rho t + B1 b^H / rho),
///                   v = T1 r + rho t,  q = b^H / |b|,
///                   B1 <- B1 (I - (1 - |tau|) q q^H) + c v q^H,
///                   c = -(conj(tau) / |tau|) sqrt(1 - |tau|^2)   (Hammarling sec. 6),
///     and the recursion continues on (T1, B1); the updated B1 satisfies
///     B1 B1^H = (the right-hand side of the leading block's equation), so the
///     factor never goes through the Gramian itself and stays accurate when the
///     Gramian is nearly singular (small Hankel singular values) or, for lightly
///     damped systems, very ill conditioned.
///  3. The observability Gramian uses the same Schur form: A^T = (U J)(J T^H J)(U J)^H
///     with J the reversal permutation, and J T^H J is upper triangular.
///  4. The complex factor L = U R has L L^H = W real, so the real n x 2n matrix
///     [Re L, Im L] is a real factor of W; a Householder QR of its transpose
///     compresses it to the n x n lower triangular factor returned.
///
/// Preconditions: A square (n x n), B with n rows (C with n columns), all poles
/// strictly stable (|z| < 1 discrete, Re s < 0 continuous): violations throw
/// std::invalid_argument. Use stable_unstable_split() (hankel_singular_values.hpp)
/// first for a model with unstable poles.
///
/// Numerical aspects: O(n^3): one real Schur decomposition (~25 n^3 flops) shared by
/// both Gramians, two triangular recursions of ~n^3/6 complex multiply-adds each,
/// two n x n complex products and two 2n x n QR compressions. Backward stable as
/// the Schur decomposition; the relative accuracy of each factor degrades only
/// with the separation of the spectrum from the stability boundary (1 - |z| or
/// -Re s), which is intrinsic to the Gramian.
///
/// References: Hammarling 1982 (above); SLICOT SB03OD/SB03OU documentation (the
/// real-arithmetic implementation of the same method).
#include <sysid/core/errors.hpp>
#include <sysid/core/state_space.hpp>

#include <Eigen/Dense>

namespace sysid {

/// Square-root factors of both Gramians: Wc = controllability * controllability^T,
/// Wo = observability * observability^T (each n x n, lower triangular).
struct GramianFactors {
  Eigen::MatrixXd controllability;  ///< Lc
  Eigen::MatrixXd observability;    ///< Lo
};

namespace detail {

/// The dense cores of controllability_gramian_factor / observability_gramian_factor
/// (compiled once in src/reduce/gramians.cpp; the templates only evaluate their arguments).
Eigen::MatrixXd controllability_gramian_factor_impl(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, bool discrete);
Eigen::MatrixXd observability_gramian_factor_impl(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C, bool discrete);

}  // namespace detail

/// Purpose: factor Lc (n x n, lower triangular) of the controllability Gramian of
/// (A, B): A Wc A^T - Wc + B B^T = 0 if discrete, A Wc + Wc A^T + B B^T = 0 if not,
/// Wc = Lc Lc^T.
/// Method / Numerical aspects: see the file comment (Hammarling 1982).
/// Preconditions: A n x n, B n x m, A strictly stable; std::invalid_argument otherwise.
template <class DerivedA, class DerivedB>
Eigen::MatrixXd controllability_gramian_factor(const Eigen::MatrixBase<DerivedA>& A,
                                               const Eigen::MatrixBase<DerivedB>& B, bool discrete) {
  return detail::controllability_gramian_factor_impl(A.eval(), B.eval(), discrete);
}

/// Purpose: factor Lo (n x n, lower triangular) of the observability Gramian of
/// (A, C): A^T Wo A - Wo + C^T C = 0 if discrete, A^T Wo + Wo A + C^T C = 0 if not,
/// Wo = Lo Lo^T.
/// Preconditions: A n x n, C l x n, A strictly stable; std::invalid_argument otherwise.
template <class DerivedA, class DerivedC>
Eigen::MatrixXd observability_gramian_factor(const Eigen::MatrixBase<DerivedA>& A,
                                             const Eigen::MatrixBase<DerivedC>& C, bool discrete) {
  return detail::observability_gramian_factor_impl(A.eval(), C.eval(), discrete);
}

/// Purpose: both Gramian factors of a model (discrete if Ts > 0), sharing one Schur
/// decomposition.
/// Preconditions: a valid, strictly stable StateSpace (std::invalid_argument otherwise).
GramianFactors gramian_factors(const StateSpace& sys);

/// Purpose: the Gramian W = L L^T itself, from a factor (convenience).
Eigen::MatrixXd gramian_from_factor(const Eigen::MatrixXd& L);

}  // namespace sysid
