#pragma once
/// @file
/// Internals of core/poles_zeros.hpp shared by several compiled parts
/// (src/core/poles_zeros.cpp, src/core/transfer_function.cpp, src/reduce/hankel_singular_values.cpp);
/// defined in src/core/poles_zeros.cpp. The methods are described in core/poles_zeros.hpp.
#include <Eigen/Dense>

namespace sysid::detail {

/// Balances A in place by a diagonal similarity with power-of-two entries
/// (Parlett & Reinsch 1969, 1-norms); returns the scaling d with
/// A_balanced = diag(d)^-1 A diag(d).
Eigen::VectorXd balance_in_place(Eigen::MatrixXd& A);

/// Result of the zero computation: the finite zeros and the normal rank of the
/// transfer matrix.
struct InvariantZeros {
  Eigen::VectorXcd zeros;
  Eigen::Index normal_rank = 0;
};

/// Invariant zeros of a square system; zeros are valid only if normal_rank == m.
InvariantZeros invariant_zeros(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, const Eigen::MatrixXd& C,
                               const Eigen::MatrixXd& D);

}  // namespace sysid::detail
