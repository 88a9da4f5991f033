// Tests of core/ljung_box.hpp: the statistic against its formula, the test's
// size on white noise (rejections near the nominal level), its power on a
// coloured series, and bad arguments rejected.
#include <sysid/core/ljung_box.hpp>

#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

namespace test_unit_core_ljung_box {

using namespace sysid;

namespace {

/// Biased normalised sample autocorrelation r(0..lags) of x (mean removed).
Eigen::VectorXd autocorrelation(Eigen::VectorXd x, Eigen::Index lags) {
  x.array() -= x.mean();
  Eigen::VectorXd r(lags + 1);
  for (Eigen::Index k = 0; k <= lags; ++k) r(k) = x.head(x.size() - k).dot(x.tail(x.size() - k));
  return r / r(0);
}

Eigen::VectorXd gaussian(Eigen::Index n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::VectorXd x(n);
  for (Eigen::Index t = 0; t < n; ++t) x(t) = normal(rng);
  return x;
}

}  // namespace

TEST(LjungBox, StatisticIsTheFormula) {
  Eigen::VectorXd r(3);
  r << 1.0, 0.1, -0.2;
  const LjungBoxTest t = ljung_box_test(r, 100, 2, 1);
  EXPECT_NEAR(t.statistic, 100.0 * 102.0 * (0.01 / 99.0 + 0.04 / 98.0), 1e-12);
  EXPECT_EQ(t.degrees_of_freedom, 1.0);
  EXPECT_EQ(t.samples, 100);
  EXPECT_EQ(t.lags, 2);
  // chi2(1) survival at Q: erfc(sqrt(Q / 2)).
  EXPECT_NEAR(t.p_value, std::erfc(std::sqrt(t.statistic / 2.0)), 1e-10);
}

TEST(LjungBox, WhiteNoiseIsRejectedAtAboutTheNominalRate) {
  // 400 white series of 1 000 samples, 20 lags, level 5 %: the count of
  // rejections is binomial(400, 0.05), mean 20, sd 4.4.
  int rejected = 0;
  for (unsigned seed = 0; seed < 400; ++seed)
    if (ljung_box_test(autocorrelation(gaussian(1000, seed), 20), 1000, 20, 0).p_value < 0.05) ++rejected;
  EXPECT_GE(rejected, 7);
  EXPECT_LE(rejected, 35);
}

TEST(LjungBox, ColouredSeriesIsRejected) {
  Eigen::VectorXd x = gaussian(2000, 7);
  for (Eigen::Index t = 1; t < x.size(); ++t) x(t) += 0.3 * x(t - 1);
  EXPECT_LT(ljung_box_test(autocorrelation(x, 20), 2000, 20, 0).p_value, 1e-10);
}

TEST(LjungBox, BadArgumentsAreRejected) {
  const Eigen::VectorXd r = Eigen::VectorXd::Ones(5);
  EXPECT_THROW(ljung_box_test(r, 100, 0, 0), std::invalid_argument);
  EXPECT_THROW(ljung_box_test(r, 100, 5, 0), std::invalid_argument);   // r has lags 0..4 only
  EXPECT_THROW(ljung_box_test(r, 4, 4, 0), std::invalid_argument);     // lags >= samples
  EXPECT_THROW(ljung_box_test(r, 100, 4, 4), std::invalid_argument);   // no degrees of freedom left
  EXPECT_THROW(ljung_box_test(r, 100, 4, -1), std::invalid_argument);
}

}  // namespace test_unit_core_ljung_box
