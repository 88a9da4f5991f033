// Tests of core/flush_subnormals.hpp: the guard flushes subnormal results and
// operands to zero in its scope, restores the caller's mode on exit (nested, on
// an exception), and touches only its own thread.
#include <sysid/core/flush_subnormals.hpp>

#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>
#include <future>
#include <thread>

#include "subnormals.hpp"

namespace test_unit_core_flush_subnormals {

// volatile: the compiler must not fold the arithmetic at compile time, where the
// run-time mode does not apply.
double halved_smallest_normal() {
  volatile double smallest = std::numeric_limits<double>::min();
  volatile double half = 0.5;
  return smallest * half;
}

double subnormal_times_one() {
  volatile double subnormal = std::numeric_limits<double>::denorm_min() * 1024.0;
  volatile double one = 1.0;
  return subnormal * one;
}

using sysid::test::flushing_subnormals;

class FlushSubnormals : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!sysid::ScopedFlushSubnormals::supported()) GTEST_SKIP() << "no flush-to-zero mode on this target";
    ASSERT_FALSE(flushing_subnormals()) << "the test process must start in IEEE mode";
  }
};

TEST_F(FlushSubnormals, FlushesResultsAndOperandsInScopeOnly) {
  EXPECT_GT(halved_smallest_normal(), 0.0);
  EXPECT_GT(subnormal_times_one(), 0.0);
  {
    const sysid::ScopedFlushSubnormals flush;
    EXPECT_EQ(halved_smallest_normal(), 0.0);  // a subnormal result (FTZ)
    EXPECT_EQ(subnormal_times_one(), 0.0);     // a subnormal operand (DAZ / FZ)
    volatile double normal = 3.0 * std::numeric_limits<double>::min();
    EXPECT_EQ(normal * 2.0, 6.0 * std::numeric_limits<double>::min());  // normal numbers untouched
  }
  EXPECT_GT(halved_smallest_normal(), 0.0);
}

TEST_F(FlushSubnormals, NestedGuardsRestoreTheOuterMode) {
  {
    const sysid::ScopedFlushSubnormals outer;
    {
      const sysid::ScopedFlushSubnormals inner;
      EXPECT_TRUE(flushing_subnormals());
    }
    EXPECT_TRUE(flushing_subnormals());  // the inner guard restored the outer's (flushing) mode
  }
  EXPECT_FALSE(flushing_subnormals());
}

TEST_F(FlushSubnormals, AnExceptionRestoresTheMode) {
  EXPECT_THROW(
      {
        const sysid::ScopedFlushSubnormals flush;
        throw std::runtime_error("leaving the scope");
      },
      std::runtime_error);
  EXPECT_FALSE(flushing_subnormals());
}

TEST_F(FlushSubnormals, OtherThreadsKeepTheirMode) {
  // A thread already running keeps its mode while this one flushes. (A thread
  // started inside the scope inherits the mode on Linux: none is, in the library.)
  std::promise<void> guard_taken;
  std::promise<bool> other_flushing;
  std::thread other([&] {
    guard_taken.get_future().wait();
    other_flushing.set_value(flushing_subnormals());
  });
  {
    const sysid::ScopedFlushSubnormals flush;
    guard_taken.set_value();
    EXPECT_FALSE(other_flushing.get_future().get());
    EXPECT_TRUE(flushing_subnormals());
  }
  other.join();
}

}  // namespace test_unit_core_flush_subnormals
