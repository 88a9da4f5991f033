// Tests of core/parallel_for.hpp: every index exactly once, nothing for an
// empty range, the exception of the lowest failing index, after every other
// index has run; a nested loop runs on its caller's thread; parallel_invoke
// runs each task once; the kept helper threads serve many loops in a row and
// loops started from several user threads at once.
#include <sysid/core/parallel_for.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace test_unit_core_parallel_for {

TEST(ParallelFor, RunsEveryIndexExactlyOnce) {
  std::vector<std::atomic<int>> calls(1000);
  sysid::parallel_for(calls.size(), [&](std::size_t k) { ++calls[k]; });
  for (std::size_t k = 0; k < calls.size(); ++k) EXPECT_EQ(calls[k].load(), 1) << "index " << k;
}

TEST(ParallelFor, KeptHelpersServeManyLoopsInARow) {
  // Thousands of short regions (each a wake-up of the kept helpers): every
  // index of every loop exactly once, and no region is lost or merged.
  for (int loop = 0; loop < 2000; ++loop) {
    std::vector<std::atomic<int>> calls(3);
    sysid::parallel_for(calls.size(), [&](std::size_t k) { ++calls[k]; });
    for (std::size_t k = 0; k < calls.size(); ++k) ASSERT_EQ(calls[k].load(), 1) << "loop " << loop << " index " << k;
  }
}

TEST(ParallelFor, LoopsFromSeveralUserThreadsAtOnceAllComplete) {
  // Four user threads each run loops: one at a time gets the kept helpers,
  // the others start their own threads; every index of every loop runs once.
  std::vector<std::thread> users;
  std::atomic<int> wrong{0};
  for (int u = 0; u < 4; ++u)
    users.emplace_back([&] {
      for (int loop = 0; loop < 200; ++loop) {
        std::vector<std::atomic<int>> calls(16);
        sysid::parallel_for(calls.size(), [&](std::size_t k) { ++calls[k]; });
        for (auto& c : calls)
          if (c.load() != 1) ++wrong;
      }
    });
  for (auto& t : users) t.join();
  EXPECT_EQ(wrong.load(), 0);
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

TEST(ParallelFor, ANestedLoopRunsInOrderOnItsCallersThread) {
  std::vector<std::vector<std::size_t>> order(4);
  std::vector<int> other_thread(4, 0);
  sysid::parallel_for(order.size(), [&](std::size_t outer) {
    const std::thread::id caller = std::this_thread::get_id();
    sysid::parallel_for(50, [&](std::size_t inner) {
      order[outer].push_back(inner);  // unsynchronised: safe only if the inner loop is sequential
      if (std::this_thread::get_id() != caller) ++other_thread[outer];
    });
  });
  for (std::size_t outer = 0; outer < order.size(); ++outer) {
    EXPECT_EQ(other_thread[outer], 0);
    ASSERT_EQ(order[outer].size(), 50u);
    for (std::size_t k = 0; k < 50; ++k) EXPECT_EQ(order[outer][k], k);
  }
  // After the nested loops, a top-level loop uses the cores again (the flag is restored).
  std::atomic<int> calls{0};
  sysid::parallel_for(8, [&](std::size_t) { ++calls; });
  EXPECT_EQ(calls.load(), 8);
}

TEST(ParallelInvoke, RunsEachTaskOnceAndRethrowsTheFirstFailingTask) {
  int a = 0, b = 0, c = 0;
  sysid::parallel_invoke([&] { ++a; }, [&] { ++b; }, [&] { ++c; });
  EXPECT_EQ(a + 10 * b + 100 * c, 111);
  try {
    sysid::parallel_invoke([] {}, [] { throw std::runtime_error("second"); }, [] { throw std::runtime_error("third"); });
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "second");
  }
}

}  // namespace test_unit_core_parallel_for
