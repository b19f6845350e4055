// The Slurm runner: the jobs not done go out as job arrays, one array task per job, chained by
// dependencies (traces -> points -> comparisons -> report); each task runs its job exactly as
// the local runner does (jobs.h). OUT/sweep.json's "slurm" member records every submission:
// its job ids and, per array, the file listing its tasks' jobs (line k: task k), so that
// --status can tell which jobs are queued and --cancel what to cancel.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "sweep/detail.h"
#include "sweep/jobs.h"

namespace tilevis::sweep {

namespace fs = std::filesystem;
using namespace detail;

namespace {

// Slurm's default MaxArraySize is 1001 (task ids 0..1000): larger stages go out as several arrays.
constexpr size_t kMaxArrayTasks = 1000;

std::string join(const std::vector<std::string>& words, const std::string& sep) {
  std::string s;
  for (const std::string& w : words) s += (s.empty() ? "" : sep) + w;
  return s;
}

std::vector<std::string> read_lines(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

// Runs sbatch --parsable ARGS; returns the job id or throws with sbatch's own words.
std::string sbatch(const std::vector<std::string>& args) {
  std::vector<std::string> argv = {"sbatch", "--parsable"};
  argv.insert(argv.end(), args.begin(), args.end());
  std::string output;
  const int rc = run_capture(argv, &output);
  const std::string last = last_line_of_text(output);
  const std::string id = last.substr(0, last.find(';'));  // "id" or "id;cluster"
  const bool numeric = !id.empty() && std::all_of(id.begin(), id.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (rc != 0 || !numeric)
    throw SweepError(rc < 0 ? "cannot run sbatch (is Slurm's client installed and on PATH?)"
                            : fmt::format("sbatch exited {}: {}", rc, last.empty() ? "no output" : last));
  return id;
}

std::string dependency(const char* type, const std::vector<std::string>& ids) {
  return ids.empty() ? "" : fmt::format("--dependency={}:{}", type, join(ids, ":"));
}

// The jobs a submission sends: not done, their producer available here.
struct Pending {
  std::vector<std::string> traces, compares;
  std::map<std::string, std::vector<std::string>> points;  // exclusive resource ("" none) -> point dirs
  size_t total = 0, already_done = 0, count = 0;
};

Pending pending_jobs(const std::vector<Job>& jobs, const std::map<std::string, Availability>& av, const Plan& plan) {
  Pending p;
  p.total = jobs.size();
  auto available = [&](const std::string& producer) { return av.at(producer).available; };
  for (const Job& j : jobs) {
    if (j.state == JobState::done) {
      ++p.already_done;
      continue;
    }
    if (j.kind == Job::Kind::trace) p.traces.push_back(j.key);
    else if (j.kind == Job::Kind::point && available(j.producer)) p.points[j.exclusive].push_back(j.key);
    else if (j.kind == Job::Kind::compare && available(plan.points[plan.compares[j.index].a].producer) &&
             available(plan.points[plan.compares[j.index].b].producer))
      p.compares.push_back(j.key);
    else continue;
    ++p.count;
  }
  return p;
}

class Submitter {
 public:
  Submitter(const Sweep& sw, const RunOptions& opt, const SlurmOptions& so, size_t number)
      : m_opt(opt), m_so(so), m_number(number), m_dir(fs::path("slurm") / std::to_string(number)),
        m_sweep_file(fs::absolute(sw.file).lexically_normal().string()), m_name(opt.out.filename().string()) {
    if (m_name.empty()) m_name = opt.out.parent_path().filename().string();  // OUT ends with a slash
    fs::create_directories(opt.out / m_dir);
  }

  // One stage's jobs (keys) as arrays of at most kMaxArrayTasks tasks; returns their ids.
  std::vector<std::string> submit_stage(const std::string& stage, const std::vector<std::string>& keys,
                                        const std::string& resource, const std::string& dep) {
    std::vector<std::string> ids;
    for (size_t first = 0, part = 0; first < keys.size(); first += kMaxArrayTasks, ++part) {
      const size_t n = std::min(kMaxArrayTasks, keys.size() - first);
      const std::string base = fmt::format("{}{}-{}", stage, resource.empty() ? "" : "-" + resource, part);
      const fs::path list = m_dir / (base + ".txt");
      std::ofstream f(m_opt.out / list);
      for (size_t i = first; i < first + n; ++i) f << keys[i] << '\n';
      f.close();
      if (!f) throw SweepError("cannot write " + (m_opt.out / list).string());
      std::vector<std::string> args = common(stage, base + "-%A_%a.out", dep);
      args.push_back(fmt::format("--array=0-{}{}", n - 1, m_so.max_array ? fmt::format("%{}", m_so.max_array) : ""));
      if (!resource.empty()) args.push_back(fmt::format("--gres={}:1", resource));
      if (stage == "points") args.push_back("--kill-on-invalid-dep=yes");
      args.push_back("--wrap=" + task_line({"--task", stage, "--task-list", (m_opt.out / list).string()}));
      const std::string id = sbatch(args);
      ids.push_back(id);
      m_ids.push_back(id);
      m_arrays.push_back({{"stage", stage}, {"id", id}, {"tasks", n}, {"list", list.string()}, {"resource", resource}});
    }
    return ids;
  }

  std::string submit_report(const std::string& dep) {
    std::vector<std::string> args = common("report", "report-%j.out", dep);
    args.push_back("--wrap=" + task_line({"--task", "report"}));
    m_report = sbatch(args);
    m_ids.push_back(m_report);
    return m_report;
  }

  // After a failed sbatch: what this submission queued goes too.
  void cancel_submitted() const {
    if (m_ids.empty()) return;
    std::vector<std::string> argv = {"scancel"};
    argv.insert(argv.end(), m_ids.begin(), m_ids.end());
    run_capture(argv, nullptr);
  }

  nlohmann::json record(const Pending& p) const {
    return {{"number", m_number},          {"submitted", now_iso()},   {"submitted_epoch", std::time(nullptr)},
            {"dir", m_dir.string()},       {"partition", m_so.partition}, {"max_array", m_so.max_array},
            {"sbatch_args", m_so.sbatch_args}, {"arrays", m_arrays},     {"report", m_report},
            {"total", p.total},            {"already_done", p.already_done}, {"submitted_jobs", p.count}};
  }

 private:
  std::vector<std::string> common(const std::string& stage, const std::string& output, const std::string& dep) const {
    std::vector<std::string> args = {fmt::format("--job-name=tilevis-{}-{}", m_name, stage),
                                     "--output=" + (m_opt.out / m_dir / output).string(),
                                     "--chdir=" + m_opt.out.string()};
    if (!m_so.partition.empty()) args.push_back("--partition=" + m_so.partition);
    if (!dep.empty()) args.push_back(dep);
    args.insert(args.end(), m_so.sbatch_args.begin(), m_so.sbatch_args.end());
    return args;
  }

  std::string task_line(const std::vector<std::string>& extra) const {
    std::string line = "exec " + shell_quote(m_opt.tilevis) + " sweep " + shell_quote(m_sweep_file) + " -o " +
                       shell_quote(m_opt.out.string());
    for (const std::string& w : extra) line += " " + shell_quote(w);
    return line;
  }

  const RunOptions& m_opt;
  const SlurmOptions& m_so;
  size_t m_number;
  fs::path m_dir;
  std::string m_sweep_file, m_name, m_report;
  std::vector<std::string> m_ids;
  nlohmann::json m_arrays = nlohmann::json::array();
};

// Appends a submission to sweep.json's "slurm" member.
void store_submission(const fs::path& out, const nlohmann::json& submission) {
  nlohmann::json m = read_json_or_null(out / "sweep.json");
  if (!m.is_object()) throw SweepError(fmt::format("{}: unreadable sweep.json", out.string()));
  nlohmann::json& slurm = m["slurm"];
  if (!slurm.is_object() || !slurm.contains("submissions")) slurm = {{"submissions", nlohmann::json::array()}};
  slurm["submissions"].push_back(submission);
  write_json_atomically(out / "sweep.json", m);
}

std::vector<std::string> submission_ids(const nlohmann::json& sub) {
  std::vector<std::string> ids;
  for (const auto& a : sub.value("arrays", nlohmann::json::array())) ids.push_back(a.value("id", ""));
  if (!sub.value("report", "").empty()) ids.push_back(sub.value("report", ""));
  return ids;
}

}  // namespace

namespace detail {

nlohmann::json slurm_record(const fs::path& out) {
  const nlohmann::json m = read_json_or_null(out / "sweep.json");
  if (m.is_object() && m.contains("slurm") && m["slurm"].is_object() && m["slurm"].contains("submissions"))
    return m["slurm"];
  return {{"submissions", nlohmann::json::array()}};
}

std::vector<std::string> slurm_job_ids(const nlohmann::json& slurm) {
  std::vector<std::string> ids;
  for (const auto& sub : slurm["submissions"])
    for (const std::string& id : submission_ids(sub)) ids.push_back(id);
  return ids;
}

Queue query_queue(const std::vector<std::string>& ids) {
  Queue q;
  if (ids.empty()) return q;
  std::string output;
  const int rc = run_capture({"squeue", "-h", "-r", "-j", join(ids, ","), "-o", "%F %K %T"}, &output);
  if (rc != 0) {
    // Jobs that have left the controller are "invalid": none of them is queued any more.
    if (output.find("Invalid job id") != std::string::npos) return q;
    q.ok = false;
    q.error = rc < 0 ? "cannot run squeue" : fmt::format("squeue exited {}: {}", rc, last_line_of_text(output));
    return q;
  }
  std::istringstream lines(output);
  for (std::string l; std::getline(lines, l);) {
    std::istringstream words(l);
    QueuedTask t;
    std::string task;
    if (!(words >> t.array_id >> task >> t.state)) continue;
    t.task = task.find_first_not_of("0123456789") == std::string::npos ? std::stol(task) : -1;
    q.tasks.push_back(t);
  }
  return q;
}

std::map<std::string, std::string> queued_keys(const nlohmann::json& submission, const fs::path& out,
                                               const Queue& queue) {
  std::map<std::string, std::string> keys;
  for (const auto& a : submission.value("arrays", nlohmann::json::array())) {
    const std::string id = a.value("id", "");
    std::vector<std::string> lines;
    for (const QueuedTask& t : queue.tasks) {
      if (t.array_id != id || t.task < 0) continue;
      if (lines.empty()) lines = read_lines(out / a.value("list", ""));
      if (size_t(t.task) < lines.size()) keys[a.value("stage", "") + ":" + lines[t.task]] = t.state;
    }
  }
  return keys;
}

}  // namespace detail

void check_slurm_idle(const RunOptions& opt, const std::string& action, bool strict) {
  const nlohmann::json slurm = slurm_record(opt.out);
  const std::vector<std::string> ids = slurm_job_ids(slurm);
  if (ids.empty()) return;
  const Queue queue = query_queue(ids);
  if (!queue.ok) {
    if (strict) throw SweepError(fmt::format("{}: {}", action, queue.error));
    fmt::print(stderr, "tilevis sweep: warning: cannot tell whether this sweep's Slurm jobs ({}) are still queued: {}\n",
               join(ids, ", "), queue.error);
    return;
  }
  if (!queue.tasks.empty())
    throw SweepError(fmt::format("{}: {} tasks of this sweep's Slurm jobs ({}) are still queued or running: wait for "
                                 "them (--status) or cancel them (--cancel) first",
                                 action, queue.tasks.size(), join(ids, ", ")));
}

int submit_slurm(const Sweep& sw, const Plan& plan, const std::map<std::string, Availability>& av,
                 const RunOptions& opt, const SlurmOptions& so) {
  check_slurm_idle(opt, "sweep --slurm", true);
  const nlohmann::json slurm = slurm_record(opt.out);
  const Pending p = pending_jobs(make_jobs(sw, plan, opt.out, opt.tilevis), av, plan);
  if (p.count == 0 && fs::is_regular_file(opt.out / "report.md")) {
    fmt::print("tilevis sweep: all {} jobs are done and the report is written; nothing to submit\n", p.total);
    return 0;
  }
  Submitter s(sw, opt, so, slurm["submissions"].size() + 1);
  std::vector<std::string> traces, points, compares;
  std::vector<std::string> skipped;
  try {
    traces = s.submit_stage("traces", p.traces, "", "");
    for (const auto& [resource, keys] : p.points) {
      try {
        for (const std::string& id : s.submit_stage("points", keys, resource, dependency("afterok", traces)))
          points.push_back(id);
      } catch (const SweepError& e) {
        if (resource.empty()) throw;
        skipped.push_back(fmt::format("{} points that need {} not submitted: {}", keys.size(), resource, e.what()));
      }
    }
    std::vector<std::string> before = traces;
    before.insert(before.end(), points.begin(), points.end());
    compares = s.submit_stage("comparisons", p.compares, "", dependency("afterany", before));
    before.insert(before.end(), compares.begin(), compares.end());
    s.submit_report(dependency("afterany", before));
  } catch (const SweepError& e) {
    s.cancel_submitted();
    throw SweepError(fmt::format("sweep --slurm: {} (nothing of this submission stays queued)", e.what()));
  }
  const nlohmann::json record = s.record(p);
  store_submission(opt.out, record);
  for (const std::string& line : skipped) fmt::print(stderr, "tilevis sweep: warning: {}\n", line);
  std::vector<std::string> arrays;
  for (const auto& a : record["arrays"])
    arrays.push_back(fmt::format("{} {} ({} tasks)", a["stage"].get<std::string>(), a["id"].get<std::string>(),
                                 a["tasks"].get<size_t>()));
  fmt::print("tilevis sweep: submission {} to Slurm: {} of {} jobs ({} already done): {} traces, {} points, "
             "{} comparisons; job arrays: {}; report: job {}\n",
             record["number"].get<size_t>(), p.count, p.total, p.already_done, p.traces.size(),
             p.count - p.traces.size() - p.compares.size(), p.compares.size(),
             arrays.empty() ? "none" : join(arrays, ", "), record["report"].get<std::string>());
  fmt::print("tilevis sweep: follow it with --status, stop it with --cancel; run the same command again to submit "
             "what is left\n");
  return 0;
}

int cancel_slurm(const RunOptions& opt) {
  const nlohmann::json slurm = slurm_record(opt.out);
  const std::vector<std::string> ids = slurm_job_ids(slurm);
  if (ids.empty()) {
    fmt::print("tilevis sweep: {} has no Slurm submission to cancel\n", opt.out.string());
    return 0;
  }
  std::vector<std::string> argv = {"scancel"};
  argv.insert(argv.end(), ids.begin(), ids.end());
  std::string output;
  const int rc = run_capture(argv, &output);
  if (rc != 0 && output.find("Invalid job id") == std::string::npos) {
    fmt::print(stderr, "tilevis sweep: scancel exited {}: {}\n", rc, last_line_of_text(output));
    return 1;
  }
  fmt::print("tilevis sweep: cancelled Slurm jobs {}; finished points stay done, and the same --slurm command "
             "submits what is left\n", join(ids, ", "));
  return 0;
}

namespace {

// Line `index` of a task list.
std::string task_key(const fs::path& list, long index) {
  const std::vector<std::string> lines = read_lines(list);
  if (index < 0 || size_t(index) >= lines.size())
    throw SweepError(fmt::format("{}: no line {} (it has {})", list.string(), index, lines.size()));
  return lines[size_t(index)];
}

int run_job_here(const Plan& plan, const Job& job, const RunOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  const Spawned s = start_job(job);
  if (s.pid < 0) {
    fmt::print(stderr, "tilevis sweep: {}: {}\n", job.label, s.error);
    return 1;
  }
  int status = 0;
  rusage ru{};
  while (wait4(s.pid, &status, 0, &ru) < 0 && errno == EINTR) {
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const Finished f = finish_job(plan, job, status, ru, wall, opt.out, {source_commit(), machine_info()});
  fmt::print(stderr, "tilevis sweep: {}\n", f.state == JobState::failed ? f.failure : f.event);
  return f.state == JobState::done ? 0 : f.state == JobState::unavailable ? 2 : 1;
}

}  // namespace

int run_slurm_task(const Sweep& sw, const Plan& plan, const RunOptions& opt, const std::string& stage,
                   const fs::path& list, long index) {
  const std::string key = task_key(list, index);
  const std::vector<Job> jobs = make_jobs(sw, plan, opt.out, opt.tilevis);
  auto it = std::find_if(jobs.begin(), jobs.end(), [&](const Job& j) { return to_string(j.kind) == stage && j.key == key; });
  if (it == jobs.end())
    throw SweepError(fmt::format("no {} job {} in the plan of {} (was the sweep file changed after submission?)", stage,
                                 key, sw.file.string()));
  if (it->state == JobState::done) {
    fmt::print(stderr, "tilevis sweep: {} already done\n", it->label);
    return 0;
  }
  for (size_t d : it->deps)
    if (jobs[d].state != JobState::done) {
      // A comparison whose side did not finish is skipped, as the local runner skips it.
      fmt::print(stderr, "tilevis sweep: {}: {} {} is not done\n", it->label,
                 it->kind == Job::Kind::compare ? "skipped:" : "cannot run:", jobs[d].label);
      return it->kind == Job::Kind::compare ? 0 : 1;
    }
  return run_job_here(plan, *it, opt);
}

RunSummary slurm_run_summary(const Sweep& sw, const Plan& plan, const RunOptions& opt) {
  const nlohmann::json slurm = slurm_record(opt.out);
  if (slurm["submissions"].empty()) throw SweepError(fmt::format("{}: no Slurm submission recorded", opt.out.string()));
  const nlohmann::json& sub = slurm["submissions"].back();
  std::set<std::string> submitted;
  for (const auto& a : sub["arrays"])
    for (const std::string& key : read_lines(opt.out / a.value("list", "")))
      submitted.insert(a.value("stage", "") + ":" + key);
  RunSummary s;
  for (const Job& j : make_jobs(sw, plan, opt.out, opt.tilevis)) {
    ++s.total;
    if (!submitted.contains(std::string(to_string(j.kind)) + ":" + j.key)) continue;
    if (j.state == JobState::done) ++s.ran;
    else ++s.failed;
  }
  s.already_done = sub.value("already_done", size_t(0));
  s.wall_seconds = double(std::time(nullptr) - sub.value("submitted_epoch", std::time(nullptr)));
  s.extra = {{"jobs", "slurm"}, {"slurm_submission", sub.value("number", 0)}};
  return s;
}

}  // namespace tilevis::sweep
