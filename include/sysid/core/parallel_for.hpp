#pragma once
/// @file
/// Purpose: run independent pieces of work on the machine's cores, for the few
/// places where the library has them (diagnose's candidate fits, PEM's starts,
/// n4sid's projections and B/D/x0 regression).
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
///
/// Nesting: a parallel_for called from inside another one's body runs its
/// indices on the calling thread, in order (as OpenMP does with nesting off).
/// The outer loop already occupies the cores; more threads would only compete
/// for them (diagnose fits candidates in parallel, and each fit may call n4sid,
/// which has parallel pieces of its own). Starting a thread costs ~30 us here,
/// so the pieces given to it should be worth well over that.
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace sysid {

namespace detail {
/// True on a thread while it runs a parallel_for body (see Nesting above).
inline thread_local bool inside_parallel_for = false;
}  // namespace detail

inline void parallel_for(std::size_t count, const std::function<void(std::size_t)>& body) {
  const std::size_t workers = detail::inside_parallel_for
                                  ? 1
                                  : std::min<std::size_t>(count, std::max(1u, std::thread::hardware_concurrency()));
  std::atomic<std::size_t> next{0};
  std::exception_ptr failure;
  std::size_t failure_index = count;
  std::mutex failure_mutex;
  auto work = [&] {
    const bool was_inside = detail::inside_parallel_for;
    detail::inside_parallel_for = true;
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
    detail::inside_parallel_for = was_inside;
  };
  std::vector<std::thread> threads;
  for (std::size_t t = 1; t < workers; ++t) threads.emplace_back(work);
  work();
  for (auto& t : threads) t.join();
  if (failure) std::rethrow_exception(failure);
}

/// Runs each of `tasks` once, on the cores as parallel_for does (same error and
/// nesting rules; a task's index is its position in the list).
template <class... Task>
void parallel_invoke(Task&&... tasks) {
  const std::function<void()> list[] = {std::function<void()>(std::forward<Task>(tasks))...};
  parallel_for(sizeof...(Task), [&list](std::size_t k) { list[k](); });
}

}  // namespace sysid
