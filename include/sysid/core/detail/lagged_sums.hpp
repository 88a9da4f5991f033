#pragma once
/// @file
/// Purpose: the Gram matrix of a block-Hankel matrix of one record without
/// forming the Hankel matrix: O(N i2) work instead of O(N i2^2). Used by the
/// block-Hankel compression's correlation route (hankel/block_hankel.hpp) and
/// by the order of persistent excitation (core/persistent_excitation.hpp).
#include <Eigen/Dense>

#include <algorithm>

namespace sysid::detail {

/// Lagged sums S(p,q) = sum_{t=0}^{j-1} x(t+p) y(t+q)^T for p, q = 0..i2-1,
/// written as an (i2*mx) x (i2*my) block matrix. The first block row and column
/// are correlation sums over the whole record, computed in chunks of rows with
/// one GEMM per chunk (BLAS-3 shape, no copy of the record); every other block
/// follows from its upper-left neighbour by adding the product that enters the
/// window and removing the one that leaves it.
template <class MX, class MY>
Eigen::MatrixXd lagged_sums(const MX& x, const MY& y, Eigen::Index i2, Eigen::Index j, bool symmetric) {
  const Eigen::Index mx = x.cols(), my = y.cols();
  Eigen::MatrixXd s = Eigen::MatrixXd::Zero(i2 * mx, i2 * my);
  Eigen::MatrixXd first_row = Eigen::MatrixXd::Zero(mx, i2 * my);  // S(0,q)
  Eigen::MatrixXd first_col = Eigen::MatrixXd::Zero(my, i2 * mx);  // S(p,0)^T
  constexpr Eigen::Index chunk = 4096;
  Eigen::MatrixXd shifted_y(chunk, i2 * my), shifted_x;
  if (!symmetric) shifted_x.resize(chunk, i2 * mx);
  for (Eigen::Index t0 = 0; t0 < j; t0 += chunk) {
    const Eigen::Index c = std::min(chunk, j - t0);
    for (Eigen::Index q = 0; q < i2; ++q) shifted_y.block(0, q * my, c, my) = y.middleRows(t0 + q, c);
    first_row.noalias() += x.middleRows(t0, c).transpose() * shifted_y.topRows(c);
    if (!symmetric) {
      for (Eigen::Index p = 0; p < i2; ++p) shifted_x.block(0, p * mx, c, mx) = x.middleRows(t0 + p, c);
      first_col.noalias() += y.middleRows(t0, c).transpose() * shifted_x.topRows(c);
    }
  }
  s.topRows(mx) = first_row;
  for (Eigen::Index p = 1; p < i2; ++p)
    s.block(p * mx, 0, mx, my) = symmetric ? Eigen::MatrixXd(first_row.middleCols(p * my, my).transpose())
                                           : Eigen::MatrixXd(first_col.middleCols(p * mx, mx).transpose());
  for (Eigen::Index p = 1; p < i2; ++p)
    for (Eigen::Index q = 1; q < i2; ++q)
      s.block(p * mx, q * my, mx, my) = s.block((p - 1) * mx, (q - 1) * my, mx, my) +
                                        x.row(p - 1 + j).transpose() * y.row(q - 1 + j) -
                                        x.row(p - 1).transpose() * y.row(q - 1);
  return s;
}

}  // namespace sysid::detail
