// Tests of subspace/order_selection.hpp: Bartlett's test of zero canonical
// correlations (its level on independent data, its power on dependent data), the
// sequential canonical-correlation order test (its level, its count of planted
// directions, its report) and when SVC is swamped. The rules are exercised on
// identified systems through n4sid (subspace_n4sid.cpp) and on a structure with
// many sensors (acceptance/subspace_many_sensors.cpp).
#include <sysid/subspace/n4sid.hpp>
#include <sysid/subspace/order_selection.hpp>

#include <gtest/gtest.h>

#include <stdexcept>

#include "random_matrices.hpp"

namespace test_unit_subspace_order_selection {

using sysid::test::canonical_correlations;

TEST(BartlettTest, LevelOnIndependentSetsIsNearNominal) {
  // 300 pairs of independent 4- and 6-dimensional Gaussian sets of 200 samples:
  // rejections at 1 % are binomial(300, 0.01), mean 3; 10 or more has
  // probability below 1e-3 if the level holds.
  int rejected = 0;
  for (std::uint64_t trial = 0; trial < 300; ++trial) {
    const Eigen::MatrixXd x = sysid::test::white_noise(200, 4, 1000 + trial);
    const Eigen::MatrixXd y = sysid::test::white_noise(200, 6, 5000 + trial);
    const auto t = sysid::bartlett_zero_correlation_test(canonical_correlations(x, y), 200, 4, 6);
    ASSERT_TRUE(t.valid);
    EXPECT_EQ(t.dof, 24.0);
    if (t.p_value < 0.01) ++rejected;
  }
  EXPECT_LT(rejected, 10);
}

TEST(BartlettTest, FindsAWeakCorrelationInOneDirection) {
  // y's first column carries 0.3 of x's first: correlation about 0.29, which
  // 500 samples resolve (statistic about 500 * 0.09 = 45 on 24 dof).
  const Eigen::MatrixXd x = sysid::test::white_noise(500, 4, 11);
  Eigen::MatrixXd y = sysid::test::white_noise(500, 6, 12);
  y.col(0) += 0.3 * x.col(0);
  const auto t = sysid::bartlett_zero_correlation_test(canonical_correlations(x, y), 500, 4, 6);
  EXPECT_LT(t.p_value, 1e-3);
}

TEST(BartlettTest, TooFewSamplesIsNotValidAndBadSizesThrow) {
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(3, 0.5);
  EXPECT_FALSE(sysid::bartlett_zero_correlation_test(c, 8, 8, 8).valid);  // 8 - 1 - 8.5 < 0
  EXPECT_THROW(sysid::bartlett_zero_correlation_test(c, 10, 0, 3), std::invalid_argument);
  // A correlation of exactly 1 gives a finite statistic, not Inf or NaN.
  const auto t = sysid::bartlett_zero_correlation_test(Eigen::VectorXd::Ones(2), 100, 2, 2);
  EXPECT_TRUE(std::isfinite(t.statistic));
  EXPECT_LT(t.p_value, 1e-10);
}

/// `directions` planted correlations (0.9, 0.8, ... of x's first columns in y's)
/// between independent Gaussian sets of p and q variables over n samples.
Eigen::VectorXd planted_correlations(Eigen::Index n, Eigen::Index p, Eigen::Index q, int directions, std::uint64_t seed) {
  const Eigen::MatrixXd x = sysid::test::white_noise(n, p, seed);
  Eigen::MatrixXd y = sysid::test::white_noise(n, q, seed + 1);
  for (int k = 0; k < directions; ++k) y.col(k) += (3.0 - 0.5 * k) * x.col(k);
  return canonical_correlations(x, y);
}

TEST(CorrelationOrderTest, FindsNoOrderInIndependentSets) {
  // At level 1e-3 the first step is rejected by chance in 1 case of 1000: among 200
  // pairs of independent 20- and 30-dimensional sets, 3 or more is below 1e-3 likely.
  int false_orders = 0;
  for (std::uint64_t trial = 0; trial < 200; ++trial) {
    const auto r = planted_correlations(1000, 20, 30, 0, 100 + 2 * trial);
    if (sysid::choose_order_by_correlation_test(r, 19, 1000, 20, 30).order > 0) ++false_orders;
  }
  EXPECT_LT(false_orders, 3);
}

TEST(CorrelationOrderTest, CountsThePlantedDirectionsAndSaysHowClearly) {
  for (int planted : {1, 3, 5}) {
    const auto r = planted_correlations(1000, 20, 30, planted, 4242 + planted);
    const auto choice = sysid::choose_order_by_correlation_test(r, 19, 1000, 20, 30);
    EXPECT_EQ(choice.order, planted);
    EXPECT_GT(choice.score, 1.0);  // the last kept correlation over its noise level
    EXPECT_NE(choice.rule.find("r_" + std::to_string(planted) + " = "), std::string::npos) << choice.rule;
    EXPECT_NE(choice.rule.find("r_" + std::to_string(planted + 1) + " = "), std::string::npos) << choice.rule;
  }
  // Capped: every correlation up to the search limit stands out.
  const auto r = planted_correlations(1000, 20, 30, 5, 77);
  const auto capped = sysid::choose_order_by_correlation_test(r, 3, 1000, 20, 30);
  EXPECT_EQ(capped.order, 3);
  EXPECT_NE(capped.rule.find("the order may be higher"), std::string::npos) << capped.rule;
  EXPECT_THROW(sysid::choose_order_by_correlation_test(r, 3, 40, 20, 30), std::invalid_argument);
}

TEST(CorrelationOrderTest, SvcIsSwampedByManyOutputsOnly) {
  // 28 outputs, 2 inputs, 8 500 columns: SVC's penalty is 0.062 per order, so 24
  // orders cost 1.5; one output: 0.0032 per order.
  EXPECT_TRUE(sysid::svc_is_swamped(24, 8500, 28, 2));
  EXPECT_FALSE(sysid::svc_is_swamped(6, 8500, 28, 2));
  EXPECT_FALSE(sysid::svc_is_swamped(24, 8500, 1, 1));
  EXPECT_EQ(sysid::order_rule_from_name("test"), sysid::OrderRule::test);
  EXPECT_STREQ(sysid::to_string(sysid::order_rule_from_name("auto")), "auto");
  EXPECT_THROW(sysid::order_rule_from_name("aic"), std::invalid_argument);
}

TEST(CorrelationOrderTest, WhiteNoiseHankelDataStayBelowTheNoiseLevel) {
  // The calibration of kHankelScaleInflation, repeated on 40 records: the subspace
  // core's canonical correlations between independent white inputs (3) and
  // outputs (6), 1 000 samples, horizon 10. Without the widened scale the largest
  // exceeds the Tracy-Widom 0.1 % level in about 5 % of such records.
  for (std::uint64_t s = 0; s < 40; ++s) {
    const sysid::IoData d(sysid::test::white_noise(1000, 3, 1000 + 7 * s), sysid::test::white_noise(1000, 6, 5000 + 7 * s), 1.0);
    sysid::N4sidOptions o;
    o.order = 1;
    o.horizon = 10;
    o.refine_bdx = false;
    o.estimate_kalman_gain = false;
    const auto r = sysid::n4sid(d, o);
    // Columns 1000 - 2 * 10 + 1, less the 30 future-input rows projected out.
    const auto choice = sysid::choose_order_by_correlation_test(r.canonical_correlations, 59, 951, 60, 90);
    EXPECT_EQ(choice.order, 0) << "record " << s << ": " << choice.rule;
  }
}

}  // namespace test_unit_subspace_order_selection
