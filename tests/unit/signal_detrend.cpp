// Unit tests of signal/detrend.hpp: constant and linear trend removal per column.
#include <sysid/signal/detrend.hpp>

#include <gtest/gtest.h>

#include <random>

namespace test_unit_signal_detrend {

using namespace sysid;

namespace {

Eigen::MatrixXd noise(Eigen::Index n, Eigen::Index c, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd x(n, c);
  for (Eigen::Index j = 0; j < c; ++j)
    for (Eigen::Index i = 0; i < n; ++i) x(i, j) = g(rng);
  return x;
}

}  // namespace

TEST(SignalDetrend, LinearRemovesAnExactLinePerColumn) {
  const Eigen::Index n = 1001;
  const Eigen::VectorXd k = Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1));
  Eigen::MatrixXd x(n, 3);
  x.col(0) = (3.0 + 0.25 * k.array()).matrix();
  x.col(1) = (-7.0 - 1e-3 * k.array()).matrix();
  x.col(2).setConstant(42.0);
  const Eigen::MatrixXd y = detrend(x, TrendType::linear);
  // A pure line leaves only rounding: |x| <= ~260, eps ~ 2e-16, N ~ 1e3 sums -> 1e-10 is ample.
  EXPECT_LT(y.cwiseAbs().maxCoeff(), 1e-10);
  const auto c = trend_coefficients(x, TrendType::linear);
  EXPECT_NEAR(c(1, 0), 0.25, 1e-13);
  EXPECT_NEAR(c(1, 1), -1e-3, 1e-13);
  EXPECT_NEAR(c(0, 0), 3.0 + 0.25 * 500.0, 1e-10);  // value at the centre sample (N-1)/2 = 500
  EXPECT_NEAR(c(1, 2), 0.0, 1e-13);
}

TEST(SignalDetrend, ResidualIsOrthogonalToConstantAndRampAndKeepsTheNoise) {
  const Eigen::Index n = 5000;
  const Eigen::MatrixXd e = noise(n, 4, 11);
  const Eigen::VectorXd k = Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1));
  Eigen::MatrixXd x = e;
  for (Eigen::Index j = 0; j < 4; ++j) x.col(j) += ((j + 1.0) * 10.0 + (j - 1.5) * 0.01 * k.array()).matrix();
  const Eigen::MatrixXd y = detrend(x, TrendType::linear);
  const Eigen::VectorXd ramp = k.array() - 0.5 * (n - 1);
  for (Eigen::Index j = 0; j < 4; ++j) {
    EXPECT_NEAR(y.col(j).sum(), 0.0, 1e-8) << j;
    EXPECT_NEAR(ramp.dot(y.col(j)), 0.0, 1e-5) << j;  // |ramp| |y| ~ 2e5 * 70: relative 1e-13
    // Removing 2 fitted parameters from white noise leaves a residual of variance ~ (N-2)/N of the
    // noise's; it differs from e only by e's own (small) projection on {1, ramp}: |y - e| ~ O(1/sqrt(N)).
    EXPECT_LT((y.col(j) - e.col(j)).cwiseAbs().maxCoeff(), 0.1) << j;
  }
}

TEST(SignalDetrend, ConstantRemovesOnlyTheMean) {
  const Eigen::Index n = 200;
  const Eigen::VectorXd k = Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1));
  Eigen::MatrixXd x(n, 2);
  x.col(0) = (5.0 + k.array()).matrix();
  x.col(1) = noise(n, 1, 3).col(0).array() - 2.0;
  const Eigen::MatrixXd y = detrend(x, TrendType::constant);
  EXPECT_NEAR(y.col(0).sum(), 0.0, 1e-9);
  EXPECT_NEAR(y.col(1).sum(), 0.0, 1e-12);
  // The slope survives a constant detrend: first and last samples still differ by N-1.
  EXPECT_NEAR(y(n - 1, 0) - y(0, 0), static_cast<double>(n - 1), 1e-12);
  EXPECT_EQ(trend_coefficients(x, TrendType::constant)(1, 0), 0.0);
}

TEST(SignalDetrend, Preconditions) {
  EXPECT_THROW(detrend(Eigen::MatrixXd(0, 2), TrendType::constant), std::invalid_argument);
  EXPECT_THROW(detrend(Eigen::MatrixXd::Ones(1, 2), TrendType::linear), std::invalid_argument);
  EXPECT_NO_THROW(detrend(Eigen::MatrixXd::Ones(1, 2), TrendType::constant));
  EXPECT_EQ(parse_trend_type("linear"), TrendType::linear);
  EXPECT_EQ(parse_trend_type("constant"), TrendType::constant);
  EXPECT_THROW(parse_trend_type("quadratic"), std::invalid_argument);
}

}  // namespace test_unit_signal_detrend
