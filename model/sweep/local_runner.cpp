// The local runner: every job not done, -j at a time as subprocesses of this machine; traces
// first, points as their traces appear, comparisons when both sides are done; a progress line
// with an ETA; SIGINT/SIGTERM stop it cleanly.
#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <set>
#include <thread>

#include <fmt/format.h>

#include "sweep/detail.h"
#include "sweep/jobs.h"
#include "sweep/progress.h"
#include "visibility/parallel.h"

namespace tilevis::sweep {

namespace fs = std::filesystem;
using namespace detail;

namespace {

// One sweep at a time per output folder: an exclusive flock on OUT/.sweep.lock, held until the
// run ends. Its descriptor is inherited by the points (no close-on-exec), so should a point
// outlive its sweep, a re-run is refused instead of starting the same point in the same folder.
class FolderLock {
 public:
  explicit FolderLock(const fs::path& out) {
    std::error_code ec;
    fs::create_directories(out, ec);
    const fs::path file = out / ".sweep.lock";
    m_fd = open(file.c_str(), O_RDWR | O_CREAT, 0644);
    if (m_fd < 0) throw SweepError(fmt::format("cannot open {}: {}", file.string(), std::strerror(errno)));
    if (flock(m_fd, LOCK_EX | LOCK_NB) != 0) {
      const int e = errno;
      close(m_fd);
      if (e == EWOULDBLOCK)
        throw SweepError(fmt::format("{} is in use by another sweep, or by points of a sweep that was killed and "
                                     "are still running: wait for them to end (they hold {})",
                                     out.string(), file.string()));
      throw SweepError(fmt::format("cannot lock {}: {}", file.string(), std::strerror(e)));
    }
  }
  ~FolderLock() { close(m_fd); }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int m_fd = -1;
};


std::atomic<int> g_stop_signal{0};
void on_stop_signal(int sig) { g_stop_signal = sig; }

// SIGINT and SIGTERM set g_stop_signal while it lives.
class StopSignals {
 public:
  StopSignals() {
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0;
    g_stop_signal = 0;
    sigaction(SIGINT, &sa, &m_old_int);
    sigaction(SIGTERM, &sa, &m_old_term);
  }
  ~StopSignals() {
    sigaction(SIGINT, &m_old_int, nullptr);
    sigaction(SIGTERM, &m_old_term, nullptr);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

 private:
  struct sigaction m_old_int {}, m_old_term {};
};

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

class LocalRunner {
 public:
  LocalRunner(const Sweep& sw, const Plan& plan, std::map<std::string, Availability>& av, const RunOptions& opt)
      : m_plan(plan), m_av(av), m_opt(opt), m_jobs(make_jobs(sw, plan, opt.out, opt.tilevis)),
        m_ctx{source_commit(), machine_info()} {
    for (Job& j : m_jobs)
      if (j.kind == Job::Kind::point && j.state == JobState::pending && !av.at(j.producer).available)
        j.state = JobState::unavailable;
    m_sum.total = m_jobs.size();
    for (const Job& j : m_jobs) m_sum.already_done += j.state == JobState::done;
    // Each job's share of the CPUs for its host threads (vis::host_threads), unless the user
    // chose: `jobs` processes each with every CPU's worth of threads would oversubscribe them.
    if (!std::getenv("TILEVIS_THREADS"))
      m_env.push_back(fmt::format("TILEVIS_THREADS={}", std::max(1u, vis::host_threads() / std::max(1u, opt.jobs))));
  }

  RunSummary run() {
    const StopSignals signals;
    report(m_sum.already_done ? fmt::format("{} already done", m_sum.already_done) : "");
    while (!g_stop_signal) {
      start_ready();
      if (m_running == 0) break;
      if (!reap_one()) break;
    }
    if (g_stop_signal) stop_running();
    for (const Job& j : m_jobs) {
      m_sum.failed += j.state == JobState::failed;
      m_sum.unavailable += j.state == JobState::unavailable;
      m_sum.skipped += j.state == JobState::skipped;
    }
    m_sum.wall_seconds = seconds_since(m_t0);
    return m_sum;
  }

 private:
  // done when every dependency is; skipped when one failed or cannot run; else pending.
  JobState deps_state(const Job& j) const {
    bool all_done = true;
    for (size_t d : j.deps) {
      JobState s = m_jobs[d].state;
      if (s == JobState::failed || s == JobState::unavailable || s == JobState::skipped) return JobState::skipped;
      all_done = all_done && s == JobState::done;
    }
    return all_done ? JobState::done : JobState::pending;
  }

  // The jobs whose dependencies are done, the largest first (traces before anything else).
  std::vector<size_t> ready_jobs() {
    std::vector<size_t> ready;
    for (size_t i = 0; i < m_jobs.size(); ++i) {
      Job& j = m_jobs[i];
      if (j.state != JobState::pending) continue;
      JobState d = deps_state(j);
      if (d == JobState::skipped) j.state = JobState::skipped;
      else if (d == JobState::done) ready.push_back(i);
    }
    std::stable_sort(ready.begin(), ready.end(), [&](size_t a, size_t b) {
      if ((m_jobs[a].kind == Job::Kind::trace) != (m_jobs[b].kind == Job::Kind::trace))
        return m_jobs[a].kind == Job::Kind::trace;
      return m_jobs[a].work > m_jobs[b].work;
    });
    return ready;
  }

  void start_ready() {
    for (size_t i : ready_jobs()) {
      if (m_running >= m_opt.jobs) break;
      Job& j = m_jobs[i];
      if (!j.exclusive.empty() && m_held.count(j.exclusive)) continue;
      Spawned s = start_job(j, m_env);
      if (s.pid < 0) {
        j.state = JobState::failed;
        m_sum.failures.push_back(fmt::format("{}: {}", j.label, s.error));
        continue;
      }
      j.pid = s.pid;
      j.state = JobState::running;
      j.started = Clock::now();
      if (!j.exclusive.empty()) m_held.insert(j.exclusive);
      ++m_running;
    }
  }

  // Waits for one job to end (refreshing the progress line every second); false when there
  // is nothing left to wait for.
  bool reap_one() {
    int status = 0;
    rusage ru{};
    pid_t pid = wait4(-1, &status, WNOHANG, &ru);
    if (pid == 0 || (pid < 0 && errno == EINTR)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      if (Clock::now() - m_last_report > std::chrono::seconds(1)) report("");
      return true;
    }
    if (pid < 0) return false;
    auto it = std::find_if(m_jobs.begin(), m_jobs.end(),
                           [&](const Job& j) { return j.pid == pid && j.state == JobState::running; });
    if (it != m_jobs.end()) on_ended(*it, status, ru);
    return true;
  }

  void on_ended(Job& j, int status, const rusage& ru) {
    --m_running;
    m_held.erase(j.exclusive);
    j.pid = -1;
    const double wall = seconds_since(j.started);
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    const bool unavailable = code == 2 && j.kind == Job::Kind::point && !point_done(m_plan.points[j.index], m_opt.out);
    if (code != 0 && !unavailable && (g_stop_signal || (WIFSIGNALED(status) && WTERMSIG(status) == SIGINT))) {
      // Ctrl-C reaches the whole process group: the job was interrupted with the sweep
      // (perhaps reaped before our own handler ran) and runs again next time.
      if (!g_stop_signal) g_stop_signal = SIGINT;
      j.state = JobState::pending;
      report("");
      return;
    }
    const Finished f = finish_job(m_plan, j, status, ru, wall, m_opt.out, m_ctx);
    j.state = f.state;
    if (f.state == JobState::done) {
      ++m_sum.ran;
      m_eta.add(j.producer, wall, j.work);
    } else if (f.state == JobState::unavailable) {
      mark_producer_unavailable(j.producer, f.why);
    } else {
      m_sum.failures.push_back(f.failure);
    }
    report(f.event);
  }

  void mark_producer_unavailable(const std::string& producer, const std::string& why) {
    m_av[producer].available = false;
    m_av[producer].why = why;
    for (Job& k : m_jobs)
      if (k.kind == Job::Kind::point && k.producer == producer && k.state == JobState::pending)
        k.state = JobState::unavailable;
  }

  // Terminates the running jobs; their points have no stats.json and run again next time.
  void stop_running() {
    m_sum.interrupted = true;
    for (Job& j : m_jobs)
      if (j.state == JobState::running && j.pid > 0) kill(j.pid, SIGTERM);
    for (Job& j : m_jobs)
      if (j.state == JobState::running && j.pid > 0) {
        int status = 0;
        while (waitpid(j.pid, &status, 0) < 0 && errno == EINTR) {
        }
        j.state = JobState::pending;
      }
  }

  std::string status_line(const std::string& event) const {
    size_t finished = 0, running = 0;
    double remaining = 0;
    bool known = true;
    for (const Job& j : m_jobs) {
      if (j.state != JobState::pending && j.state != JobState::running) {
        ++finished;
        continue;
      }
      double e = m_eta.estimate(j.producer, j.work);
      if (e < 0) known = false;
      if (j.state == JobState::running) {
        ++running;
        e -= seconds_since(j.started);
      }
      remaining += std::max(e, 0.0);
    }
    const double eta = known ? remaining / std::max(1u, m_opt.jobs) : -1.0;
    return progress_line(finished, m_jobs.size(), seconds_since(m_t0), eta, running, event);
  }

  void report(const std::string& event) {
    m_last_report = Clock::now();
    if (m_opt.progress) m_opt.progress(status_line(event), !event.empty());
  }

  const Plan& m_plan;
  std::map<std::string, Availability>& m_av;
  const RunOptions& m_opt;
  const Clock::time_point m_t0 = Clock::now();
  std::vector<Job> m_jobs;
  const RunContext m_ctx;
  RunSummary m_sum;
  EtaModel m_eta;
  std::set<std::string> m_held;  // exclusive resources in use
  std::vector<std::string> m_env;  // set in every job's environment
  size_t m_running = 0;
  Clock::time_point m_last_report = Clock::now();
};

}  // namespace

RunSummary run_plan(const Sweep& sw, const Plan& plan, std::map<std::string, Availability>& av, const RunOptions& opt) {
  const FolderLock lock(opt.out);
  return LocalRunner(sw, plan, av, opt).run();
}

}  // namespace tilevis::sweep
