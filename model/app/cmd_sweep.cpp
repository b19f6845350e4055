// tilevis sweep SWEEP.json -o DIR: runs an exploration sweep (model/sweep) as subprocesses
// of this binary, -j at a time, resumable, then writes the report (reports/make_report.py:
// DIR/index.html, DIR/report.md, DIR/points.csv).
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <thread>

#include <fmt/format.h>

#include "commands.h"
#include "sweep/sweep.h"

extern char** environ;

namespace tilevis::app {
namespace {

namespace fs = std::filesystem;

struct SweepArgs {
  std::string file, out, jobs_file;
  unsigned jobs = 0;
  bool report_only = false, no_report = false;
};

std::string self_path() {
  std::error_code ec;
  fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("sweep: cannot find this binary (/proc/self/exe)");
  return p.string();
}

fs::path report_script() {
  if (const char* env = std::getenv("TILEVIS_REPORT_SCRIPT"); env && *env) return env;
  return sweep::source_dir() / "reports" / "make_report.py";
}

// python3 reports/make_report.py OUT; its output goes to ours. Returns its exit status.
int make_report(const fs::path& out) {
  const fs::path script = report_script();
  if (!fs::is_regular_file(script))
    throw std::runtime_error(fmt::format("sweep: report generator {} not found (set TILEVIS_REPORT_SCRIPT)",
                                         script.string()));
  // Debian's python3 has python3-matplotlib; a python3 earlier on PATH (pyenv, venv) may not.
  std::string python = "python3";
  if (const char* env = std::getenv("TILEVIS_PYTHON"); env && *env) python = env;
  else if (fs::exists("/usr/bin/python3")) python = "/usr/bin/python3";
  std::vector<std::string> argv = {python, script.string(), out.string()};
  std::vector<char*> args;
  for (auto& a : argv) args.push_back(a.data());
  args.push_back(nullptr);
  pid_t pid = -1;
  if (int rc = posix_spawnp(&pid, python.c_str(), nullptr, nullptr, args.data(), environ); rc != 0)
    throw std::runtime_error(fmt::format("sweep: cannot run {} for the report: {}", python, std::strerror(rc)));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 1;
}

int run_sweep(const SweepArgs& a) {
  const sweep::Sweep sw = sweep::load_sweep(a.file);
  const sweep::Plan plan = sweep::make_plan(sw);
  sweep::RunOptions opt;
  opt.out = fs::absolute(a.out).lexically_normal();
  opt.tilevis = self_path();
  opt.jobs = a.jobs ? a.jobs : std::max(1u, std::thread::hardware_concurrency());
  auto availability = sweep::probe_producers(sw, plan, opt.tilevis);
  sweep::check_params(sw, plan, availability);
  for (const auto& [name, av] : availability)
    if (!av.available) fmt::print(stderr, "tilevis sweep: producer {} unavailable here, its points are left out: {}\n", name, av.why);

  if (!a.jobs_file.empty()) {
    sweep::write_manifest(sw, plan, availability, opt, std::nullopt);
    sweep::write_jobs_file(sw, plan, availability, opt, a.jobs_file);
    fmt::print("tilevis sweep: {} points, {} traces, {} comparisons; the jobs not yet done are in {}\n",
               plan.points.size(), plan.traces.size(), plan.compares.size(), a.jobs_file);
    return 0;
  }

  int rc = 0;
  if (!a.report_only) {
    sweep::write_manifest(sw, plan, availability, opt, std::nullopt);
    const bool tty = isatty(STDERR_FILENO);
    opt.progress = [tty](const std::string& line, bool event) {
      if (tty) fmt::print(stderr, "\r\033[K{}", line);
      else if (event) fmt::print(stderr, "{}\n", line);
    };
    fmt::print(stderr, "tilevis sweep: {}: {} points ({} traces, {} comparisons), {} at a time -> {}\n", a.file,
               plan.points.size(), plan.traces.size(), plan.compares.size(), opt.jobs, opt.out.string());
    const sweep::RunSummary s = sweep::run_plan(sw, plan, availability, opt);
    if (tty) fmt::print(stderr, "\n");
    sweep::write_manifest(sw, plan, availability, opt, s);
    for (const std::string& f : s.failures) fmt::print(stderr, "tilevis sweep: failed: {}\n", f);
    fmt::print(stderr,
               "tilevis sweep: {} jobs: {} already done, {} run now, {} failed, {} unavailable, {} skipped; {:.1f} s\n",
               s.total, s.already_done, s.ran, s.failed, s.unavailable, s.skipped, s.wall_seconds);
    if (s.interrupted) {
      fmt::print(stderr, "tilevis sweep: interrupted; run the same command again to finish the remaining points\n");
      return 130;
    }
    if (s.failed) rc = 1;
  } else {
    if (!fs::is_regular_file(opt.out / "sweep.json"))
      throw std::runtime_error(fmt::format("sweep: --report-only: {} has no sweep.json (run the sweep first)",
                                           opt.out.string()));
    sweep::write_manifest(sw, plan, availability, opt, std::nullopt);
  }
  if (a.no_report) return rc;
  if (int r = make_report(opt.out); r != 0) {
    fmt::print(stderr, "tilevis sweep: the report generator failed (exit status {})\n", r);
    return r;
  }
  return rc;
}

}  // namespace

Command add_sweep_command(CLI::App& app) {
  auto a = std::make_shared<SweepArgs>();
  auto* cmd = app.add_subcommand("sweep", "Run an exploration sweep (scenes x tiles x resolutions x samples x producers "
                                          "x configurations) and write its report");
  cmd->add_option("sweep", a->file, "Sweep file (JSON; reports/sweeps/README.md)")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", a->out, "Output folder (reports/NAME): points, traces, report")->required();
  cmd->add_option("-j,--jobs", a->jobs, "Points run at once (default: the number of cores)")->check(CLI::Range(1, 1024));
  cmd->add_option("--jobs-file", a->jobs_file,
                  "Write one independent command line per job not yet done to this file instead of running");
  cmd->add_flag("--report-only", a->report_only, "Run nothing; make the report from the points that exist");
  cmd->add_flag("--no-report", a->no_report, "Run the points; do not make the report");
  return {cmd, [a]() { return run_sweep(*a); }};
}

}  // namespace tilevis::app
