#pragma once
/// @file
/// Purpose: the Cholesky factor of a symmetric positive definite matrix given
/// in double-double (core/double_double.hpp), rounded to double at the end.
///
/// Why: a Gram matrix G = H^T H formed in double carries an error of about
/// u ||H||^2 (u = 1.1e-16), which swamps its small eigenvalues once
/// cond(H) > 1e8, so chol(G) fails or loses every digit there, while a
/// Householder QR of H keeps an error of u ||H|| in R. Formed and factorised in
/// double-double (error ~1e-30 ||H||^2), chol(G) gives an R at least as accurate
/// as Householder's for cond(H) up to about 1e15, beyond which neither is
/// meaningful in double.
///
/// Method: the column-oriented (up-looking) Cholesky algorithm, Golub & Van Loan,
/// "Matrix Computations", 4th ed., Algorithm 4.2.1 (gaxpy Cholesky), every
/// operation in double-double. Cost k^3 / 3 double-double multiply-adds (about
/// 20 flops each): 80 x 80 in about 1 ms.
///
/// Result: R upper triangular with R^T R = G (rounded to double), whether G was
/// found positive definite, and the smallest pivot ratio R_jj / sqrt(G_jj) over
/// the columns: the sine of the angle between column j of H and the span of the
/// columns before it, a cheap lower bound on how close H is to rank deficiency
/// (ratio >= sigma_min(H) / sigma_max(H)).
#include <Eigen/Dense>
#include <sysid/core/double_double.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace sysid {

/// A pivot ratio below this proves the matrix behind G rank deficient to double
/// precision (ratio >= sigma_min / sigma_max, so cond > 1e14): there the
/// double-double factor is no better defined than a Householder R, and the
/// callers (block-Hankel compression, PEM Jacobian) let the QR decide.
inline constexpr double kRankDeficientPivotRatio = 1e-14;

struct DoubleDoubleCholeskyResult {
  Eigen::MatrixXd R;               ///< k x k upper triangular, rounded to double (valid only if positive_definite)
  bool positive_definite = false;  ///< every pivot was positive
  double smallest_pivot_ratio = 0;  ///< min_j R_jj / sqrt(G_jj)
};

inline DoubleDoubleCholeskyResult double_double_cholesky(const DoubleDoubleMatrix& g) {
  const Eigen::Index k = g.hi.rows();
  DoubleDoubleCholeskyResult out;
  out.R = Eigen::MatrixXd::Zero(k, k);
  out.smallest_pivot_ratio = std::numeric_limits<double>::infinity();
  // Column-major upper triangle of R in double-double: column j holds R(0..j, j).
  std::vector<DoubleDouble> r(static_cast<std::size_t>(k * k));
  auto at = [&r, k](Eigen::Index i, Eigen::Index j) -> DoubleDouble& { return r[static_cast<std::size_t>(j * k + i)]; };
  for (Eigen::Index j = 0; j < k; ++j) {
    for (Eigen::Index i = 0; i <= j; ++i) {
      DoubleDouble s = g(i, j);
      const DoubleDouble* ri = &at(0, i);
      const DoubleDouble* rj = &at(0, j);
      for (Eigen::Index p = 0; p < i; ++p) s -= ri[p] * rj[p];
      if (i < j) {
        at(i, j) = s / at(i, i);
        continue;
      }
      if (!(s.hi > 0.0)) {
        out.smallest_pivot_ratio = 0.0;
        return out;  // not positive definite (to double-double accuracy)
      }
      at(j, j) = sqrt(s);
      out.smallest_pivot_ratio = std::min(out.smallest_pivot_ratio, at(j, j).hi / std::sqrt(g.hi(j, j)));
    }
  }
  for (Eigen::Index j = 0; j < k; ++j)
    for (Eigen::Index i = 0; i <= j; ++i) out.R(i, j) = at(i, j).to_double();
  out.positive_definite = true;
  return out;
}

}  // namespace sysid
