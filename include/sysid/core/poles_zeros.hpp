#pragma once
/// @file
/// Purpose: poles and (invariant/transmission) zeros of a state-space model.
///
/// Poles: eigenvalues of A after a diagonal balancing similarity (exact powers of
/// two, so it adds no rounding) that equalises row and column norms; this is what
/// keeps the eigenvalues of companion-form realisations of polynomial models
/// accurate (their raw rows and columns differ by orders of magnitude).
///
/// Zeros: the finite generalised eigenvalues of the Rosenbrock system pencil
///
///   S(lambda) = [A - lambda I, B; C, D],   i.e. the pencil ([A B; C D], [I 0; 0 0]).
///
/// The square system matrix is first balanced (a state similarity plus output
/// and input scalings, none of which moves a zero): unbalanced companion-form
/// realisations lose several digits in their zeros.
/// Feeding that (n+m) x (n+m) pencil straight to QZ is unreliable when D is
/// singular: the pencil then has infinite eigenvalues in Jordan chains (one chain
/// of length k+1 for relative degree k), and rounding splits such a chain into
/// spurious finite eigenvalues of size ~ eps^(-1/(k+1)), which no threshold on
/// |beta| separates from genuine large zeros. So the pencil is first reduced
/// (Emami-Naeini & Van Dooren 1982, Sec. 3): orthogonal row compressions of D and
/// column compressions of the part of C that D cannot see deflate every infinite
/// eigenvalue exactly, leaving a system (A_r, B_r, C_r, D_r) with the same finite
/// zeros and D_r of full row rank. For a square system of full normal rank D_r
/// is then m x m and invertible; one more orthogonal column compression
/// [C_r D_r] W = [0 D~] gives an n_r x n_r pencil (A_f, E_f) with E_f nonsingular,
/// whose eigenvalues (real QZ) are the zeros. Infinite eigenvalues can no longer
/// occur; a final |beta| filter only guards against rounding.
///
/// These are the invariant zeros: for a non-minimal realisation they include the
/// decoupling zeros (uncontrollable/unobservable modes), which then also appear
/// among the poles and cancel in the transfer function.
///
/// References:
/// - A. Emami-Naeini, P. Van Dooren, "Computation of zeros of linear multivariable
///   systems", Automatica 18(4):415-430, 1982.
/// - B. N. Parlett, C. Reinsch, "Balancing a matrix for calculation of eigenvalues
///   and eigenvectors", Numer. Math. 13:293-304, 1969.
/// - SLICOT AB08ND documentation (default rank tolerance (n+p)(n+m) eps ||S||).
#include <sysid/core/errors.hpp>
#include <sysid/core/state_space.hpp>

#include <Eigen/Dense>

namespace sysid {

/// Purpose: poles of the model, the eigenvalues of A (z-plane if discrete,
/// s-plane if continuous). Complex poles come in exact conjugate pairs.
/// Method: power-of-two balancing (Parlett & Reinsch 1969), then Hessenberg QR
/// (Eigen::EigenSolver, eigenvalues only).
/// Numerical aspects: O(n^3); backward stable for the balanced matrix.
/// Throws NumericalError if the QR iteration does not converge.
Eigen::VectorXcd poles(const StateSpace& sys);

/// Purpose: transmission (invariant) zeros of a square system (l == m): the finite
/// lambda where the Rosenbrock matrix [A - lambda I, B; C, D] loses rank.
/// Method: Emami-Naeini & Van Dooren (1982) reduction, then QZ on a regular pencil;
/// see the file comment.
/// Preconditions: outputs() == inputs() (std::invalid_argument otherwise).
/// Throws NumericalError if the transfer matrix is rank deficient for every
/// lambda (normal rank < m), where zeros are not defined, or if QZ fails.
/// Numerical aspects: O((n+m)^3); rank decisions with tolerance
/// (n+l)(n+m) eps ||[A B; C D]||_F.
Eigen::VectorXcd transmission_zeros(const StateSpace& sys);

/// Purpose: zeros of the single channel from input `input` to output `output`
/// (invariant zeros of the realisation (A, B(:,input), C(output,:), D(output,input))).
/// Preconditions: 0 <= output < l, 0 <= input < m.
/// Throws NumericalError if the channel is identically zero.
Eigen::VectorXcd channel_zeros(const StateSpace& sys, Eigen::Index output, Eigen::Index input);

}  // namespace sysid
