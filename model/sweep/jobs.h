// The jobs of a plan (traces, points, comparisons) as the runners see them, and what running
// one means: the same for the local runner and for a Slurm array task, so that both leave the
// same outputs and the same process.json.
#pragma once

#include <sys/resource.h>
#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sweep/detail.h"
#include "sweep/sweep.h"

namespace tilevis::sweep::detail {

enum class JobState { pending, running, done, failed, unavailable, skipped };

struct Job {
  enum class Kind { trace, point, compare } kind = Kind::point;
  size_t index = 0;             // into plan.traces / points / compares
  std::string key;              // what names it across runs: the trace file, point or comparison directory
  std::string label, producer;  // producer: the ETA class ("trace", "compare" or the producer)
  std::string exclusive;        // the producer's exclusive resource, if any
  Command command;
  std::filesystem::path log;
  std::vector<size_t> deps;     // indices into the job list
  double work = 1;              // megasamples, for the ETA
  JobState state = JobState::pending;
  pid_t pid = -1;
  std::chrono::steady_clock::time_point started;
};

const char* to_string(Job::Kind kind);  // "traces", "points", "comparisons"

// Every job of the plan: traces, then points, then comparisons, each done or pending by its
// done marker (availability is the runner's business).
std::vector<Job> make_jobs(const Sweep& sw, const Plan& plan, const std::filesystem::path& out,
                           const std::string& tilevis);

// Recorded in every point's process.json.
struct RunContext {
  std::string commit;
  nlohmann::json machine;
};

// Makes a job's output directories and starts it, its output into its log; `env` as spawn()'s.
Spawned start_job(const Job& job, const std::vector<std::string>& env = {});

// What became of a job whose process ended with `status` (from wait4) after `wall` seconds:
// renames its outputs into place and writes the point's process.json when it succeeded.
struct Finished {
  JobState state = JobState::failed;
  std::string event;    // for the progress line
  std::string failure;  // for the summary, when failed
  std::string why;      // when unavailable: the producer's last words
};
Finished finish_job(const Plan& plan, const Job& job, int status, const rusage& ru, double wall,
                    const std::filesystem::path& out, const RunContext& ctx);

}  // namespace tilevis::sweep::detail
