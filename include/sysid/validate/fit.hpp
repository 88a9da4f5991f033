#pragma once
/// @file
/// Purpose: the normalised fit of DESIGN.md, per output channel:
///   fit % = 100 (1 - ||y - yhat|| / ||y - mean(y)||)
/// (the NRMSE fit of Ljung's System Identification Toolbox). 100 is perfect,
/// 0 is as good as the mean, negative is worse than the mean.
#include <Eigen/Dense>
#include <limits>
#include <stdexcept>

namespace sysid {

template <class D1, class D2>
Eigen::VectorXd fit_percent(const Eigen::MatrixBase<D1>& y, const Eigen::MatrixBase<D2>& y_hat) {
  if (y.rows() != y_hat.rows() || y.cols() != y_hat.cols())
    throw std::invalid_argument("fit: measured and simulated outputs differ in size");
  Eigen::VectorXd fit(y.cols());
  for (Eigen::Index c = 0; c < y.cols(); ++c) {
    const double spread = (y.col(c).array() - y.col(c).mean()).matrix().norm();
    const double error = (y.col(c) - y_hat.col(c)).norm();
    fit(c) = spread > 0 ? 100.0 * (1.0 - error / spread) : -std::numeric_limits<double>::infinity();
  }
  return fit;
}

}  // namespace sysid
