// Implementation of pem/lagged_regression.hpp (method in the header).
#include <sysid/core/streaming_qr.hpp>
#include <sysid/pem/lagged_regression.hpp>

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace sysid {

RegressionSolution lagged_least_squares(const std::vector<Eigen::MatrixXd>& signals, Eigen::Index target,
                                        const std::vector<RegressionTerm>& terms) {
  if (signals.empty()) throw std::invalid_argument("least squares: need at least one experiment");
  const Eigen::Index width = signals.front().cols();
  if (target < 0 || target >= width) throw std::invalid_argument("least squares: target column out of range");
  Eigen::Index p = 0;
  int max_lag = 0;
  for (const RegressionTerm& t : terms) {
    if (t.signal < 0 || t.signal >= width) throw std::invalid_argument("least squares: term signal out of range");
    if (t.count < 0 || t.first_lag < 0) throw std::invalid_argument("least squares: need count >= 0 and first_lag >= 0");
    if (t.signal == target && t.count > 0 && t.first_lag < 1)
      throw std::invalid_argument("least squares: the target may only enter with lags >= 1");
    p += t.count;
    if (t.count > 0) max_lag = std::max(max_lag, t.first_lag + t.count - 1);
  }
  if (p == 0) throw std::invalid_argument("least squares: need at least one coefficient");
  Eigen::Index equations = 0;
  for (const auto& s : signals) {
    if (s.cols() != width) throw std::invalid_argument("least squares: experiments differ in their signals");
    equations += std::max<Eigen::Index>(0, s.rows() - max_lag);
  }
  if (equations <= p)
    throw std::invalid_argument("least squares: need more equations than parameters (" + std::to_string(equations) +
                                " <= " + std::to_string(p) + "); the data are too short for these orders");

  StreamingQR qr(p + 1);
  const Eigen::Index chunk = 2048;
  Eigen::MatrixXd rows(chunk, p + 1);
  for (const auto& s : signals) {
    for (Eigen::Index start = max_lag; start < s.rows(); start += chunk) {
      const Eigen::Index count = std::min(chunk, s.rows() - start);
      Eigen::Index col = 0;
      for (const RegressionTerm& t : terms)
        for (int k = 0; k < t.count; ++k, ++col)
          rows.col(col).head(count) = t.sign * s.col(t.signal).segment(start - t.first_lag - k, count);
      rows.col(p).head(count) = s.col(target).segment(start, count);
      qr.add_rows(rows.topRows(count));
    }
  }
  const Eigen::MatrixXd r = qr.r();
  const Eigen::MatrixXd r11 = r.topLeftCorner(p, p).triangularView<Eigen::Upper>();
  RegressionSolution out;
  out.rows = equations;
  out.residual_sum_of_squares = r(p, p) * r(p, p);
  out.residual_variance = out.residual_sum_of_squares / static_cast<double>(equations - p);
  // Condition of the column-scaled R (collinearity, not units).
  Eigen::VectorXd norms = r11.colwise().norm().transpose();
  for (Eigen::Index k = 0; k < p; ++k)
    if (!(norms(k) > 0)) norms(k) = 1.0;
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(r11 * norms.cwiseInverse().asDiagonal()).singularValues();
  out.condition = sv(p - 1) > 0 ? sv(0) / sv(p - 1) : std::numeric_limits<double>::infinity();
  out.rank_deficient = !(out.condition < 1e12);
  if (!out.rank_deficient) {
    out.theta = r11.triangularView<Eigen::Upper>().solve(r.col(p).head(p));
    const Eigen::MatrixXd r_inv = r11.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(p, p));
    out.covariance = out.residual_variance * r_inv * r_inv.transpose();
  } else {
    const auto cod = r11.completeOrthogonalDecomposition();
    out.theta = cod.solve(r.col(p).head(p));
    const Eigen::MatrixXd pinv = cod.pseudoInverse();
    out.covariance = out.residual_variance * pinv * pinv.transpose();
  }
  return out;
}

}  // namespace sysid
