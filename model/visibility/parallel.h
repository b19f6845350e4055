// Host threads for independent pieces of functional work (a frame's draws, say): plain
// std::thread, no pool. Results must not depend on the schedule, so each index writes only
// what belongs to it and the caller joins them in index order.
#pragma once

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#ifdef __linux__
#include <sched.h>
#endif
#include <thread>
#include <unordered_map>
#include <utility>
#include <vector>

namespace tilevis::vis {

// A positive count in environment variable `name`, else 0.
inline unsigned long env_count(const char* name) {
  const char* env = std::getenv(name);
  if (!env) return 0;
  char* end = nullptr;
  const unsigned long n = std::strtoul(env, &end, 10);
  return end != env && *end == '\0' ? n : 0;
}

// Threads to use: TILEVIS_THREADS when set to a positive number (1: everything on the calling
// thread), else the CPUs this process may run on (its affinity mask: what taskset, a Slurm
// task's binding or a container's cpuset leave it; the host's count where there is none), and
// inside a Slurm job at most the CPUs the job holds on its node (SLURM_CPUS_ON_NODE): without
// task binding every task's mask is the whole node, and the array tasks sharing it would each
// start a thread per CPU.
inline unsigned host_threads() {
  if (const unsigned long n = env_count("TILEVIS_THREADS")) return unsigned(std::min<unsigned long>(n, 1024));
  unsigned cpus = std::max(1u, std::thread::hardware_concurrency());
#ifdef __linux__
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0) cpus = unsigned(CPU_COUNT(&set));
#endif
  if (const unsigned long job = env_count("SLURM_CPUS_ON_NODE")) cpus = unsigned(std::min<unsigned long>(cpus, job));
  return cpus;
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

// Work done ahead of its consumer on other host threads. submit() queues keys in the order the
// consumer is expected to ask for them; take(key, result) hands over fn's result for a queued
// key: at once if a thread has finished it; if a thread is on it, once it is done, the caller
// computing later queued keys meanwhile; and computed on the calling thread if none has
// started it. A key not queued (or already taken) returns false: the
// caller computes it itself. At most `window` results are computed and not yet taken, so memory
// stays bounded whatever the consumer's pace. The consumer decides the order in which results
// are used, so whatever it sums from them has the same bits as without threads.
template <typename Result>
class Ahead {
 public:
  // fn(key, result, worker): `worker` is the thread, 0 .. threads - 1, or `threads` for the
  // caller of take(); each worker index is used by one thread at a time (its scratch). One
  // thread calls submit() and take().
  using Fn = std::function<void(uint32_t, Result&, unsigned)>;

  Ahead(unsigned threads, size_t window, Fn fn) : m_fn(std::move(fn)), m_window(window) {
    for (unsigned t = 0; t < threads; ++t) m_pool.emplace_back([this, t] { run(t); });
  }
  ~Ahead() {
    {
      std::lock_guard<std::mutex> lock(m_m);
      m_stop = true;
    }
    m_work.notify_all();
    for (std::thread& t : m_pool) t.join();
  }
  Ahead(const Ahead&) = delete;
  Ahead& operator=(const Ahead&) = delete;

  void submit(const std::vector<uint32_t>& keys) {
    {
      std::lock_guard<std::mutex> lock(m_m);
      for (uint32_t k : keys) {
        if (m_slot_of.count(k)) continue;  // already queued
        m_slot_of[k] = m_slots.size();
        m_slots.emplace_back().key = k;
      }
    }
    m_work.notify_all();
  }

  bool take(uint32_t key, Result& result) {
    std::unique_lock<std::mutex> lock(m_m);
    const auto it = m_slot_of.find(key);
    if (it == m_slot_of.end()) return false;
    Slot& s = m_slots[it->second];
    m_slot_of.erase(it);
    if (s.state == State::queued) {
      s.state = State::taken;
      lock.unlock();
      m_fn(key, result, caller());
      return true;
    }
    // A thread is on it: meanwhile the caller computes the next queued result, if any.
    while (s.state != State::done) {
      if (Slot* next = next_queued())
        compute(*next, caller(), lock);
      else
        m_done.wait(lock);
    }
    s.state = State::taken;
    result = std::move(s.result);
    s.result = Result{};
    const std::exception_ptr error = s.error;
    --m_ready;
    lock.unlock();
    m_work.notify_all();
    if (error) std::rethrow_exception(error);
    return true;
  }

 private:
  enum class State { queued, running, done, taken };
  struct Slot {
    uint32_t key = 0;
    State state = State::queued;
    Result result{};
    std::exception_ptr error;
  };

  unsigned caller() const { return unsigned(m_pool.size()); }  // the caller's worker index

  // The next queued slot a thread may start within the window (null: none), marked running.
  // Called with the lock held.
  Slot* next_queued() {
    while (m_next < m_slots.size() && m_ready + m_running < m_window) {
      Slot& s = m_slots[m_next++];
      if (s.state != State::queued) continue;  // the consumer took it first
      s.state = State::running;
      ++m_running;
      return &s;
    }
    return nullptr;
  }

  // Computes a slot marked running; `lock` is held on entry and on return.
  void compute(Slot& s, unsigned worker, std::unique_lock<std::mutex>& lock) {
    lock.unlock();
    Result r{};
    std::exception_ptr error;
    try {
      m_fn(s.key, r, worker);
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    s.result = std::move(r);
    s.error = error;
    s.state = State::done;
    --m_running;
    ++m_ready;
    m_done.notify_all();
  }

  void run(unsigned worker) {
    std::unique_lock<std::mutex> lock(m_m);
    for (;;) {
      m_work.wait(lock, [&] { return m_stop || (m_next < m_slots.size() && m_ready + m_running < m_window); });
      if (m_stop) return;
      if (Slot* s = next_queued()) compute(*s, worker, lock);
    }
  }

  Fn m_fn;
  size_t m_window;
  std::mutex m_m;
  std::condition_variable m_work, m_done;
  std::deque<Slot> m_slots;  // references stay valid as it grows
  std::unordered_map<uint32_t, size_t> m_slot_of;  // queued, not yet taken
  size_t m_next = 0, m_ready = 0, m_running = 0;
  bool m_stop = false;
  std::vector<std::thread> m_pool;  // last: started after everything above exists
};

}  // namespace tilevis::vis
