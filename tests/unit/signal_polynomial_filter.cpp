// filter_polynomial (signal/polynomial_filter.hpp) against the difference
// equation written out, and the impulse response of a first-order section.
#include <sysid/signal/polynomial_filter.hpp>

#include <sysid/core/flush_subnormals.hpp>

#include <gtest/gtest.h>

#include <cmath>

#include "random_systems.hpp"
#include "subnormals.hpp"

namespace test_unit_signal_polynomial_filter {

using namespace sysid;

TEST(PolynomialFilter, MatchesTheDifferenceEquation) {
  Eigen::VectorXd num(3), den(4);
  num << 0.5, -0.2, 0.1;
  den << 1.0, -1.2, 0.5, -0.1;
  const Eigen::MatrixXd x = test::white_noise(500, 2, 3);
  const Eigen::MatrixXd y = filter_polynomial(num, den, x);
  for (Eigen::Index c = 0; c < 2; ++c)
    for (Eigen::Index t = 0; t < 500; ++t) {
      double expected = 0;
      for (Eigen::Index k = 0; k < num.size(); ++k)
        if (t - k >= 0) expected += num(k) * x(t - k, c);
      for (Eigen::Index k = 1; k < den.size(); ++k)
        if (t - k >= 0) expected -= den(k) * y(t - k, c);
      ASSERT_NEAR(y(t, c), expected, 1e-12 * (1 + std::abs(expected)));
    }
}

TEST(PolynomialFilter, FirstOrderImpulseResponse) {
  Eigen::VectorXd impulse = Eigen::VectorXd::Zero(30);
  impulse(0) = 1.0;
  const Eigen::MatrixXd h = filter_polynomial(Eigen::VectorXd::Ones(1), Eigen::Vector2d(1.0, -0.5), impulse);
  for (Eigen::Index k = 0; k < 30; ++k) EXPECT_DOUBLE_EQ(h(k, 0), std::pow(0.5, static_cast<double>(k)));
}

TEST(PolynomialFilter, ImpulseResponseReachesZeroWithoutPassingThroughSubnormals) {
  // 1 / (1 - 0.5 q^-1) from an impulse: 0.5^k exactly while that is a normal
  // number, then zero (core/flush_subnormals.hpp: the recursion runs with
  // subnormals flushed, ~100 cycles an operation on Intel cores otherwise).
  if (!ScopedFlushSubnormals::supported()) GTEST_SKIP() << "no flush-to-zero mode on this target";
  Eigen::VectorXd impulse = Eigen::VectorXd::Zero(1200);
  impulse(0) = 1.0;
  const Eigen::MatrixXd h = filter_polynomial(Eigen::VectorXd::Ones(1), Eigen::Vector2d(1.0, -0.5), impulse);
  for (Eigen::Index k = 0; k <= 1022; ++k) ASSERT_EQ(h(k, 0), std::ldexp(1.0, -static_cast<int>(k))) << k;
  EXPECT_EQ(h.bottomRows(1200 - 1023).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_FALSE(sysid::test::flushing_subnormals());  // the caller's mode is restored
}

TEST(PolynomialFilter, MovingAverageAgreesWithTheRecursion) {
  // M = 1 takes the blocked convolution; M = [1, 0] the recursion. Both add the
  // same products in the same order, so they agree exactly (no FMA in either at
  // the project's portable flags; with -march=native to rounding), also across
  // the 2048-sample blocks and for records shorter than the order.
  const Eigen::MatrixXd x = Eigen::MatrixXd::Random(4100, 2);
  for (const Eigen::Index n : {Eigen::Index{3}, Eigen::Index{2047}, Eigen::Index{2049}, Eigen::Index{4100}})
    for (const int order : {0, 1, 32, 40}) {
      const Eigen::VectorXd num = Eigen::VectorXd::Random(order + 1);
      const Eigen::MatrixXd fast = filter_polynomial(num, Eigen::VectorXd::Ones(1), x.topRows(n));
      const Eigen::MatrixXd recursion = filter_polynomial(num, Eigen::Vector2d(1.0, 0.0), x.topRows(n));
      EXPECT_LE((fast - recursion).cwiseAbs().maxCoeff(), 1e-14 * recursion.cwiseAbs().maxCoeff())
          << "n " << n << " order " << order;
    }
}

TEST(PolynomialFilter, RejectsANonMonicDenominator) {
  EXPECT_THROW(filter_polynomial(Eigen::VectorXd::Ones(1), Eigen::Vector2d(2.0, 1.0), Eigen::VectorXd::Ones(5)),
               std::invalid_argument);
  EXPECT_THROW(filter_polynomial(Eigen::VectorXd(), Eigen::VectorXd::Ones(1), Eigen::VectorXd::Ones(5)), std::invalid_argument);
}

}  // namespace test_unit_signal_polynomial_filter
