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
/// operation in double-double, the inner products by the compensated `dot` of
/// core/double_double.hpp. Cost k^3 / 6 exact products and sums: 80 x 80 in
/// about 0.2 ms (0.6 ms with a double-double accumulation, one long dependency chain).
///
/// Result: R upper triangular with R^T R = G (rounded to double), whether G was
/// found positive definite, and the smallest pivot ratio R_jj / sqrt(G_jj) over
/// the columns: the sine of the angle between column j of H and the span of the
/// columns before it, a cheap lower bound on how close H is to rank deficiency
/// (ratio >= sigma_min(H) / sigma_max(H)).
///
/// Semidefinite mode (DoubleDoubleCholeskyOptions::gram_relative_error > 0):
/// a Schur complement pivot s_jj that is not above the rounding level,
/// s_jj <= kRankDeficientPivotRatio^2 G_jj (possibly negative), is taken as
/// exactly zero when the errors of G explain it: row j of R is zero and the
/// elimination goes on without it (the Cholesky factorisation of a positive
/// semidefinite matrix without pivoting; Higham, "Accuracy and Stability of
/// Numerical Algorithms", 2nd ed., sec. 10.3). If every entry of G is known to
/// |dG_ik| <= eps sqrt(G_ii G_kk), then s_jj = G_jj - g^T G11^-1 g moves by
///   |ds_jj| <= eps G_jj (1 + sum_i |w_i| sqrt(G_ii / G_jj))^2,  w = G11^-1 g
/// (first order; w holds the coefficients of column j of H regressed on the
/// columns before it, w = R11^-1 R(0:j, j), solved in double). A pivot below minus
/// that bound fails: G is then not a Gram matrix to the stated accuracy. The
/// bound grows with the regression coefficients: near-dependent columns with
/// large coefficients (near common factors in a polynomial model) give negative
/// pivots far above eps G_jj in size (1e-22 to 2e-17 of G_jj on the Par2
/// ARMAX(32,32,26) Jacobian) yet 1e4 to 1e6 times inside the bound.
/// Positive pivots above the rounding level are kept as they are, as a
/// Householder QR keeps its small pivots: zeroing every pivot inside the bound
/// (tried with eps from 1e-30 to 1e-28) discards directions the minimisation
/// of that ARMAX still uses (final cost 1.988-1.993 against 1.987).
/// R^T R equals G up to the dropped Schur complement entries,
/// |s_jk| <= sqrt(s_jj s_kk), and the column norms of R stay those of H (column
/// j's component along the dependent direction moves into later pivots). A
/// Householder R of the same H holds rounding noise of about u ||H|| (1 + ||w||)
/// in that row: no better defined.
#include <Eigen/Dense>
#include <sysid/core/double_double.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

namespace sysid {

/// A pivot ratio below this proves the matrix behind G rank deficient to double
/// precision (ratio >= sigma_min / sigma_max, so cond > 1e14): there the
/// double-double factor is no better defined than a Householder R: the
/// block-Hankel compression lets the QR decide; the PEM Jacobian, whose
/// over-parametrised models make this the rule, factorises in semidefinite mode.
inline constexpr double kRankDeficientPivotRatio = 1e-14;

/// Relative accuracy of the double-double Gram sums of core/detail/lagged_sums.hpp,
/// |dG_ik| <= eps sqrt(G_ii G_kk): ~3e-30 measured, with room for the recursions.
inline constexpr double kDoubleDoubleGramRelativeError = 1e-28;

struct DoubleDoubleCholeskyOptions {
  /// 0: fail at the first pivot that is not positive. > 0: semidefinite mode
  /// (file comment), with eps the relative accuracy of G's entries,
  /// |dG_ik| <= eps sqrt(G_ii G_kk) (kDoubleDoubleGramRelativeError for those sums).
  double gram_relative_error = 0;
};

struct DoubleDoubleCholeskyResult {
  Eigen::MatrixXd R;  ///< k x k upper triangular, rounded to double (valid only if factorised)
  bool factorised = false;          ///< R is valid: every pivot positive, or zeroed in semidefinite mode
  bool positive_definite = false;   ///< every pivot was positive and none was zeroed
  double smallest_pivot_ratio = 0;  ///< min_j R_jj / sqrt(G_jj) (0 when a pivot was zeroed)
  std::vector<Eigen::Index> zero_pivots;  ///< the columns whose pivot semidefinite mode took as zero
  /// Semidefinite mode: largest |s_jj| / (error bound) over the zeroed pivots
  /// (how deep inside the noise they were; <= 1), 0 if none was zeroed.
  double largest_zeroed_pivot_to_bound = 0;
};

namespace detail {

/// The first-order bound on the error of the Schur complement pivot s_jj of the
/// file comment, eps G_jj (1 + sum_i |w_i| sqrt(G_ii / G_jj))^2, with
/// w = R11^-1 R(0:j, j) from the (double) columns of R computed so far; a zero
/// pivot row contributes w_i = 0.
inline double pivot_error_bound(const Eigen::MatrixXd& R, const DoubleDoubleMatrix& g, Eigen::Index j, double eps) {
  const double gjj = g.hi(j, j);
  if (!(gjj > 0)) return 0.0;
  Eigen::VectorXd w = R.col(j).head(j);
  double spread = 0;
  for (Eigen::Index i = j - 1; i >= 0; --i) {
    const double sum = w(i) - R.row(i).segment(i + 1, j - i - 1).dot(w.segment(i + 1, j - i - 1));
    w(i) = R(i, i) == 0.0 ? 0.0 : sum / R(i, i);
    spread += std::abs(w(i)) * std::sqrt(std::max(g.hi(i, i), 0.0) / gjj);
  }
  return eps * gjj * (1.0 + spread) * (1.0 + spread);
}

}  // namespace detail

inline DoubleDoubleCholeskyResult double_double_cholesky(const DoubleDoubleMatrix& g,
                                                         const DoubleDoubleCholeskyOptions& options = {}) {
  const Eigen::Index k = g.hi.rows();
  DoubleDoubleCholeskyResult out;
  out.R = Eigen::MatrixXd::Zero(k, k);
  out.smallest_pivot_ratio = std::numeric_limits<double>::infinity();
  // Column-major upper triangle of R in double-double: column j holds R(0..j, j).
  std::vector<DoubleDouble> r(static_cast<std::size_t>(k * k));
  auto at = [&r, k](Eigen::Index i, Eigen::Index j) -> DoubleDouble& { return r[static_cast<std::size_t>(j * k + i)]; };
  for (Eigen::Index j = 0; j < k; ++j) {
    for (Eigen::Index i = 0; i <= j; ++i) {
      // s = G(i, j) - R(0:i, i)^T R(0:i, j): the compensated dot product keeps
      // the double-double accuracy of an accumulation at a fraction of its latency.
      const DoubleDouble s = g(i, j) - dot(&at(0, i), &at(0, j), i);
      if (i < j) {
        // A zeroed pivot leaves its row of R zero (the elimination skips it).
        at(i, j) = at(i, i).hi == 0.0 ? DoubleDouble() : s / at(i, i);
        out.R(i, j) = at(i, j).to_double();
        continue;
      }
      if (options.gram_relative_error > 0) {
        const double bound = s.hi > kRankDeficientPivotRatio * kRankDeficientPivotRatio * g.hi(j, j)
                                 ? 0.0
                                 : detail::pivot_error_bound(out.R, g, j, options.gram_relative_error);
        if (std::abs(s.hi) <= bound) {
          out.zero_pivots.push_back(j);
          if (bound > 0)  // a zero column (G_jj = 0) has bound and pivot 0
            out.largest_zeroed_pivot_to_bound = std::max(out.largest_zeroed_pivot_to_bound, std::abs(s.hi) / bound);
          out.smallest_pivot_ratio = 0.0;
          at(j, j) = DoubleDouble();
          continue;
        }
      }
      if (!(s.hi > 0.0)) {
        out.smallest_pivot_ratio = 0.0;
        return out;  // not positive (semi)definite (to double-double accuracy)
      }
      at(j, j) = sqrt(s);
      out.R(j, j) = at(j, j).to_double();
      out.smallest_pivot_ratio = std::min(out.smallest_pivot_ratio, at(j, j).hi / std::sqrt(g.hi(j, j)));
    }
  }
  out.factorised = true;
  out.positive_definite = out.zero_pivots.empty();
  return out;
}

/// R of a Gram matrix of double-double lagged sums (core/detail/lagged_sums.hpp,
/// entries to kDoubleDoubleGramRelativeError) in semidefinite mode, or nothing
/// when a pivot is negative beyond those errors (the caller's QR decides then).
/// The Gram routes of the PEM Jacobian and of the lagged regressions share it.
inline std::optional<Eigen::MatrixXd> lagged_sums_gram_factor(const DoubleDoubleMatrix& gram) {
  DoubleDoubleCholeskyOptions semidefinite;
  semidefinite.gram_relative_error = kDoubleDoubleGramRelativeError;
  DoubleDoubleCholeskyResult chol = double_double_cholesky(gram, semidefinite);
  if (!chol.factorised) return std::nullopt;
  return std::move(chol.R);
}

}  // namespace sysid
