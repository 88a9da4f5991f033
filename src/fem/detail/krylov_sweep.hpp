#pragma once
/// @file
/// Purpose: the displacement response of a large FE model at many frequencies from
/// ONE sparse factorisation, for sparse_frf's method = krylov (sparse_frf.hpp has
/// the user-facing contract).
///
/// Method: moment matching on a block Krylov space of the shift-invert operator,
/// the "fast frequency sweep" of structural FE codes (Grimes, Lewis & Simon 1994,
/// SIAM J. Matrix Anal. Appl. 15(1); Bai, Appl. Numer. Math. 43 (2002)). With
/// proportional damping (none, Rayleigh, structural)
///
///   Z(omega) = a K - b M = a S + (a sigma0 - b) M,   S = K - sigma0 M,
///   a = 1 + j (omega beta + eta),  b = omega^2 - j omega alpha.
///
/// S (real, sigma0 < 0: positive definite) is factorised once by CHOLMOD. Block
/// Lanczos with full reorthogonalisation on S^-1 M gives an M-orthonormal V and
///
///   S^-1 M V = V H + W E^T,   S^-1 F = V G
///
/// (H p x p symmetric, W the next block's part M-orthogonal to V, E the last block's
/// columns of the identity). Multiplying Z X = F by S^-1 and asking the part in
/// span V to vanish gives, per frequency,
///
///   X ~ V y,  (a I + (a sigma0 - b) H) y = G,
///   S^-1 (F - Z V y) = -(a sigma0 - b) W E^T y   (exactly, from the relation).
///
/// H = Q Theta Q^T once per basis size makes each frequency O(p (l + m) m); only
/// the output rows of V and W are used, no full-length vector is formed per
/// frequency. V is real; only the p x m coefficients are complex.
///
/// The error estimate. e = X_true - V y = Z^-1 S S^-1 R, and in the modes of
/// (K, M) Z^-1 S = diag((lambda_i - sigma0) / (a lambda_i - b)). W is M-orthogonal to
/// the span V, which holds the excited modes from the bottom of the spectrum up, so
/// its modes are taken to lie above lambda_front = sigma0 + 1 / theta_min (the
/// highest eigenvalue the basis represents), where that factor is at most
/// rho = max(1/|a|, (lambda_front - sigma0) / |a lambda_front - b|) when omega^2 is
/// below lambda_front (a frequency above it is not accepted). So
///
///   |e| <~ rho |a sigma0 - b| |W E^T y|   at each output DOF,
///
/// free of the round-off that makes the full residual F - Z V y of a beam or plate
/// model useless (its stiffness spans 10 or more decades, so round-off in the high
/// modes swamps ||R||; a normwise backward error is small even when the response
/// is wrong: both were tried and measured). Beside it stands the round-off floor
/// eps cond(S), cond(S) = (lambda_max - sigma0) theta_max with lambda_max from a
/// short power iteration: the solves with S, like any direct solve, are accurate
/// only to about that (measured: 3e-2 predicted, ~1e-2 found on data/fem's
/// 3 002-DOF bar, whose direct solves are themselves 4e-4 off a long-double
/// solve; 5e-11 on the 50 000-DOF membrane of bench/). A frequency is accepted
/// when the larger of the two, the truncation estimate taken relative to each
/// output entry (entries below 1e-4 of their input's largest count as that size),
/// is <= tolerance; when the floor alone exceeds it, the sweep stops at once and
/// leaves everything to the direct solves. The assumption behind rho is why this
/// is an estimate, not a bound: the tests and the benchmark compare the accepted
/// responses with direct solves.
///
/// The basis grows (by a quarter at a time) while frequencies fail; what is still
/// unaccepted when the next block would pass max_basis, 0 Hz (where a free
/// structure's rigid-body modes make Z singular), and frequencies where a projected
/// modal stiffness |a lambda_i - b| nearly vanishes (an undamped resonance) are left
/// to the caller's direct solves, which judge singularity as they always do.
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "sysid/fem/second_order_model.hpp"

namespace sysid::fem::detail {

struct KrylovSweepOptions {
  double tolerance = 1e-8;        ///< largest estimated relative error of an output entry
  Eigen::Index max_basis = 400;   ///< basis columns at most (memory: dofs x max_basis doubles)
  double shift_hz = 0.0;          ///< sigma0 = -(2 pi shift_hz)^2; 0 = 1/20 of the highest frequency
};

struct KrylovSweepResult {
  /// Per frequency: displacement at the output DOFs per unit force, outputs x
  /// inputs; an empty matrix where the frequency was not certified.
  std::vector<Eigen::MatrixXcd> output_displacement;
  long certified = 0;              ///< frequencies with a certified response
  Eigen::Index basis_size = 0;     ///< final p
  double shift = 0.0;              ///< sigma0 factorised, rad^2/s^2
  double max_estimated_error = 0.0; ///< over the certified frequencies
  long symbolic_analyses = 0, numeric_factorisations = 0;  ///< of K - sigma0 M (CHOLMOD)
  double rounding_error_estimate = 0.0;  ///< eps cond(K - sigma0 M), the round-off floor
  bool exhausted = false;          ///< the Krylov space became invariant before max_basis
};

/// omega in rad/s, each >= 0. Throws std::invalid_argument for a model with a
/// damping matrix (not proportional), sysid::NumericalError when K - sigma0 M is
/// not positive definite (K indefinite).
KrylovSweepResult krylov_sweep(const SecondOrderModel& model, const Eigen::VectorXd& omega, const KrylovSweepOptions& options);

}  // namespace sysid::fem::detail
