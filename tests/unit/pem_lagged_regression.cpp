#include <sysid/pem/lagged_regression.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "random_matrices.hpp"

namespace test_unit_pem_lagged_regression {

using namespace sysid;

namespace {

using quad = __float128;

/// y(t) = -a1 y(t-1) - a2 y(t-2) + sum_k b_k u(t-k) + e(t) for a resonance of
/// the given pole radius and angle: a lightly damped mode sampled fast makes
/// the lagged outputs nearly collinear (the condition the Gram route must survive).
Eigen::MatrixXd resonant_arx_log(Eigen::Index n, double radius, double angle, double noise, std::uint64_t seed) {
  const Eigen::MatrixXd w = test::white_noise(n, 2, seed);
  const double a1 = -2 * radius * std::cos(angle), a2 = radius * radius;
  Eigen::MatrixXd s = Eigen::MatrixXd::Zero(n, 2);
  s.col(1) = w.col(0);
  for (Eigen::Index t = 0; t < n; ++t) {
    double y = noise * w(t, 1);
    if (t >= 1) y += -a1 * s(t - 1, 0) + 0.5 * s(t - 1, 1);
    if (t >= 2) y += -a2 * s(t - 2, 0) + 0.25 * s(t - 2, 1);
    s(t, 0) = y;
  }
  return s;
}

/// Least squares of the terms in binary128 by the normal equations: with
/// cond^2 far below 1 / u_quad = 1e34 this is exact to double precision.
Eigen::VectorXd quad_least_squares(const Eigen::MatrixXd& s, const std::vector<RegressionTerm>& terms, int max_lag) {
  std::vector<std::pair<Eigen::Index, int>> cols;
  std::vector<double> signs;
  for (const auto& t : terms)
    for (int k = 0; k < t.count; ++k) {
      cols.emplace_back(t.signal, t.first_lag + k);
      signs.push_back(t.sign);
    }
  const std::size_t p = cols.size();
  std::vector<quad> g(p * p, 0), b(p, 0);
  for (Eigen::Index t = max_lag; t < s.rows(); ++t)
    for (std::size_t i = 0; i < p; ++i) {
      const quad xi = static_cast<quad>(signs[i] * s(t - cols[i].second, cols[i].first));
      b[i] += xi * static_cast<quad>(s(t, 0));
      for (std::size_t j = 0; j <= i; ++j) g[i * p + j] += xi * static_cast<quad>(signs[j] * s(t - cols[j].second, cols[j].first));
    }
  // Cholesky in binary128, then the two triangular solves.
  std::vector<quad> l(p * p, 0);
  for (std::size_t j = 0; j < p; ++j) {
    quad d = g[j * p + j];
    for (std::size_t k = 0; k < j; ++k) d -= l[j * p + k] * l[j * p + k];
    const quad root = __builtin_sqrtf128(d);
    l[j * p + j] = root;
    for (std::size_t i = j + 1; i < p; ++i) {
      quad v = g[i * p + j];
      for (std::size_t k = 0; k < j; ++k) v -= l[i * p + k] * l[j * p + k];
      l[i * p + j] = v / root;
    }
  }
  std::vector<quad> z(p);
  for (std::size_t i = 0; i < p; ++i) {
    quad v = b[i];
    for (std::size_t k = 0; k < i; ++k) v -= l[i * p + k] * z[k];
    z[i] = v / l[i * p + i];
  }
  Eigen::VectorXd theta(static_cast<Eigen::Index>(p));
  for (std::size_t i = p; i-- > 0;) {
    quad v = z[i];
    for (std::size_t k = i + 1; k < p; ++k) v -= l[k * p + i] * static_cast<quad>(theta(static_cast<Eigen::Index>(k)));
    theta(static_cast<Eigen::Index>(i)) = static_cast<double>(v / l[i * p + i]);
  }
  return theta;
}

LaggedRegressionOptions qr_only() {
  LaggedRegressionOptions o;
  o.gram_first = false;
  return o;
}

}  // namespace

TEST(LaggedRegression, GramAndQrRoutesAgreeOnAWellConditionedArx) {
  const Eigen::MatrixXd s = resonant_arx_log(3000, 0.8, 0.6, 0.1, 1);
  const std::vector<RegressionTerm> terms{{0, 1, 4, -1.0}, {1, 1, 3, 1.0}};
  const RegressionSolution gram = lagged_least_squares({s}, 0, terms);
  const RegressionSolution qr = lagged_least_squares({s}, 0, terms, qr_only());
  EXPECT_EQ(gram.route, "gram_double_double");
  EXPECT_EQ(qr.route, "householder_qr");
  EXPECT_LT((gram.theta - qr.theta).norm(), 1e-12 * qr.theta.norm());
  EXPECT_NEAR(gram.residual_variance, qr.residual_variance, 1e-12 * qr.residual_variance);
  EXPECT_LT((gram.covariance - qr.covariance).norm(), 1e-10 * qr.covariance.norm());
  EXPECT_NEAR(gram.condition, qr.condition, 1e-8 * qr.condition);
  EXPECT_EQ(gram.rows, qr.rows);
  // The true coefficients (A = 1 - 1.6 cos(0.6) q^-1 + 0.64 q^-2, B = 0.5 q^-1 + 0.25 q^-2) within a few standard errors.
  const Eigen::VectorXd truth = (Eigen::VectorXd(7) << -1.6 * std::cos(0.6), 0.64, 0, 0, 0.5, 0.25, 0).finished();
  for (Eigen::Index k = 0; k < 7; ++k)
    EXPECT_NEAR(gram.theta(k), truth(k), 5 * std::sqrt(gram.covariance(k, k))) << "coefficient " << k;
}

TEST(LaggedRegression, GramRouteIsAsAccurateAsTheQrOnNearlyCollinearRegressors) {
  // A mode at 0.002 of the sampling rate with pole radius 0.9995 and an ARX of
  // order 12 on it: scaled condition ~2e7, where the normal equations in double
  // would keep about one digit (cond^2 u ~ 0.03) and the QR about ten.
  const Eigen::MatrixXd s = resonant_arx_log(20000, 0.9995, 2 * M_PI * 0.002, 1e-3, 2);
  const std::vector<RegressionTerm> terms{{0, 1, 12, -1.0}, {1, 1, 12, 1.0}};
  const RegressionSolution gram = lagged_least_squares({s}, 0, terms);
  const RegressionSolution qr = lagged_least_squares({s}, 0, terms, qr_only());
  ASSERT_EQ(gram.route, "gram_double_double");
  ASSERT_GT(qr.condition, 1e7) << "the case is not ill-conditioned enough to test anything";
  const Eigen::VectorXd exact = quad_least_squares(s, terms, 12);
  const double gram_error = (gram.theta - exact).norm() / exact.norm();
  const double qr_error = (qr.theta - exact).norm() / exact.norm();
  // Measured: Gram 2.9e-16, QR 3.7e-11 (cond 1.7e7): the double-double Gram
  // matrix and Cholesky lose nothing to the condition at this size.
  EXPECT_LT(gram_error, 1e-13) << "QR error " << qr_error;
  EXPECT_LT(gram_error, qr_error);
}

TEST(LaggedRegression, SeveralExperimentsAndAShortOneAreSummedAsByTheQr) {
  const Eigen::MatrixXd a = resonant_arx_log(1500, 0.9, 0.3, 0.05, 3), b = resonant_arx_log(900, 0.9, 0.3, 0.05, 4);
  const Eigen::MatrixXd tiny = resonant_arx_log(2, 0.9, 0.3, 0.05, 5);  // not longer than the lags: no equations
  const std::vector<RegressionTerm> terms{{0, 1, 2, -1.0}, {1, 0, 3, 1.0}};
  const RegressionSolution gram = lagged_least_squares({a, tiny, b}, 0, terms);
  const RegressionSolution qr = lagged_least_squares({a, tiny, b}, 0, terms, qr_only());
  EXPECT_EQ(gram.route, "gram_double_double");
  EXPECT_EQ(gram.rows, (1500 - 2) + (900 - 2));
  EXPECT_LT((gram.theta - qr.theta).norm(), 1e-12 * qr.theta.norm());
  EXPECT_NEAR(gram.residual_sum_of_squares, qr.residual_sum_of_squares, 1e-11 * qr.residual_sum_of_squares);
}

TEST(LaggedRegression, CollinearRegressorsAreReportedAndTheGramRouteKeepsTheTrueResidual) {
  // The input entered twice: the regressors are exactly collinear. Both routes
  // report rank deficiency. The residual sum of squares must be that of the
  // regression without the copy: the Gram route's semidefinite Cholesky zeroes
  // the dependent pivots and gets it to rounding. A Householder QR instead
  // turns each dependent column's rounding noise into a direction of its own
  // and removes the target's (random) component along it, about one residual
  // variance per copied column (here 2 columns, ~0.005 of 5.04).
  Eigen::MatrixXd s = resonant_arx_log(2000, 0.9, 0.3, 0.05, 6);
  s.conservativeResize(Eigen::NoChange, 3);
  s.col(2) = s.col(1);
  const std::vector<RegressionTerm> terms{{0, 1, 2, -1.0}, {1, 1, 2, 1.0}, {2, 1, 2, 1.0}};
  const RegressionSolution gram = lagged_least_squares({s}, 0, terms);
  const RegressionSolution qr = lagged_least_squares({s}, 0, terms, qr_only());
  const RegressionSolution reduced = lagged_least_squares({s}, 0, {{0, 1, 2, -1.0}, {1, 1, 2, 1.0}}, qr_only());
  EXPECT_EQ(gram.route, "gram_double_double");
  EXPECT_TRUE(gram.rank_deficient);
  EXPECT_TRUE(qr.rank_deficient);
  EXPECT_NEAR(gram.residual_sum_of_squares, reduced.residual_sum_of_squares, 1e-10 * reduced.residual_sum_of_squares);
  EXPECT_LE(qr.residual_sum_of_squares, reduced.residual_sum_of_squares * (1 + 1e-12));
  // The minimum-norm theta splits each input coefficient evenly between the copies.
  for (Eigen::Index k : {2, 3}) {
    EXPECT_NEAR(gram.theta(k), gram.theta(k + 2), 1e-8) << "coefficient " << k;
    EXPECT_NEAR(gram.theta(k) + gram.theta(k + 2), reduced.theta(k), 1e-8) << "coefficient " << k;
  }
}

TEST(LaggedRegression, SparseUseOfTheLagTableGoesToTheQr) {
  // One coefficient at lag 40 of each signal: the lagged-sum table (2 signals x
  // 41 lags) would be 40x the 3 x 3 Gram matrix: the QR answers.
  const Eigen::MatrixXd s = resonant_arx_log(1000, 0.8, 0.6, 0.1, 7);
  const std::vector<RegressionTerm> terms{{0, 40, 1, -1.0}, {1, 40, 1, 1.0}};
  const RegressionSolution sol = lagged_least_squares({s}, 0, terms);
  EXPECT_EQ(sol.route, "householder_qr");
  EXPECT_EQ(sol.rows, 1000 - 40);
}

}  // namespace test_unit_pem_lagged_regression
