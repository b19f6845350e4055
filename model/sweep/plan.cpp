// The plan: the cross product of every grid as points (each once, keyed by its directory),
// the traces they read, the command lines of traces and points, and their done markers.
#include <algorithm>
#include <set>
#include <tuple>

#include <fmt/format.h>

#include "sweep/detail.h"

namespace tilevis::sweep {

namespace fs = std::filesystem;
using namespace detail;

namespace {

std::string trace_file_name(const std::string& scene, Size r, uint32_t samples) {
  return fmt::format("{}-{}-s{}.tvt", scene, r.text(), samples);
}

// points/SCENE/WxH-sS/... for a scene; points/WORKLOAD/fK-WxH-sS/... for frame K of a workload's trace.
fs::path point_dir(const std::string& scene, Size res, uint32_t samples, const std::string& producer,
                   const std::string& mode, Size tile, const std::string& config, int frame = -1) {
  return fs::path("points") / scene /
         (frame < 0 ? fmt::format("{}-s{}", res.text(), samples) : fmt::format("f{}-{}-s{}", frame, res.text(), samples)) /
         (mode.empty() ? producer : producer + "-" + mode) /
         (config == "default" ? "t" + tile.text() : "t" + tile.text() + "-" + config);
}

// The points of one grid at one scene x resolution x samples (or one frame of a workload's
// trace, frame >= 0), appended unless already there.
void add_points(const Sweep& sw, const Grid& g, const std::string& scene, Size res, uint32_t samples, Plan& plan,
                std::map<fs::path, size_t>& by_dir, std::set<fs::path>& traces, int frame = -1) {
  const fs::path trace =
      frame < 0 ? fs::path("traces") / trace_file_name(scene, res, samples) : sw.workloads.at(scene).file;
  for (const std::string& pname : g.producers) {
    const Producer& pr = sw.producer(pname);
    std::vector<std::string> modes = pr.uses_mode() ? g.modes : std::vector<std::string>{""};
    std::vector<std::string> configs = pr.uses_params() ? g.configs : std::vector<std::string>{"default"};
    for (Size tile : g.tiles)
      for (const std::string& mode : modes)
        for (const std::string& config : configs) {
          Point p{scene, pname, mode, config, g.name, res, tile, samples, {}, trace, frame};
          p.dir = point_dir(scene, res, samples, pname, mode, tile, config, frame);
          if (by_dir.contains(p.dir)) continue;
          by_dir[p.dir] = plan.points.size();
          plan.points.push_back(p);
          if (frame < 0 && traces.insert(trace).second) plan.traces.push_back({scene, res, samples, trace});
        }
  }
}

}  // namespace

Plan make_plan(const Sweep& sw) {
  Plan plan;
  std::map<fs::path, size_t> by_dir;
  std::set<fs::path> traces;
  for (const Grid& g : sw.grids)
    for (const std::string& scene : g.scenes)
      for (Size res : g.resolutions)
        for (uint32_t samples : g.samples) add_points(sw, g, scene, res, samples, plan, by_dir, traces);
  // Workloads given as traces: every frame (pass) a point of its own, at its viewport and samples.
  for (const Grid& g : sw.grids)
    for (const std::string& name : g.traces) {
      const Workload& w = sw.workloads.at(name);
      for (size_t k = 0; k < w.frames.size(); ++k)
        add_points(sw, g, name, w.frames[k].viewport, w.frames[k].samples, plan, by_dir, traces, static_cast<int>(k));
    }
  // Points that may share a functional pass: a record is kept only where another point could
  // replay it (a record is megabytes, and writing one costs a run more).
  std::map<std::tuple<fs::path, int, Size, uint32_t, std::string>, size_t> functional;
  auto functional_key = [](const Point& p) { return std::make_tuple(p.trace, p.frame, p.tile, p.samples, p.mode); };
  auto uses_cache = [&](const Point& p) {
    return sw.producer(p.producer).command.find("{functional_cache}") != std::string::npos;
  };
  for (const Point& p : plan.points)
    if (uses_cache(p)) ++functional[functional_key(p)];
  for (Point& p : plan.points) p.shares_functional = uses_cache(p) && functional[functional_key(p)] > 1;
  plan_compares(sw, plan);
  return plan;
}

std::string Command::shell() const {
  std::string line;
  for (const std::string& w : argv) line += (line.empty() ? "" : " ") + shell_quote(w);
  for (const auto& [from, to] : renames) line += " && mv -f " + shell_quote(from.string()) + " " + shell_quote(to.string());
  return line;
}

Command trace_command(const Sweep& sw, const TraceJob& job, const std::string& tilevis, const fs::path& out) {
  const fs::path file = out / job.file;
  const fs::path part = file.string() + ".part";
  Command c;
  c.argv = {tilevis,        "trace", sw.scenes.at(job.scene).file.string(),  "--viewport", job.resolution.text(),
            "--samples", std::to_string(job.samples), "-q", "-o", part.string()};
  c.renames = {{part, file}};
  return c;
}

Command point_command(const Sweep& sw, const Point& p, const std::string& tilevis, const fs::path& out) {
  const Producer& pr = sw.producer(p.producer);
  Command c;
  for (const std::string& w : split_words(pr.command)) {
    if (w == "{params}") {
      for (const auto& [k, v] : sw.configs.at(p.config)) {
        c.argv.push_back("-p");
        c.argv.push_back(k + "=" + v);
      }
      continue;
    }
    std::string s = w;
    s = replace_all(s, "{tilevis}", tilevis);
    s = replace_all(s, "{trace}", (out / p.trace).string());
    s = replace_all(s, "{out}", (out / p.dir).string());
    s = replace_all(s, "{functional_cache}", p.shares_functional ? (out / "functional_cache").string() : "");
    s = replace_all(s, "{tile}", p.tile.text());
    s = replace_all(s, "{samples}", std::to_string(p.samples));
    s = replace_all(s, "{mode}", p.mode);
    s = replace_all(s, "{scene}", p.scene);
    s = replace_all(s, "{resolution}", p.resolution.text());
    s = replace_all(s, "{frame}", std::to_string(std::max(p.frame, 0)));
    c.argv.push_back(s);
  }
  return c;
}

bool trace_done(const TraceJob& job, const fs::path& out) { return fs::is_regular_file(out / job.file); }

bool point_done(const Point& p, const fs::path& out) { return fs::is_regular_file(out / p.dir / "stats.json"); }

}  // namespace tilevis::sweep
