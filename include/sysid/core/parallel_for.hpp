#pragma once
/// @file
/// Purpose: run independent pieces of work on the machine's cores, for the few
/// places where the library has them (diagnose's candidate fits, PEM's starts).
///
/// Method: up to std::thread::hardware_concurrency() workers (the caller is one
/// of them) take the indices 0..count-1 from an atomic counter, so uneven pieces
/// balance themselves. Every body(k) runs exactly once; the results must go to
/// per-index storage (no shared mutable state), which keeps the outcome the same
/// as a sequential loop's whatever the scheduling.
///
/// Errors: the exception of the lowest index that threw is rethrown after all
/// workers have joined (the other indices still run): the same one whatever the
/// scheduling, the one a sequential loop would have thrown first.
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace sysid {

inline void parallel_for(std::size_t count, const std::function<void(std::size_t)>& body) {
  const std::size_t workers = std::min<std::size_t>(count, std::max(1u, std::thread::hardware_concurrency()));
  std::atomic<std::size_t> next{0};
  std::exception_ptr failure;
  std::size_t failure_index = count;
  std::mutex failure_mutex;
  auto work = [&] {
    for (std::size_t k = next++; k < count; k = next++) {
      try {
        body(k);
      } catch (...) {
        std::lock_guard<std::mutex> lock(failure_mutex);
        if (k < failure_index) {
          failure = std::current_exception();
          failure_index = k;
        }
      }
    }
  };
  std::vector<std::thread> threads;
  for (std::size_t t = 1; t < workers; ++t) threads.emplace_back(work);
  work();
  for (auto& t : threads) t.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace sysid
