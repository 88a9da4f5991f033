// Implementation of pem/lagged_regression.hpp (method in the header).
#include <sysid/core/column_scaled_condition.hpp>
#include <sysid/core/detail/lagged_sums.hpp>
#include <sysid/core/double_double_cholesky.hpp>
#include <sysid/core/streaming_qr.hpp>
#include <sysid/pem/lagged_regression.hpp>

#include <algorithm>
#include <limits>
#include <optional>
#include <stdexcept>

namespace sysid {

namespace {

/// Column (signal, lag, sign) of [Phi target], in the order of the terms, the target last.
struct LaggedColumn {
  Eigen::Index signal = 0;
  int lag = 0;
  double sign = 1.0;
};

std::vector<LaggedColumn> lagged_columns(Eigen::Index target, const std::vector<RegressionTerm>& terms) {
  std::vector<LaggedColumn> columns;
  for (const RegressionTerm& t : terms)
    for (int k = 0; k < t.count; ++k) columns.push_back({t.signal, t.first_lag + k, t.sign});
  columns.push_back({target, 0, 1.0});
  return columns;
}

/// R of [Phi target] from its double-double Gram matrix (header: the Gram
/// route); empty when the semidefinite Cholesky refuses it. Row t >= max_lag of
/// column (signal, lag) is s(t - lag) = s(t' + max_lag - lag) with t' = t -
/// max_lag, so the Gram entry of two columns is the lagged sum
/// S(max_lag - lag_a, max_lag - lag_b) over the N - max_lag rows.
std::optional<Eigen::MatrixXd> gram_factor(const std::vector<Eigen::MatrixXd>& signals,
                                           const std::vector<LaggedColumn>& columns, int max_lag) {
  const Eigen::Index width = signals.front().cols(), k = static_cast<Eigen::Index>(columns.size());
  DoubleDoubleMatrix gram = DoubleDoubleMatrix::zero(k, k);
  for (const auto& s : signals) {
    const Eigen::Index rows = s.rows() - max_lag;
    if (rows <= 0) continue;
    const DoubleDoubleMatrix sums = detail::lagged_sums_double_double(s, s, max_lag + 1, rows, true);
    for (Eigen::Index c = 0; c < k; ++c)
      for (Eigen::Index r = 0; r <= c; ++r) {
        const LaggedColumn &a = columns[static_cast<std::size_t>(r)], &b = columns[static_cast<std::size_t>(c)];
        const DoubleDouble sum = sums((max_lag - a.lag) * width + a.signal, (max_lag - b.lag) * width + b.signal);
        const double sign = a.sign * b.sign;
        const DoubleDouble entry = gram(r, c) + DoubleDouble(sign * sum.hi, sign * sum.lo);
        gram.set(r, c, entry);
        gram.set(c, r, entry);
      }
  }
  return lagged_sums_gram_factor(gram);
}

/// R of [Phi target] by a Householder QR of the streamed rows.
Eigen::MatrixXd householder_factor(const std::vector<Eigen::MatrixXd>& signals, const std::vector<LaggedColumn>& columns,
                                   int max_lag) {
  const Eigen::Index k = static_cast<Eigen::Index>(columns.size());
  StreamingQR qr(k);
  const Eigen::Index chunk = 2048;
  Eigen::MatrixXd rows(chunk, k);
  for (const auto& s : signals) {
    for (Eigen::Index start = max_lag; start < s.rows(); start += chunk) {
      const Eigen::Index count = std::min(chunk, s.rows() - start);
      for (Eigen::Index c = 0; c < k; ++c) {
        const LaggedColumn& col = columns[static_cast<std::size_t>(c)];
        rows.col(c).head(count) = col.sign * s.col(col.signal).segment(start - col.lag, count);
      }
      qr.add_rows(rows.topRows(count));
    }
  }
  return qr.r();
}

}  // namespace

RegressionSolution lagged_least_squares(const std::vector<Eigen::MatrixXd>& signals, Eigen::Index target,
                                        const std::vector<RegressionTerm>& terms, const LaggedRegressionOptions& options) {
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

  const std::vector<LaggedColumn> columns = lagged_columns(target, terms);
  RegressionSolution out;
  // The lagged-sum table covers every signal at every lag up to max_lag; when the
  // terms use a small part of it (many signals, few lags each, or a long first
  // lag) it would cost more memory and time than the QR: then the QR.
  const Eigen::Index table_side = static_cast<Eigen::Index>(max_lag + 1) * width;
  std::optional<Eigen::MatrixXd> gram_r;
  if (options.gram_first && table_side <= 2 * (p + 1)) gram_r = gram_factor(signals, columns, max_lag);
  out.route = gram_r ? "gram_double_double" : "householder_qr";
  const Eigen::MatrixXd r = gram_r ? std::move(*gram_r) : householder_factor(signals, columns, max_lag);
  const Eigen::MatrixXd r11 = r.topLeftCorner(p, p).triangularView<Eigen::Upper>();
  out.rows = equations;
  out.residual_sum_of_squares = r(p, p) * r(p, p);
  out.residual_variance = out.residual_sum_of_squares / static_cast<double>(equations - p);
  out.condition = column_scaled_condition(r11);  // collinearity, not units
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
