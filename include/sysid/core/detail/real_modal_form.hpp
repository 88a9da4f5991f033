#pragma once
/// @file
/// Purpose: the real modal form of a real square matrix, shared by modal
/// truncation (reduce/modal_truncation.hpp) and the joint refit of a nominal's
/// linear dynamics (diagnose/linear_core_refit.hpp).
///
/// Method: A V = V diag(lambda) from Eigen's EigenSolver; each real eigenvalue
/// keeps its (real) eigenvector as a column of T, each complex pair lambda,
/// conj(lambda) with Im lambda > 0 the real and imaginary parts of lambda's
/// eigenvector, so that T^-1 A T = blockdiag([lambda] or [[Re, Im], [-Im, Re]]).
/// EigenSolver of a real matrix gives real eigenvalues an exactly zero
/// imaginary part (1x1 blocks of its real Schur form), so the test is exact.
/// Conditioning of T (a defective or nearly defective A) is the caller's to
/// judge: each has its own policy.
#include <Eigen/Dense>
#include <complex>
#include <vector>

namespace sysid::detail {

struct RealModalBlock {
  Eigen::Index start = 0;        ///< first column of T
  Eigen::Index size = 1;         ///< 1 (real eigenvalue) or 2 (complex pair)
  std::complex<double> lambda;   ///< the eigenvalue (Im > 0 for a pair)
};

struct RealModalForm {
  Eigen::MatrixXd T;                   ///< n x n
  std::vector<RealModalBlock> blocks;  ///< in EigenSolver's order
};

enum class RealModalStatus { ok, no_convergence, unpaired };

/// Fills `form` for A (n x n, n >= 1); `unpaired` when a complex eigenvalue has
/// no conjugate (the columns would not fill T).
RealModalStatus real_modal_form(const Eigen::MatrixXd& A, RealModalForm& form);

/// The block of an eigenvalue: [Re] (size 1) or [[Re, Im], [-Im, Re]] (size 2).
Eigen::MatrixXd real_modal_block(const RealModalBlock& block);

}  // namespace sysid::detail
