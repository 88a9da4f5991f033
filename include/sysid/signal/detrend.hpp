#pragma once
/// @file
/// Purpose: removal of a constant or a straight line from every column of a
/// signal (N x channels), the usual first step before spectral estimation or
/// identification of data with offsets or slow drift.
///
/// Method: ordinary least squares per column on the basis {1, n - (N-1)/2},
/// n = 0..N-1. The centred ramp is orthogonal to the constant, so the normal
/// equations are diagonal and the two coefficients are independent projections:
///   offset = sum_n x_n / N,   slope = sum_n (n - c) x_n / sum_n (n - c)^2,  c = (N-1)/2
/// (Bendat & Piersol, Random Data, 4th ed., sec. 11.1.2, "trend removal").
/// The removed trend is offset + slope (n - c); `trend_coefficients` returns the
/// two numbers per column so a caller can record or restore them.
///
/// Numerical aspects: O(N channels), two passes over each column; centring the
/// ramp avoids the cancellation of the uncentred normal equations (whose
/// condition grows like N^2).
#include <Eigen/Dense>
#include <stdexcept>
#include <string>

namespace sysid {

/// What detrend() removes from each column.
enum class TrendType {
  constant,  ///< the column mean
  linear,    ///< the least-squares straight line
};

/// Per-column trend: row 0 = offset (value at the record centre, sample (N-1)/2),
/// row 1 = slope per sample (0 for TrendType::constant).
template <class Derived>
Eigen::Matrix<double, 2, Eigen::Dynamic> trend_coefficients(const Eigen::MatrixBase<Derived>& x, TrendType type) {
  const Eigen::Index n = x.rows();
  if (n < 1) throw std::invalid_argument("detrend: need samples >= 1");
  if (type == TrendType::linear && n < 2) throw std::invalid_argument("detrend: a linear trend needs samples >= 2");
  Eigen::Matrix<double, 2, Eigen::Dynamic> c(2, x.cols());
  c.row(0) = x.colwise().mean();
  c.row(1).setZero();
  if (type == TrendType::linear) {
    const Eigen::VectorXd ramp =
        Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)).array() - 0.5 * static_cast<double>(n - 1);
    c.row(1) = (ramp.transpose() * x) / ramp.squaredNorm();
  }
  return c;
}

/// Purpose: x minus its per-column constant (mean) or least-squares line.
/// Method: see the file comment.
/// Preconditions (std::invalid_argument): rows(x) >= 1 (>= 2 for linear).
/// Numerical aspects: O(N channels). Returns an N x channels matrix; the result of
/// `constant` has zero column sums and that of `linear` is also orthogonal to the ramp
/// (up to rounding).
/// Example: `Eigen::MatrixXd y = detrend(log.y, TrendType::linear);`
template <class Derived>
Eigen::MatrixXd detrend(const Eigen::MatrixBase<Derived>& x, TrendType type = TrendType::linear) {
  const Eigen::Matrix<double, 2, Eigen::Dynamic> c = trend_coefficients(x, type);
  const Eigen::Index n = x.rows();
  Eigen::MatrixXd y = x;
  y.rowwise() -= c.row(0);
  if (type == TrendType::linear) {
    const Eigen::VectorXd ramp =
        Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)).array() - 0.5 * static_cast<double>(n - 1);
    y.noalias() -= ramp * c.row(1);
  }
  return y;
}

/// "constant" / "linear" (also "mean", "none" is not a trend) -> TrendType; std::invalid_argument otherwise.
inline TrendType parse_trend_type(const std::string& name) {
  if (name == "constant" || name == "mean") return TrendType::constant;
  if (name == "linear") return TrendType::linear;
  throw std::invalid_argument("detrend: unknown trend '" + name + "' (need constant or linear)");
}

}  // namespace sysid
