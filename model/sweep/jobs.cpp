#include "sweep/jobs.h"

#include <sys/wait.h>

#include <fmt/format.h>

#include "sweep/detail.h"

namespace tilevis::sweep::detail {

namespace fs = std::filesystem;

namespace {

Job make_job(Job::Kind kind, size_t index, std::string key, std::string label, std::string producer, Command command,
             fs::path log, std::vector<size_t> deps, double work) {
  Job j;
  j.kind = kind;
  j.index = index;
  j.key = std::move(key);
  j.label = std::move(label);
  j.producer = std::move(producer);
  j.command = std::move(command);
  j.log = std::move(log);
  j.deps = std::move(deps);
  j.work = work;
  return j;
}

std::string point_label(const Point& p) {
  return fmt::format("{} {} {} s{} t{}{}{}", p.producer, p.scene, p.resolution.text(), p.samples, p.tile.text(),
                     p.mode.empty() ? "" : " " + p.mode, p.config == "default" ? "" : " " + p.config);
}

}  // namespace

const char* to_string(Job::Kind kind) {
  switch (kind) {
    case Job::Kind::trace: return "traces";
    case Job::Kind::point: return "points";
    case Job::Kind::compare: return "comparisons";
  }
  return "?";
}

std::vector<Job> make_jobs(const Sweep& sw, const Plan& plan, const fs::path& out, const std::string& tilevis) {
  std::vector<Job> jobs;
  jobs.reserve(plan.traces.size() + plan.points.size() + plan.compares.size());
  std::map<fs::path, size_t> trace_job;
  for (size_t i = 0; i < plan.traces.size(); ++i) {
    const TraceJob& t = plan.traces[i];
    Job j = make_job(Job::Kind::trace, i, t.file.string(),
                     fmt::format("trace {} {} s{}", t.scene, t.resolution.text(), t.samples), "trace",
                     trace_command(sw, t, tilevis, out), out / (t.file.string() + ".log"), {},
                     megasamples(t.resolution, t.samples));
    if (trace_done(t, out)) j.state = JobState::done;
    trace_job[t.file] = jobs.size();
    jobs.push_back(std::move(j));
  }
  const size_t first_point = jobs.size();
  for (size_t i = 0; i < plan.points.size(); ++i) {
    const Point& p = plan.points[i];
    Job j = make_job(Job::Kind::point, i, p.dir.string(), point_label(p), p.producer,
                     point_command(sw, p, tilevis, out), out / p.dir / "run.log",
                     p.frame < 0 ? std::vector<size_t>{trace_job.at(p.trace)} : std::vector<size_t>{},
                     megasamples(p.resolution, p.samples));
    j.exclusive = sw.producer(p.producer).exclusive;
    if (point_done(p, out)) j.state = JobState::done;
    jobs.push_back(std::move(j));
  }
  for (size_t i = 0; i < plan.compares.size(); ++i) {
    const CompareJob& c = plan.compares[i];
    const Point &a = plan.points[c.a], &b = plan.points[c.b];
    Job j = make_job(Job::Kind::compare, i, c.dir.string(), fmt::format("compare {} vs {}", a.dir.string(), b.producer),
                     "compare", compare_command(plan, c, tilevis, out), out / c.dir / "compare.log",
                     {first_point + c.a, first_point + c.b}, megasamples(a.resolution, a.samples));
    if (compare_done(plan, c, out)) j.state = JobState::done;
    jobs.push_back(std::move(j));
  }
  return jobs;
}

Spawned start_job(const Job& job, const std::vector<std::string>& env) {
  std::error_code ec;
  fs::create_directories(job.log.parent_path(), ec);
  for (const auto& [from, to] : job.command.renames) fs::create_directories(from.parent_path(), ec);
  return spawn(job.command.argv, job.log, env);
}

namespace {

Finished succeeded(const Plan& plan, const Job& j, const rusage& ru, double wall, const fs::path& out,
                   const RunContext& ctx) {
  std::error_code ec;
  for (const auto& [from, to] : j.command.renames) {
    fs::rename(from, to, ec);
    if (ec) break;
  }
  bool complete = !ec;
  if (j.kind == Job::Kind::point) complete = complete && point_done(plan.points[j.index], out);
  if (!complete)
    return {JobState::failed, "FAILED " + j.label,
            fmt::format("{}: exited 0 but left no complete result{} (log {})", j.label, ec ? ": " + ec.message() : "",
                        j.log.string()),
            ""};
  if (j.kind == Job::Kind::point) {
    const double cpu = double(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
                       1e-6 * double(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
    write_json_atomically(out / plan.points[j.index].dir / "process.json",
                          {{"command", j.command.shell()},
                           {"wall_seconds", wall},
                           {"cpu_seconds", cpu},
                           {"max_rss_mib", double(ru.ru_maxrss) / 1024.0},
                           {"finished", now_iso()},
                           {"commit", ctx.commit},
                           {"machine", ctx.machine}});
  }
  return {JobState::done, fmt::format("done {} ({:.1f} s)", j.label, wall), "", ""};
}

}  // namespace

Finished finish_job(const Plan& plan, const Job& j, int status, const rusage& ru, double wall, const fs::path& out,
                    const RunContext& ctx) {
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (code == 0) return succeeded(plan, j, ru, wall, out, ctx);
  if (code == 2 && j.kind == Job::Kind::point && !point_done(plan.points[j.index], out)) {
    // Exit status 2 with nothing written: the producer cannot run here (e.g. no GPU).
    const std::string why = last_line(j.log);
    return {JobState::unavailable, fmt::format("{} unavailable here: {}", j.producer, why), "", why};
  }
  const std::string why = WIFSIGNALED(status) ? fmt::format("killed by signal {}", WTERMSIG(status))
                                              : fmt::format("exit status {}", code);
  return {JobState::failed, "FAILED " + j.label,
          fmt::format("{}: {}: {} (log {})", j.label, why, last_line(j.log), j.log.string()), ""};
}

}  // namespace tilevis::sweep::detail
