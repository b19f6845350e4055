// Helpers shared by the parts of the sweep engine (not part of its interface): words and
// quoting, subprocesses, files written atomically, durations.
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sweep/sweep.h"

namespace tilevis::sweep::detail {

std::vector<std::string> split_words(const std::string& text);
std::string replace_all(std::string s, const std::string& from, const std::string& to);
std::string shell_quote(const std::string& s);

struct Spawned {
  pid_t pid = -1;
  std::string error;
};

// Starts argv with stdin from /dev/null and stdout + stderr into `log`; the child dies with
// its parent (PR_SET_PDEATHSIG). `env`: "NAME=value" entries set in the child's environment
// (replacing the parent's of the same names).
Spawned spawn(const std::vector<std::string>& argv, const std::filesystem::path& log,
              const std::vector<std::string>& env = {});

// Runs argv to completion; its stdout and stderr in `output`. Returns the exit status (-1: not run).
int run_capture(const std::vector<std::string>& argv, std::string* output);

std::string last_line(const std::filesystem::path& file);
std::string last_line_of_text(const std::string& text);
std::string now_iso();
void write_json_atomically(const std::filesystem::path& file, const nlohmann::json& j);
// A JSON file, or null when it is missing or unreadable.
nlohmann::json read_json_or_null(const std::filesystem::path& file);
std::string duration_text(double seconds);  // "m:ss" or "h:mm:ss"; "?" when unknown

// Appends the comparisons the sweep's rules ask for to a plan of points (compare.cpp).
void plan_compares(const Sweep& sw, Plan& plan);

// Slurm's view of a sweep (slurm.cpp).
nlohmann::json slurm_record(const std::filesystem::path& out);  // sweep.json's "slurm", {"submissions": []} if none
std::vector<std::string> slurm_job_ids(const nlohmann::json& slurm);
struct QueuedTask {
  std::string array_id;  // the array's job id (a plain job's own id)
  long task = -1;        // the array task id; -1 for a plain job
  std::string state;     // PENDING, RUNNING, ...
};
struct Queue {
  bool ok = true;
  std::string error;
  std::vector<QueuedTask> tasks;
};
Queue query_queue(const std::vector<std::string>& ids);  // squeue, one line per array task
// "stage:key" -> state of the jobs of `submission` that are in the queue.
std::map<std::string, std::string> queued_keys(const nlohmann::json& submission, const std::filesystem::path& out,
                                               const Queue& queue);

// Megasamples of a frame: the unit of work behind every ETA.
double megasamples(Size resolution, uint32_t samples);

}  // namespace tilevis::sweep::detail
