// tilevis sweep --status: how far a sweep is, from its folder alone (done markers, process.json)
// and, for a sweep submitted to Slurm, one squeue call; no job is started and no producer probed.
#include <sys/stat.h>

#include <algorithm>
#include <ctime>
#include <vector>

#include <fmt/format.h>

#include "sweep/detail.h"
#include "sweep/jobs.h"
#include "sweep/progress.h"

namespace tilevis::sweep {

namespace fs = std::filesystem;
using namespace detail;

namespace {

struct StageCount {
  size_t total = 0, done = 0, running = 0, queued = 0;
  size_t missing() const { return total - done - running - queued; }
};

struct Survey {
  StageCount stage[3];  // by Job::Kind
  EtaModel eta;         // from the done points' process.json
  size_t measured = 0;  // points behind it
  std::vector<bool> in_queue;  // per job: running or queued in Slurm
};

// The squeue state of every queued job of every submission, keyed "stage:key".
std::map<std::string, std::string> queued_jobs(const nlohmann::json& slurm, const fs::path& out, const Queue& q) {
  std::map<std::string, std::string> keys;
  for (const auto& sub : slurm["submissions"]) keys.merge(queued_keys(sub, out, q));
  return keys;
}

Survey survey(const std::vector<Job>& jobs, const std::map<std::string, std::string>& queued, const fs::path& out,
              const Plan& plan) {
  Survey s;
  s.in_queue.assign(jobs.size(), false);
  for (const Job& j : jobs) {
    StageCount& c = s.stage[size_t(j.kind)];
    ++c.total;
    if (j.state == JobState::done) {
      ++c.done;
      if (j.kind != Job::Kind::point) continue;
      const nlohmann::json proc = read_json_or_null(out / plan.points[j.index].dir / "process.json");
      if (proc.is_object() && proc.contains("wall_seconds") && proc["wall_seconds"].is_number()) {
        s.eta.add(j.producer, proc["wall_seconds"].get<double>(), j.work);
        ++s.measured;
      }
      continue;
    }
    auto q = queued.find(std::string(to_string(j.kind)) + ":" + j.key);
    if (q == queued.end()) continue;
    ++(q->second == "RUNNING" ? c.running : c.queued);
    s.in_queue[size_t(&j - jobs.data())] = true;
  }
  return s;
}

// Seconds of point work left by the measured rates (on Slurm: of the points in the queue), and
// whether every such point's producer has a rate.
std::pair<double, bool> work_left(const std::vector<Job>& jobs, const Survey& s, bool slurm) {
  double seconds = 0;
  bool known = true;
  for (size_t i = 0; i < jobs.size(); ++i) {
    const Job& j = jobs[i];
    if (j.kind != Job::Kind::point || j.state == JobState::done || (slurm && !s.in_queue[i])) continue;
    const double e = s.eta.estimate(j.producer, j.work);
    if (e < 0) known = false;
    else seconds += e;
  }
  return {seconds, known};
}

std::string stage_text(const char* name, const StageCount& c, bool slurm) {
  std::string t = fmt::format("{} {}/{} done", name, c.done, c.total);
  if (slurm) t += fmt::format(", {} running, {} queued, {} neither done nor queued", c.running, c.queued, c.missing());
  return t;
}

std::string report_text(const fs::path& out, const nlohmann::json& slurm, const Queue& q) {
  if (!slurm["submissions"].empty()) {
    const std::string id = slurm["submissions"].back().value("report", "");
    for (const QueuedTask& t : q.tasks)
      if (t.array_id == id) return fmt::format("report: job {} {}", id, t.state == "RUNNING" ? "running" : "queued");
  }
  struct stat st {};
  if (stat((out / "report.md").c_str(), &st) != 0) return "report: not written";
  char when[32];
  std::strftime(when, sizeof when, "%Y-%m-%d %H:%M:%S", std::localtime(&st.st_mtime));
  return fmt::format("report: written {}", when);
}

std::string eta_text(const std::vector<Job>& jobs, const Survey& s, bool slurm) {
  const StageCount& p = s.stage[size_t(Job::Kind::point)];
  if (p.done == p.total) return "ETA: every point is done";
  const auto [seconds, known] = work_left(jobs, s, slurm);
  if (s.measured == 0) return "ETA: ? (no point has finished yet)";
  const std::string basis = fmt::format("{}from {} finished points' seconds per megasample{}",
                                        slurm ? "points in the queue, " : "", s.measured,
                                        known ? "" : "; producers with none finished yet are left out");
  if (slurm && p.running > 0)
    return fmt::format("ETA {} at {} tasks at a time ({})", duration_text(seconds / double(p.running)), p.running,
                       basis);
  return fmt::format("work left: {} at one job at a time ({}){}", duration_text(seconds), basis,
                     slurm ? "; no task of it is running in Slurm now" : "");
}

std::string slurm_text(const nlohmann::json& slurm, const Queue& q) {
  const nlohmann::json& last = slurm["submissions"].back();
  std::string t = fmt::format("Slurm: {} submission(s); the last, {}, at {}: jobs {}", slurm["submissions"].size(),
                              last.value("number", 0), last.value("submitted", "?"),
                              fmt::join(slurm_job_ids({{"submissions", {last}}}), ", "));
  if (!q.ok) t += fmt::format(" (queue unknown: {})", q.error);
  return t;
}

}  // namespace

std::string sweep_status(const Sweep& sw, const Plan& plan, const RunOptions& opt) {
  const std::vector<Job> jobs = make_jobs(sw, plan, opt.out, opt.tilevis);
  const nlohmann::json slurm = slurm_record(opt.out);
  const bool on_slurm = !slurm["submissions"].empty();
  const Queue q = on_slurm ? query_queue(slurm_job_ids(slurm)) : Queue{};
  const Survey s = survey(jobs, on_slurm ? queued_jobs(slurm, opt.out, q) : std::map<std::string, std::string>{},
                          opt.out, plan);
  const StageCount& p = s.stage[size_t(Job::Kind::point)];
  std::string text = fmt::format("{}: {} of {} points done ({:.0f} %)\n", opt.out.string(), p.done, p.total,
                                 100.0 * double(p.done) / double(std::max<size_t>(1, p.total)));
  text += "  " + stage_text("traces", s.stage[size_t(Job::Kind::trace)], on_slurm) + "\n";
  text += "  " + stage_text("points", p, on_slurm) + "\n";
  text += "  " + stage_text("comparisons", s.stage[size_t(Job::Kind::compare)], on_slurm) + "\n";
  text += "  " + report_text(opt.out, slurm, q) + "\n";
  if (on_slurm) text += "  " + slurm_text(slurm, q) + "\n";
  text += "  " + eta_text(jobs, s, on_slurm) + "\n";
  return text;
}

}  // namespace tilevis::sweep
