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
/// which has parallel pieces of its own).
///
/// Threads: the helpers are started once, on the first parallel_for, and kept
/// (detail::HelperPool): a parallel region then costs a wake-up, not a thread
/// start (~30 us on the 2-core CI machine; n4sid has seven regions of 0.1-2 ms).
/// After a region a helper polls for the next one for ~100 us before it
/// sleeps. Regions from several user threads at once do not queue: a caller
/// that finds the helpers busy runs its loop on fresh threads as before.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
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

/// hardware_concurrency() - 1 threads that run one job at a time beside its
/// caller (see Threads above). Joined at exit.
class HelperPool {
 public:
  static HelperPool& instance() {
    static HelperPool pool;
    return pool;
  }

  std::size_t helpers() const { return m_threads.size(); }

  /// Runs `job` on `count` <= helpers() helpers and on the caller, and returns
  /// when every one has returned; `job` must not throw. False, with nothing
  /// run, when another thread's job is using the helpers.
  bool run(std::size_t count, const std::function<void()>& job) {
    std::unique_lock<std::mutex> use(m_use, std::try_to_lock);
    if (!use.owns_lock()) return false;
    {
      std::lock_guard<std::mutex> lock(m_mutex);
      m_job = &job;
      m_wanted = std::min(count, m_threads.size());
      m_claimed = m_finished = 0;
      m_generation.fetch_add(1, std::memory_order_release);
    }
    m_wake.notify_all();
    job();
    std::unique_lock<std::mutex> lock(m_mutex);
    m_done.wait(lock, [this] { return m_finished == m_wanted; });
    m_job = nullptr;
    return true;
  }

  HelperPool(const HelperPool&) = delete;
  HelperPool& operator=(const HelperPool&) = delete;

  ~HelperPool() {
    {
      std::lock_guard<std::mutex> lock(m_mutex);
      m_stop = true;
      m_generation.fetch_add(1, std::memory_order_release);
    }
    m_wake.notify_all();
    for (std::thread& t : m_threads) t.join();
  }

 private:
  HelperPool() {
    const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
    for (unsigned t = 1; t < cores; ++t) m_threads.emplace_back([this] { serve(); });
  }

  void serve() {
    std::uint64_t seen = 0;
    for (;;) {
      // Poll briefly (regions often follow each other within ~0.1 ms), then sleep.
      const auto poll_until = std::chrono::steady_clock::now() + std::chrono::microseconds(100);
      while (m_generation.load(std::memory_order_acquire) == seen && std::chrono::steady_clock::now() < poll_until)
        std::this_thread::yield();
      std::unique_lock<std::mutex> lock(m_mutex);
      m_wake.wait(lock, [&] { return m_generation.load(std::memory_order_relaxed) != seen; });
      seen = m_generation.load(std::memory_order_relaxed);
      if (m_stop) return;
      if (m_claimed >= m_wanted) continue;
      ++m_claimed;
      const std::function<void()>* job = m_job;
      lock.unlock();
      (*job)();
      lock.lock();
      if (++m_finished == m_wanted) m_done.notify_one();
    }
  }

  std::mutex m_use;    // one job at a time
  std::mutex m_mutex;  // guards everything below but m_generation's polling
  std::condition_variable m_wake, m_done;
  std::atomic<std::uint64_t> m_generation{0};
  const std::function<void()>* m_job = nullptr;
  std::size_t m_wanted = 0, m_claimed = 0, m_finished = 0;
  bool m_stop = false;
  std::vector<std::thread> m_threads;
};
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
  if (workers > 1) {
    detail::HelperPool& pool = detail::HelperPool::instance();
    const std::function<void()> job = work;
    if (workers - 1 > pool.helpers() || !pool.run(workers - 1, job)) {
      std::vector<std::thread> threads;
      for (std::size_t t = 1; t < workers; ++t) threads.emplace_back(work);
      work();
      for (auto& t : threads) t.join();
    }
  } else {
    work();
  }
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
