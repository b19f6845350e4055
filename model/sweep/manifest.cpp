// What a sweep records about itself: the producers' availability (their probes), the
// configurations' keys checked against the parameters a probe lists, and OUT/sweep.json.
#include <algorithm>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "sweep/detail.h"

namespace tilevis::sweep {

namespace fs = std::filesystem;
using namespace detail;

namespace {

Availability probe(const Producer& pr, const std::string& tilevis) {
  Availability a;
  if (pr.probe.empty()) return a;
  std::vector<std::string> argv;
  for (const std::string& w : split_words(pr.probe)) argv.push_back(replace_all(w, "{tilevis}", tilevis));
  std::string output;
  int rc = run_capture(argv, &output);
  if (rc != 0) {
    a.available = false;
    const std::string last = last_line_of_text(output);
    a.why = fmt::format("`{}` exited {}{}", pr.probe, rc, last.empty() ? "" : ": " + last);
  } else if (pr.probe_lists_params) {
    std::istringstream lines(output);
    for (std::string l; std::getline(lines, l);) {
      std::istringstream words(l);
      std::string first;
      if (words >> first) a.param_names.push_back(first);
    }
  }
  return a;
}

nlohmann::json point_record(const Sweep& sw, const Point& p, const RunOptions& opt) {
  const Command c = point_command(sw, p, opt.tilevis, opt.out);
  nlohmann::json params = nlohmann::json::object();
  if (sw.producer(p.producer).uses_params())
    for (const auto& [k, v] : sw.configs.at(p.config)) params[k] = v;
  nlohmann::json r = {{"dir", p.dir.string()},
          {"scene", p.scene},
          {"resolution", p.resolution.text()},
          {"width", p.resolution.width},
          {"height", p.resolution.height},
          {"samples", p.samples},
          {"tile", p.tile.text()},
          {"tile_w", p.tile.width},
          {"tile_h", p.tile.height},
          {"producer", p.producer},
          {"kind", to_string(sw.producer(p.producer).kind)},
          {"mode", p.mode},
          {"config", p.config},
          {"params", params},
          {"grid", p.grid},
          {"trace", p.trace.string()},
          {"command", c.shell()}};
  if (p.frame >= 0) r["frame"] = p.frame;  // a workload's trace frame (scene points have none)
  return r;
}

nlohmann::json run_record(const RunSummary& s, const RunOptions& opt) {
  nlohmann::json r = {{"finished", now_iso()},
          {"commit", source_commit()},
          {"machine", machine_info()},
          {"jobs", opt.jobs},
          {"total", s.total},
          {"already_done", s.already_done},
          {"ran", s.ran},
          {"failed", s.failed},
          {"unavailable", s.unavailable},
          {"skipped", s.skipped},
          {"interrupted", s.interrupted},
          {"wall_seconds", s.wall_seconds}};
  if (s.extra.is_object()) r.update(s.extra);
  return r;
}

// The sweep file's producers, configurations, scenes and grids as the manifest lists them.
void describe_sweep(const Sweep& sw, const std::map<std::string, Availability>& av, nlohmann::json& m) {
  nlohmann::json producers = nlohmann::json::object();
  for (const Producer& p : sw.producers) {
    if (!av.contains(p.name)) continue;
    const Availability& a = av.at(p.name);
    producers[p.name] = {{"command", p.command},     {"kind", to_string(p.kind)}, {"description", p.description},
                         {"available", a.available}, {"why", a.why}};
  }
  m["producers"] = producers;
  nlohmann::json configs = nlohmann::json::object();
  for (const auto& [name, params] : sw.configs) {
    nlohmann::json c = nlohmann::json::object();
    for (const auto& [k, v] : params) c[k] = v;
    configs[name] = c;
  }
  m["configs"] = configs;
  nlohmann::json scenes = nlohmann::json::object();
  for (const auto& [name, s] : sw.scenes) scenes[name] = fs::absolute(s.file).string();
  m["scenes"] = scenes;
  // Workloads given as traces: what the sweep read of each (per frame), and the sets that were
  // missing (their points are not in the plan; the report says so).
  nlohmann::json workloads = nlohmann::json::object();
  for (const auto& [name, w] : sw.workloads) {
    nlohmann::json frames = nlohmann::json::array();
    for (const TraceFrame& f : w.frames)
      frames.push_back({{"resolution", f.viewport.text()},
                        {"width", f.viewport.width},
                        {"height", f.viewport.height},
                        {"samples", f.samples},
                        {"draws", f.draws},
                        {"triangles", f.triangles},
                        {"non_occluding_triangles", f.non_occluding_triangles},
                        {"per_pixel_triangles", f.per_pixel_triangles}});
    workloads[name] = {{"file", w.file.string()}, {"set", w.set}, {"source", w.source}, {"frames", frames}};
  }
  m["workloads"] = workloads;
  nlohmann::json sets = nlohmann::json::object();
  for (const auto& [name, s] : sw.trace_sets)
    sets[name] = {{"path", s.path_text},        {"resolved", fs::absolute(s.path).lexically_normal().string()},
                  {"optional", s.optional},     {"make", s.make},
                  {"description", s.description}, {"workloads", s.workloads},
                  {"grids", s.grids},           {"missing", s.missing}};
  m["trace_sets"] = sets;
  nlohmann::json grids = nlohmann::json::array();
  for (const Grid& g : sw.grids)
    grids.push_back({{"name", g.name}, {"description", g.description}, {"trace_sets", g.trace_sets}});
  m["grids"] = grids;
}

}  // namespace

std::map<std::string, Availability> probe_producers(const Sweep& sw, const Plan& plan, const std::string& tilevis) {
  std::map<std::string, Availability> av;
  for (const Point& p : plan.points)
    if (!av.contains(p.producer)) av[p.producer] = probe(sw.producer(p.producer), tilevis);
  return av;
}

void check_params(const Sweep& sw, const Plan& plan, const std::map<std::string, Availability>& av) {
  std::set<std::pair<std::string, std::string>> checked;
  const std::string file_name = sw.file.string();
  for (const Point& p : plan.points) {
    const auto it = av.find(p.producer);
    if (it == av.end() || !it->second.available || it->second.param_names.empty()) continue;
    if (!checked.insert({p.producer, p.config}).second) continue;
    for (const auto& [key, value] : sw.configs.at(p.config)) {
      const auto& names = it->second.param_names;
      if (std::find(names.begin(), names.end(), key) == names.end())
        throw SweepError(fmt::format("{}: $.configs.{}[\"{}\"]: unknown parameter of {} (see `{}`)", file_name,
                                     p.config, key, p.producer,
                                     replace_all(sw.producer(p.producer).probe, "{tilevis}", "tilevis")));
    }
  }
}

void write_manifest(const Sweep& sw, const Plan& plan, const std::map<std::string, Availability>& av,
                    const RunOptions& opt, const std::optional<RunSummary>& summary) {
  fs::create_directories(opt.out);
  const fs::path file = opt.out / "sweep.json";
  // Kept from the manifest before: the run history and the Slurm submissions (an unreadable
  // old manifest only loses them).
  const nlohmann::json old = read_json_or_null(file);
  nlohmann::json runs = old.is_object() && old.contains("runs") && old["runs"].is_array() ? old["runs"]
                                                                                          : nlohmann::json::array();
  nlohmann::json m;
  m["sweep_file"] = fs::absolute(sw.file).string();
  m["sweep"] = sw.source;
  m["description"] = sw.description;
  m["tilevis"] = opt.tilevis;
  describe_sweep(sw, av, m);
  nlohmann::json points = nlohmann::json::array();
  for (const Point& p : plan.points) points.push_back(point_record(sw, p, opt));
  m["points"] = points;
  nlohmann::json compares = nlohmann::json::array();
  for (const CompareJob& c : plan.compares)
    compares.push_back({{"a", plan.points[c.a].dir.string()},
                        {"b", plan.points[c.b].dir.string()},
                        {"dir", c.dir.string()},
                        {"explain", c.explain}});
  m["compares"] = compares;
  if (summary) runs.push_back(run_record(*summary, opt));
  m["runs"] = runs;
  if (old.is_object() && old.contains("slurm")) m["slurm"] = old["slurm"];
  write_json_atomically(file, m);
}

}  // namespace tilevis::sweep
