// Tests of core/median.hpp: odd and even counts, order independence, the one
// shared definition behind every robust statistic.
#include <sysid/core/median.hpp>

#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>
#include <vector>

namespace test_unit_core_median {

TEST(Median, OddCountIsTheMiddleValue) {
  EXPECT_DOUBLE_EQ(sysid::median({3.0, -1.0, 7.0}), 3.0);
  EXPECT_DOUBLE_EQ(sysid::median({5.0}), 5.0);
}

TEST(Median, EvenCountIsTheMeanOfTheTwoMiddleValues) {
  EXPECT_DOUBLE_EQ(sysid::median({4.0, 1.0, 3.0, 2.0}), 2.5);
  EXPECT_DOUBLE_EQ(sysid::median({-2.0, 10.0}), 4.0);
  // Repeated middle values.
  EXPECT_DOUBLE_EQ(sysid::median({1.0, 2.0, 2.0, 9.0}), 2.0);
}

TEST(Median, DoesNotDependOnOrderAndIgnoresOutliers) {
  std::vector<double> v;
  for (int k = 0; k < 101; ++k) v.push_back(static_cast<double>((k * 37) % 101));  // a permutation of 0..100
  EXPECT_DOUBLE_EQ(sysid::median(v), 50.0);
  v.back() = 1e300;
  v.front() = -1e300;
  EXPECT_DOUBLE_EQ(sysid::median(v), 50.0);
}

TEST(Median, EvenCountOfHugeValuesDoesNotOverflow) {
  // 0.5 * (a + b) overflowed to Inf for two values of 1e308 (found by fuzz.csv).
  const double big = 1e308;
  EXPECT_EQ(sysid::median({big, big}), big);
  const double max = std::numeric_limits<double>::max();
  EXPECT_EQ(sysid::median({max, max, -1.0, max}), max);
  EXPECT_EQ(sysid::median({-max, -max}), -max);
}

TEST(Median, EmptySetIsAnError) {
  EXPECT_THROW(sysid::median({}), std::invalid_argument);
}

}  // namespace test_unit_core_median
