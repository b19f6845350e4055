// tilevis sweep SWEEP.json -o DIR: runs an exploration sweep (model/sweep) as subprocesses
// of this binary, -j at a time, resumable, then writes the report (reports/make_report.py:
// DIR/index.html, DIR/report.md, DIR/points.csv); or writes a jobs file (--jobs-file), or
// submits it to Slurm (--slurm; --status, --cancel, and the hidden --task an array task runs).
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <thread>

#include <fmt/format.h>

#include "commands.h"
#include "sweep/sweep.h"

namespace tilevis::app {
namespace {

namespace fs = std::filesystem;

struct SweepArgs {
  std::string file, out, jobs_file;
  unsigned jobs = 0;
  bool report_only = false, no_report = false;
  bool slurm = false, status = false, cancel = false;
  sweep::SlurmOptions slurm_options;
  std::string sbatch_args;
  std::string task, task_list;  // a Slurm array task (internal)
  long task_index = -1;
};

std::string self_path() {
  std::error_code ec;
  fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("sweep: cannot find this binary (/proc/self/exe)");
  return p.string();
}

std::vector<std::string> words_of(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

// A Slurm array task's index: --task-index, else SLURM_ARRAY_TASK_ID.
long task_index(long given) {
  if (given >= 0) return given;
  const char* env = std::getenv("SLURM_ARRAY_TASK_ID");
  if (!env || !*env) throw std::runtime_error("sweep --task: no --task-index and no SLURM_ARRAY_TASK_ID");
  return std::stol(env);
}

// The report task of a Slurm submission: its run in sweep.json's history, then the report.
int slurm_report_task(const sweep::Sweep& sw, const sweep::Plan& plan, const sweep::RunOptions& opt) {
  auto availability = sweep::probe_producers(sw, plan, opt.tilevis);
  sweep::write_manifest(sw, plan, availability, opt, sweep::slurm_run_summary(sw, plan, opt));
  if (int r = sweep::make_report(opt.out); r != 0) {
    fmt::print(stderr, "tilevis sweep: the report generator failed (exit status {})\n", r);
    return r;
  }
  return 0;
}

// --status, --cancel and the Slurm tasks: no probes, nothing else written. -1: none of them.
int run_side_command(const SweepArgs& a, const sweep::Sweep& sw, const sweep::Plan& plan,
                     const sweep::RunOptions& opt) {
  if (a.status) {
    fmt::print("{}", sweep::sweep_status(sw, plan, opt));
    return 0;
  }
  if (a.cancel) return sweep::cancel_slurm(opt);
  if (a.task == "report") return slurm_report_task(sw, plan, opt);
  if (!a.task.empty()) return sweep::run_slurm_task(sw, plan, opt, a.task, a.task_list, task_index(a.task_index));
  return -1;
}

int run_sweep(const SweepArgs& a) {
  sweep::RunOptions opt;
  opt.out = fs::absolute(a.out).lexically_normal();
  opt.tilevis = self_path();
  opt.jobs = a.jobs ? a.jobs : std::max(1u, std::thread::hardware_concurrency());
  const sweep::Sweep sw = sweep::load_sweep(a.file, opt.out);  // {out} in a trace set's path is opt.out
  const sweep::Plan plan = sweep::make_plan(sw);
  if (int rc = run_side_command(a, sw, plan, opt); rc >= 0) return rc;
  // Optional trace sets not found here (e.g. captured workloads where nothing can capture):
  // said before anything runs, recorded in sweep.json and in the report.
  for (const std::string& line : sweep::missing_trace_lines(sw)) fmt::print(stderr, "tilevis sweep: {}\n", line);
  auto availability = sweep::probe_producers(sw, plan, opt.tilevis);
  sweep::check_params(sw, plan, availability);
  for (const auto& [name, av] : availability)
    if (!av.available) fmt::print(stderr, "tilevis sweep: producer {} unavailable here, its points are left out: {}\n", name, av.why);

  if (a.slurm) {
    sweep::write_manifest(sw, plan, availability, opt, std::nullopt);
    sweep::SlurmOptions so = a.slurm_options;
    so.sbatch_args = words_of(a.sbatch_args);
    return sweep::submit_slurm(sw, plan, availability, opt, so);
  }

  if (!a.jobs_file.empty()) {
    sweep::check_slurm_idle(opt, "sweep --jobs-file", false);
    sweep::write_manifest(sw, plan, availability, opt, std::nullopt);
    sweep::write_jobs_file(sw, plan, availability, opt, a.jobs_file);
    fmt::print("tilevis sweep: {} points, {} traces, {} comparisons; the jobs not yet done are in {}\n",
               plan.points.size(), plan.traces.size(), plan.compares.size(), a.jobs_file);
    return 0;
  }

  int rc = 0;
  if (!a.report_only) {
    sweep::check_slurm_idle(opt, "sweep", false);
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
  if (int r = sweep::make_report(opt.out); r != 0) {
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
  auto* slurm = cmd->add_flag("--slurm", a->slurm,
                              "Submit the jobs not yet done to Slurm as job arrays (traces, points, comparisons, "
                              "report), chained by dependencies; the job ids go into OUT/sweep.json");
  cmd->add_option("--partition", a->slurm_options.partition, "Slurm partition (with --slurm)")->needs(slurm);
  cmd->add_option("--max-array", a->slurm_options.max_array,
                  "Tasks of one array running at once (with --slurm; default: no limit)")
      ->check(CLI::Range(1u, 100000u))
      ->needs(slurm);
  cmd->add_option("--sbatch-args", a->sbatch_args,
                  "More sbatch words for every job, as one argument: --sbatch-args='--time=30 --qos=low'")
      ->needs(slurm);
  auto* status = cmd->add_flag("--status", a->status,
                               "Print progress and time left from OUT's points (and squeue, after --slurm); run nothing");
  auto* cancel = cmd->add_flag("--cancel", a->cancel, "Cancel the Slurm jobs of this sweep (scancel)");
  slurm->excludes(status)->excludes(cancel);
  status->excludes(cancel);
  for (auto* o : {slurm, status, cancel}) {
    o->excludes("--jobs-file");
    o->excludes("--report-only");
  }
  // What a Slurm array task runs (internal, hidden from --help).
  cmd->add_option("--task", a->task)->group("")->check(CLI::IsMember({"traces", "points", "comparisons", "report"}));
  cmd->add_option("--task-list", a->task_list)->group("");
  cmd->add_option("--task-index", a->task_index)->group("");
  return {cmd, [a]() { return run_sweep(*a); }};
}

}  // namespace tilevis::app
