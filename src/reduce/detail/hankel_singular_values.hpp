#pragma once
/// @file
/// Internals of reduce/hankel_singular_values.hpp shared by several compiled parts
/// (src/reduce/hankel_singular_values.cpp, src/reduce/balanced_truncation.cpp,
/// src/reduce/modal_truncation.cpp); defined in src/reduce/hankel_singular_values.cpp. The
/// methods are described in reduce/hankel_singular_values.hpp.
#include <sysid/core/state_space.hpp>
#include "reduce/detail/gramians.hpp"
#include <sysid/reduce/hankel_singular_values.hpp>

#include <Eigen/Dense>

namespace sysid::detail {

/// The model with A balanced by a power-of-two diagonal similarity (exact).
StateSpace balanced_realisation(const StateSpace& sys);

/// Square-root balancing data of a stable model: factors and the SVD of Lo^T Lc.
struct SquareRootBalancing {
  Eigen::MatrixXd Lc, Lo;
  Eigen::MatrixXd U, V;  ///< singular vectors (empty when only values were asked for)
  Eigen::VectorXd hsv;
};

/// SVD of M = Lo^T Lc (square-root method). Fast path (cross-product method with
/// a Rayleigh-quotient step): eigen-decomposition M^T M = V Lambda V^T (symmetric
/// tridiagonal QR, ~4x cheaper than Eigen's BDCSVD at n ~ 100), then W = M V,
/// sigma_i = ||W e_i||, U e_i = W e_i / sigma_i. A direction of V with eigenvalue
/// lambda_i is accurate to ~eps sigma_1^2 / gap, and the norm ||M v_i|| is
/// stationary in v_i, so sigma_i has relative error ~ eps sigma_1/sigma_i (the
/// rounding of M V, as for an SVD) + (eps (sigma_1/sigma_i)^2)^2, i.e. below ~1e-11
/// for sigma_i >= 1e-5 sigma_1, instead of the eps (sigma_1/sigma_i)^2 of
/// sqrt(lambda_i). Used only when lambda_min >= 1e-10 lambda_max (HSV spread
/// <= 1e5, typical of lightly damped structural models); otherwise the
/// divide-and-conquer SVD (Eigen::BDCSVD).
SquareRootBalancing square_root_balancing(const StateSpace& stable, const ComplexSchurForm& schur, bool vectors);

/// stable_unstable_split() that also returns the complex Schur form of the stable
/// part's A (A_s = stable_schur.U T U^H), so the Gramians need no second Schur.
StabilitySplit stable_unstable_split(const StateSpace& sys, double tol, ComplexSchurForm& stable_schur);

}  // namespace sysid::detail
