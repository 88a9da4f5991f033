// Tests of subspace/order_selection.hpp: Bartlett's test of zero canonical
// correlations (its level on independent data, its power on dependent data).
// The SVC and gap rules are exercised through n4sid (subspace_n4sid.cpp).
#include <sysid/subspace/order_selection.hpp>

#include <gtest/gtest.h>

#include <stdexcept>

#include "random_matrices.hpp"

namespace test_unit_subspace_order_selection {

/// Canonical correlations between the columns of x and y (singular values of
/// Qx^T Qy from thin QRs).
Eigen::VectorXd canonical_correlations(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y) {
  const Eigen::MatrixXd qx = Eigen::HouseholderQR<Eigen::MatrixXd>(x).householderQ() * Eigen::MatrixXd::Identity(x.rows(), x.cols());
  const Eigen::MatrixXd qy = Eigen::HouseholderQR<Eigen::MatrixXd>(y).householderQ() * Eigen::MatrixXd::Identity(y.rows(), y.cols());
  return Eigen::JacobiSVD<Eigen::MatrixXd>(qx.transpose() * qy).singularValues();
}

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

}  // namespace test_unit_subspace_order_selection
