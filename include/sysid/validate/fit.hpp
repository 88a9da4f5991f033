#pragma once
/// @file
/// Purpose: the normalised fit of DESIGN.md, per output channel:
///   fit % = 100 (1 - ||y - yhat|| / ||y - mean(y)||)
/// (the NRMSE fit of Ljung's System Identification Toolbox). 100 is perfect,
/// 0 is as good as the mean, negative is worse than the mean.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace sysid {

/// The same fit accumulated block by block (experiments, chunks), so that a
/// fit over several records needs neither their concatenation nor a second
/// pass: ||y - mean(y)||^2 = sum y^2 - (sum y)^2 / N about the overall mean.
class FitAccumulator {
 public:
  explicit FitAccumulator(Eigen::Index outputs)
      : error2_(Eigen::VectorXd::Zero(outputs)), sum_(Eigen::VectorXd::Zero(outputs)), sum2_(Eigen::VectorXd::Zero(outputs)) {}

  /// Adds measured outputs y and the residual y - y_hat of one block (rows = samples).
  template <class D1, class D2>
  void add_residual(const Eigen::MatrixBase<D1>& y, const Eigen::MatrixBase<D2>& residual) {
    if (y.rows() != residual.rows() || y.cols() != residual.cols() || y.cols() != error2_.size())
      throw std::invalid_argument("fit: measured outputs and residuals differ in size");
    // Shift by the first block's first sample: the sums of y and y^2 then do not
    // cancel catastrophically for signals riding on a large offset.
    if (count_ == 0 && y.rows() > 0) shift_ = y.row(0).transpose();
    const Eigen::MatrixXd centred = y.rowwise() - shift_.transpose();
    error2_ += residual.colwise().squaredNorm().transpose();
    sum_ += centred.colwise().sum().transpose();
    sum2_ += centred.colwise().squaredNorm().transpose();
    count_ += static_cast<double>(y.rows());
  }

  /// Per output, 100 (1 - ||y - y_hat|| / ||y - mean(y)||); -inf for a constant output.
  Eigen::VectorXd fit_percent() const {
    Eigen::VectorXd fit(error2_.size());
    for (Eigen::Index c = 0; c < fit.size(); ++c) {
      const double spread2 = count_ > 0 ? std::max(0.0, sum2_(c) - sum_(c) * sum_(c) / count_) : 0.0;
      fit(c) = spread2 > 0 ? 100.0 * (1.0 - std::sqrt(error2_(c) / spread2)) : -std::numeric_limits<double>::infinity();
    }
    return fit;
  }

 private:
  Eigen::VectorXd error2_, sum_, sum2_, shift_;
  double count_ = 0;
};

template <class D1, class D2>
Eigen::VectorXd fit_percent(const Eigen::MatrixBase<D1>& y, const Eigen::MatrixBase<D2>& y_hat) {
  if (y.rows() != y_hat.rows() || y.cols() != y_hat.cols())
    throw std::invalid_argument("fit: measured and simulated outputs differ in size");
  FitAccumulator fit(y.cols());
  fit.add_residual(y, y - y_hat);
  return fit.fit_percent();
}

}  // namespace sysid
