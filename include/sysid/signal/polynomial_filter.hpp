#pragma once
/// @file
/// Purpose: y = N(q) / M(q) x for polynomials in the backward shift q^-1 with a
/// monic denominator, applied to every column of x from rest (zero initial
/// conditions) — the filtering that prediction-error methods apply to data and
/// regressors.
///
/// Method: direct form II transposed, one pass, O(N (deg N + deg M)) per column.
///
/// Preconditions: M(0) = 1 (monic), N non-empty; std::invalid_argument otherwise.
/// Numerical aspects: an unstable M makes the output grow without bound; the
/// caller keeps its denominators stable (PEM does).
#include <Eigen/Dense>
#include <stdexcept>

namespace sysid {

template <class Derived>
Eigen::MatrixXd filter_polynomial(const Eigen::VectorXd& num, const Eigen::VectorXd& den, const Eigen::MatrixBase<Derived>& x) {
  if (den.size() < 1 || den(0) != 1.0) throw std::invalid_argument("filter_polynomial: need a monic denominator (den(0) = 1)");
  if (num.size() < 1) throw std::invalid_argument("filter_polynomial: need a non-empty numerator");
  const Eigen::Index order = std::max(num.size(), den.size()) - 1;
  Eigen::VectorXd b = Eigen::VectorXd::Zero(order + 1), a = Eigen::VectorXd::Zero(order + 1);
  b.head(num.size()) = num;
  a.head(den.size()) = den;
  Eigen::MatrixXd y(x.rows(), x.cols());
  Eigen::VectorXd z(order + 1);
  for (Eigen::Index c = 0; c < x.cols(); ++c) {
    z.setZero();
    for (Eigen::Index t = 0; t < x.rows(); ++t) {
      const double xt = x(t, c);
      const double yt = b(0) * xt + z(0);
      for (Eigen::Index k = 1; k <= order; ++k) z(k - 1) = z(k) + b(k) * xt - a(k) * yt;
      y(t, c) = yt;
    }
  }
  return y;
}

}  // namespace sysid
