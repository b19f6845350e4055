// Exploration sweeps (issue 6): the cross product of scenes x resolutions x sample counts x
// tile sizes x producers/modes x unit configurations, run as subprocesses of the tilevis
// binary, resumable, with a progress line; or written out as independent command lines.
//
// A sweep file is JSON (reports/sweeps/README.md documents it); unknown keys and bad values
// are one-line errors "FILE: $.path: expected ...". A producer is a command template:
//
//   {tilevis} golden {trace} --tile {tile} --samples {samples} -o {out}
//
// with {tilevis} the running binary, {trace} the trace built once per scene x resolution x
// samples, {tile} "WxH", {out} the point's directory, {mode} the visibility mode and
// {params} the unit configuration as "-p key=value" words, {frame} the trace frame. A
// workload may also be given as trace files (captured programs, "traces" in the sweep file):
// every frame of such a trace is a point of its own at the frame's viewport and samples. A
// point is done when its
// DIR/stats.json exists (every producer writes it last, atomically), so an interrupted
// sweep, run again, runs only what is missing.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "geom/tile_grid.h"

namespace tilevis::sweep {

class SweepError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr uint32_t kMinTile = geom::TileGrid::kMinTile, kMaxTile = geom::TileGrid::kMaxTile;

struct Size {
  uint32_t width = 0, height = 0;
  std::string text() const;  // "WxH"
  auto operator<=>(const Size&) const = default;
};

// What a producer's numbers are good for in the report.
enum class ProducerKind {
  visibility,  // ids and per-tile counters (golden, cuda)
  truth,       // z-buffer truth: fragments per visibility mode (exact or quantised depth)
  timing,      // cycles (the SystemC model)
};
const char* to_string(ProducerKind kind);

struct Producer {
  std::string name, command, probe, description;
  ProducerKind kind = ProducerKind::visibility;
  bool probe_lists_params = false;  // the probe prints one parameter name per line, first word
  std::string exclusive;            // a resource (e.g. "gpu"): jobs naming the same one run one at a time,
                                    // so that their timings do not include each other's work
  bool uses_mode() const;           // the command has {mode}
  bool uses_params() const;         // the command has {params}
  bool uses_frame() const;          // the command has {frame}
};

// The built-in producers: golden, truth, truth_q16, truth_q24, sim_analytic, sim_tile,
// sim_primitive, cuda_exact, cuda_float.
std::vector<Producer> builtin_producers();

struct Scene {
  std::string name;
  std::filesystem::path file;
};

// One frame of a workload given as a trace: a pass of a captured program (a shadow map, a
// render-to-texture pass, the window), with what the sweep read from the trace.
struct TraceFrame {
  Size viewport;
  uint32_t samples = 1, draws = 0;
  uint64_t triangles = 0;
  uint64_t non_occluding_triangles = 0;  // alpha-tested or blended: shaded, never occluding
  uint64_t per_pixel_triangles = 0;      // the shader discards or writes depth
};

// A workload given as a trace file; its name is the file's stem.
struct Workload {
  std::string name, set;             // set: the key of Sweep::trace_sets that found it
  std::filesystem::path file;        // absolute
  std::string source;                // the trace's source string
  std::vector<TraceFrame> frames;
};

// A named group of trace files in the sweep file's "traces": one .tvt file or every .tvt of a
// folder. An optional set that is missing leaves its points out, and says so (missing).
struct TraceSet {
  std::string name, description, make;   // make: how to make the traces ({out} expanded)
  std::string path_text;                 // as written
  std::filesystem::path path;            // {out} expanded, relative to the sweep file's folder
  bool optional = false;
  std::vector<std::string> workloads;    // names, keys of Sweep::workloads
  std::string missing;                   // why it was left out (empty: found)
  std::vector<std::string> grids;        // the grids that name it
};

struct Grid {
  std::string name, description;
  std::vector<std::string> scenes;   // names, keys of Sweep::scenes
  std::vector<std::string> traces;   // workload names, keys of Sweep::workloads (a grid has scenes or traces)
  std::vector<std::string> trace_sets;  // the sets the grid names (found or missing)
  std::vector<Size> resolutions, tiles;
  std::vector<uint32_t> samples;
  std::vector<std::string> producers, modes, configs;
};

struct CompareRule {
  std::string a, b;   // producer names: every point of a against the matching point of b
  bool explain = false;
  std::vector<std::string> grids;  // only points of a made by these grids (empty: all)
  std::vector<std::string> modes;  // only points of a in these visibility modes (empty: all)
};

struct Sweep {
  std::filesystem::path file;
  nlohmann::json source;                             // the file as read
  std::string description;
  std::map<std::string, Scene> scenes;               // every scene some grid uses
  std::map<std::string, TraceSet> trace_sets;        // the file's "traces"
  std::map<std::string, Workload> workloads;         // every trace file found through them
  std::vector<Producer> producers;                   // built-ins, then the file's (same name replaces)
  std::map<std::string, std::vector<std::pair<std::string, std::string>>> configs;  // name -> key=value
  std::vector<Grid> grids;
  std::vector<CompareRule> compares;
  const Producer& producer(const std::string& name) const;
};

// Where bare scene names resolve ("bunny" -> DIR/bunny.json) unless the file says scenes_dir.
std::filesystem::path default_scenes_dir();
// The source tree this binary was built from (reports/make_report.py lives there).
std::filesystem::path source_dir();

// Reads and validates a sweep file, and every trace file it names (the placeholder {out} in
// a trace set's path is `out`, the sweep's output folder). Throws SweepError naming the file
// and JSON path: also for a trace that is missing (unless its set is optional) or unreadable.
Sweep load_sweep(const std::filesystem::path& file, const std::filesystem::path& out = {});

// One line per optional trace set that was not found: what is left out, why, how to make it.
std::vector<std::string> missing_trace_lines(const Sweep& sweep);

struct Point {
  std::string scene, producer, mode, config, grid;
  Size resolution, tile;
  uint32_t samples = 1;
  std::filesystem::path dir, trace;  // dir relative to the sweep output; trace likewise (absolute for a workload's trace)
  int frame = -1;                    // a workload's trace frame; -1: a scene's trace, made by the sweep (frame 0)
  // Another point of a producer with {functional_cache} has this one's trace, frame, tile size,
  // samples and mode: {functional_cache} is the sweep's cache folder (else empty: no record kept).
  bool shares_functional = false;
};

struct CompareJob {
  size_t a = 0, b = 0;               // point indices
  bool explain = false;
  std::filesystem::path dir;         // relative: a's dir / "vs-<b producer>"
};

struct TraceJob {
  std::string scene;
  Size resolution;
  uint32_t samples = 1;
  std::filesystem::path file;        // relative to the sweep output
};

struct Plan {
  std::vector<TraceJob> traces;
  std::vector<Point> points;
  std::vector<CompareJob> compares;
};

// The cross product of every grid, identical points (same directory) once.
Plan make_plan(const Sweep& sweep);

// Command words of one job, paths made absolute under `out`.
struct Command {
  std::vector<std::string> argv;
  std::vector<std::pair<std::filesystem::path, std::filesystem::path>> renames;  // after success
  std::string shell() const;  // one shell line: quoted words, then "&& mv -f A B" per rename
};
Command trace_command(const Sweep& sweep, const TraceJob& job, const std::string& tilevis,
                      const std::filesystem::path& out);
Command point_command(const Sweep& sweep, const Point& point, const std::string& tilevis,
                      const std::filesystem::path& out);
Command compare_command(const Plan& plan, const CompareJob& job, const std::string& tilevis,
                        const std::filesystem::path& out);

// Done markers: a trace file; a point's stats.json; a compare.json newer than both sides.
bool trace_done(const TraceJob& job, const std::filesystem::path& out);
bool point_done(const Point& point, const std::filesystem::path& out);
bool compare_done(const Plan& plan, const CompareJob& job, const std::filesystem::path& out);

struct Availability {
  bool available = true;
  std::string why;                       // when not
  std::vector<std::string> param_names;  // from a probe that lists them
};

struct RunOptions {
  std::filesystem::path out;
  std::string tilevis;                   // absolute path of the binary
  unsigned jobs = 1;
  // The status line ("[done/total] % elapsed ETA running, last event"); `event` is true when
  // a job just finished (false: a periodic refresh). The caller draws it.
  std::function<void(const std::string& line, bool event)> progress;
};

struct RunSummary {
  size_t total = 0, already_done = 0, ran = 0, failed = 0, unavailable = 0, skipped = 0;
  bool interrupted = false;
  double wall_seconds = 0;
  std::vector<std::string> failures;     // one line each: job, exit status, log file
  nlohmann::json extra;                  // more members of the run's record in sweep.json (Slurm), or null
};

// Runs each producer's probe; the map is keyed by producer name (only producers in the plan).
std::map<std::string, Availability> probe_producers(const Sweep& sweep, const Plan& plan, const std::string& tilevis);

// Checks every configuration's keys against the parameter names the probes listed.
void check_params(const Sweep& sweep, const Plan& plan, const std::map<std::string, Availability>& availability);

// Writes OUT/sweep.json (the plan, producers and their availability, machine, commit).
void write_manifest(const Sweep& sweep, const Plan& plan, const std::map<std::string, Availability>& availability,
                    const RunOptions& options, const std::optional<RunSummary>& summary);

// Runs what is not done, -j at a time; traces first, points as their traces appear,
// comparisons when both sides are done. SIGINT/SIGTERM stop it cleanly (running jobs are
// terminated; their points have no stats.json and run again next time).
RunSummary run_plan(const Sweep& sweep, const Plan& plan, std::map<std::string, Availability>& availability,
                    const RunOptions& options);

// One independent command line per job that is not done, in three stages (traces, points,
// comparisons); lines within a stage are independent of each other.
void write_jobs_file(const Sweep& sweep, const Plan& plan, const std::map<std::string, Availability>& availability,
                     const RunOptions& options, const std::filesystem::path& file);

// python3 reports/make_report.py OUT (TILEVIS_REPORT_SCRIPT, TILEVIS_PYTHON override them); its
// output goes to ours. Returns its exit status.
int make_report(const std::filesystem::path& out);

// ---- Slurm (slurm.cpp): job arrays chained by dependencies, one array task per job.

struct SlurmOptions {
  std::string partition;                 // sbatch --partition, when not empty
  unsigned max_array = 0;                // tasks of one array running at once (sbatch --array=...%N); 0: no limit
  std::vector<std::string> sbatch_args;  // more sbatch words, given to every submission
};

// Submits every job not done as job arrays: traces, then points (afterok on the traces; one
// array per exclusive resource R, asking for --gres=R:1), then comparisons (afterany), then
// the report (afterany). Records the job ids in OUT/sweep.json. Refuses while jobs of an
// earlier submission are still queued or running. Returns the exit status.
int submit_slurm(const Sweep& sweep, const Plan& plan, const std::map<std::string, Availability>& availability,
                 const RunOptions& options, const SlurmOptions& slurm);

// Throws SweepError naming `action` while tasks of the sweep's Slurm submissions are queued or
// running (a local run or a second submission would run the same jobs in the same folder).
// Where squeue cannot answer: an error when `strict`, else a warning.
void check_slurm_idle(const RunOptions& options, const std::string& action, bool strict);

// Cancels (scancel) every job of every submission recorded in OUT/sweep.json.
int cancel_slurm(const RunOptions& options);

// One array task: runs the job named on line `index` of `list` (stage "traces", "points" or
// "comparisons") exactly as the local runner runs it, or, for stage "report", records the
// submission's run and makes the report. Returns the exit status.
int run_slurm_task(const Sweep& sweep, const Plan& plan, const RunOptions& options, const std::string& stage,
                   const std::filesystem::path& list, long index);

// The run record of the latest submission, for sweep.json when its report task runs: jobs
// submitted and done now (ran), submitted and not done (failed), seconds since submission.
RunSummary slurm_run_summary(const Sweep& sweep, const Plan& plan, const RunOptions& options);

// ---- Progress (status.cpp)

// What `tilevis sweep --status` prints: jobs done per stage from the point directories, queued
// and running tasks from squeue (when the sweep was submitted to Slurm), and the time left.
std::string sweep_status(const Sweep& sweep, const Plan& plan, const RunOptions& options);

// Machine and commit, as recorded with every result.
nlohmann::json machine_info();
std::string source_commit();  // "abc1234" or "abc1234-dirty"; "unknown" without git

}  // namespace tilevis::sweep
