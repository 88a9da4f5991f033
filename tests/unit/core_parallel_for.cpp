// Tests of core/parallel_for.hpp: every index exactly once, nothing for an
// empty range, and the exception of the lowest failing index, after every
// other index has run.
#include <sysid/core/parallel_for.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

namespace test_unit_core_parallel_for {

TEST(ParallelFor, RunsEveryIndexExactlyOnce) {
  std::vector<std::atomic<int>> calls(1000);
  sysid::parallel_for(calls.size(), [&](std::size_t k) { ++calls[k]; });
  for (std::size_t k = 0; k < calls.size(); ++k) EXPECT_EQ(calls[k].load(), 1) << "index " << k;
}

TEST(ParallelFor, AnEmptyRangeRunsNothing) {
  int calls = 0;
  sysid::parallel_for(0, [&](std::size_t) { ++calls; });
  EXPECT_EQ(calls, 0);
}

TEST(ParallelFor, RethrowsTheLowestFailingIndexAfterTheOthersRan) {
  // Indices 3 and 7 fail, on whichever threads take them: the message must be
  // index 3's every time (repeated, since the scheduling varies).
  for (int repeat = 0; repeat < 20; ++repeat) {
    std::vector<std::atomic<int>> calls(64);
    try {
      sysid::parallel_for(calls.size(), [&](std::size_t k) {
        ++calls[k];
        if (k == 7 || k == 3) throw std::runtime_error("index " + std::to_string(k));
      });
      ADD_FAILURE() << "no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), "index 3");
    }
    for (std::size_t k = 0; k < calls.size(); ++k) EXPECT_EQ(calls[k].load(), 1) << "index " << k;
  }
}

}  // namespace test_unit_core_parallel_for
