// Host threads for independent pieces of functional work (a frame's draws, say): plain
// std::thread, no pool. Results must not depend on the schedule, so each index writes only
// what belongs to it and the caller joins them in index order.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace tilevis::vis {

// Threads to use: TILEVIS_THREADS when set to a positive number (1: everything on the calling
// thread), else what the host offers.
inline unsigned host_threads() {
  if (const char* env = std::getenv("TILEVIS_THREADS")) {
    char* end = nullptr;
    const unsigned long n = std::strtoul(env, &end, 10);
    if (end != env && *end == '\0' && n > 0) return unsigned(std::min<unsigned long>(n, 1024));
  }
  return std::max(1u, std::thread::hardware_concurrency());
}

// Runs fn(i, scratch) for every i in [0, n) on up to host_threads() threads, each with a
// Scratch of its own; an index goes to whichever thread is free. If any call throws, the
// exception of the lowest such index is rethrown once every thread is done.
template <typename Scratch, typename Fn>
void for_each_index(size_t n, Fn&& fn) {
  const size_t threads = std::min<size_t>(host_threads(), n);
  std::atomic<size_t> next{0};
  std::mutex m;
  size_t failed_at = n;
  std::exception_ptr error;
  auto work = [&] {
    Scratch scratch;
    for (size_t i; (i = next.fetch_add(1)) < n;) {
      try {
        fn(i, scratch);
      } catch (...) {
        std::lock_guard<std::mutex> lock(m);
        if (i < failed_at) failed_at = i, error = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (size_t t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace tilevis::vis
