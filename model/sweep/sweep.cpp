#include "sweep/sweep.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include <fmt/format.h>

#include "tilevis/json_node.h"

extern char** environ;

namespace tilevis::sweep {

namespace fs = std::filesystem;
using json::Node;

namespace {

[[noreturn]] void raise_sweep_error(const std::string& message) { throw SweepError(message); }

bool is_name(const std::string& s) {
  if (s.empty() || s.size() > 64 || s[0] == '.' || s[0] == '-') return false;
  return std::all_of(s.begin(), s.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
           c == '.';
  });
}

std::string name_of(const Node& n) {
  std::string s = n.string();
  if (!is_name(s)) n.fail(fmt::format("expected a name of letters, digits, '_', '-', '.', got \"{}\"", s));
  return s;
}

std::optional<Size> parse_size(const std::string& text) {
  unsigned long w = 0, h = 0;
  char x = 0, extra = 0;
  int n = std::sscanf(text.c_str(), "%lu%c%lu%c", &w, &x, &h, &extra);
  if (n == 1) h = w;
  else if (n != 3 || x != 'x') return std::nullopt;
  if (w == 0 || h == 0 || w > 65536 || h > 65536) return std::nullopt;
  return Size{static_cast<uint32_t>(w), static_cast<uint32_t>(h)};
}

// A tile: N (square) or "WxH", each side in [kMinTile, kMaxTile].
Size tile_of(const Node& n) {
  std::optional<Size> s;
  if (n.is_number()) {
    uint32_t v = n.integer(kMinTile, kMaxTile);
    s = Size{v, v};
  } else if (n.is_string()) {
    s = parse_size(n.string());
  }
  if (!s || s->width < kMinTile || s->height < kMinTile || s->width > kMaxTile || s->height > kMaxTile)
    n.fail(fmt::format("expected a tile size N or \"WxH\" with {} <= N, W, H <= {}", kMinTile, kMaxTile));
  return *s;
}

Size resolution_of(const Node& n) {
  // "WxH" only: a bare number is not a resolution (parse_size would read it as square).
  std::optional<Size> s =
      n.is_string() && n.string().find('x') != std::string::npos ? parse_size(n.string()) : std::nullopt;
  if (!s || s->width < 16 || s->height < 16 || s->width > 16384 || s->height > 16384)
    n.fail("expected a resolution \"WxH\" with 16 <= W, H <= 16384");
  return *s;
}

uint32_t samples_of(const Node& n) {
  uint32_t s = n.integer(1, 16);
  if (s != 1 && s != 2 && s != 4 && s != 8 && s != 16) n.fail(fmt::format("expected 1, 2, 4, 8 or 16, got {}", s));
  return s;
}

// A non-empty array, each element read by `f`; duplicates are an error.
template <class T, class F>
std::vector<T> list_of(const Node& n, F f) {
  if (n.array_size() == 0) n.fail("expected a non-empty array");
  std::vector<T> out;
  for (size_t i = 0; i < n.array_size(); ++i) {
    T v = f(n.at(i));
    if (std::find(out.begin(), out.end(), v) != out.end()) n.at(i).fail("duplicate value");
    out.push_back(v);
  }
  return out;
}

const std::vector<std::string>& placeholders() {
  static const std::vector<std::string> names = {"tilevis", "trace", "out",   "tile",      "samples",
                                                 "mode",    "params", "scene", "resolution"};
  return names;
}

// Every {name} in a template must be a known placeholder.
void check_template(const Node& n, const std::string& text, bool is_probe) {
  size_t pos = 0;
  while ((pos = text.find('{', pos)) != std::string::npos) {
    size_t end = text.find('}', pos);
    if (end == std::string::npos) n.fail("expected a closing '}'");
    std::string name = text.substr(pos + 1, end - pos - 1);
    const auto& known = placeholders();
    if (is_probe ? name != "tilevis" : std::find(known.begin(), known.end(), name) == known.end())
      n.fail(fmt::format("unknown placeholder {{{}}} (expected {})", name,
                         is_probe ? "{tilevis}" : "{tilevis}, {trace}, {out}, {tile}, {samples}, {mode}, {params}, "
                                                  "{scene}, {resolution}"));
    pos = end + 1;
  }
  if (!is_probe && (text.find("{out}") == std::string::npos || text.find("{trace}") == std::string::npos))
    n.fail("expected a command with {trace} and {out}");
  if (!is_probe && text.find("{params}") != std::string::npos) {
    std::istringstream words(text);
    std::string w;
    bool alone = false;
    while (words >> w) alone = alone || w == "{params}";
    if (!alone) n.fail("expected {params} as a word of its own (it becomes \"-p key=value\" words)");
  }
}

std::vector<std::string> split_words(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> words;
  std::string w;
  while (in >> w) words.push_back(w);
  return words;
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (size_t pos = 0; (pos = s.find(from, pos)) != std::string::npos; pos += to.size()) s.replace(pos, from.size(), to);
  return s;
}

std::string shell_quote(const std::string& s) {
  bool plain = !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || std::strchr("_-./=:,+@%", c);
  });
  if (plain) return s;
  return "'" + replace_all(s, "'", "'\\''") + "'";
}

std::string trace_file_name(const std::string& scene, Size r, uint32_t samples) {
  return fmt::format("{}-{}-s{}.tvt", scene, r.text(), samples);
}

}  // namespace

std::string Size::text() const { return fmt::format("{}x{}", width, height); }

const char* to_string(ProducerKind kind) {
  switch (kind) {
    case ProducerKind::visibility: return "visibility";
    case ProducerKind::truth: return "truth";
    case ProducerKind::timing: return "timing";
  }
  return "?";
}

bool Producer::uses_mode() const { return command.find("{mode}") != std::string::npos; }
bool Producer::uses_params() const { return command.find("{params}") != std::string::npos; }

std::vector<Producer> builtin_producers() {
  const std::string golden = "{tilevis} golden {trace} --tile {tile} --samples {samples}";
  const std::string sim = "{tilevis} sim {trace} --tile {tile} --samples {samples} -p sim.mode={mode} -p sim.fidelity=";
  const std::string cuda = "{tilevis} cuda {trace} --tile {tile} --samples {samples} --precision ";
  const std::string sim_probe = "{tilevis} sim --list-params";  // fails where the build has no SystemC model
  std::vector<Producer> p = {
      {"golden", golden + " -o {out}", "", "untimed SVGPU pipeline (exact)", ProducerKind::visibility, false, ""},
      {"truth", golden + " --truth -o {out}", "", "z-buffer truth, exact depth", ProducerKind::truth, false, ""},
      {"truth_q16", golden + " --truth --quantized-depth 16 -o {out}", "", "z-buffer, depth rounded to 16 bits",
       ProducerKind::truth, false, ""},
      {"truth_q24", golden + " --truth --quantized-depth 24 -o {out}", "", "z-buffer, depth rounded to 24 bits",
       ProducerKind::truth, false, ""},
      {"sim_analytic", sim + "analytic {params} -o {out}", sim_probe,
       "SystemC model, closed-form cycles per tile", ProducerKind::timing, true, ""},
      {"sim_tile", sim + "tile {params} -o {out}", sim_probe, "SystemC model, one transaction per tile per unit",
       ProducerKind::timing, true, ""},
      {"sim_primitive", sim + "primitive {params} -o {out}", sim_probe,
       "SystemC model, per-primitive transactions with back-pressure", ProducerKind::timing, true, ""},
      {"cuda_exact", cuda + "exact -o {out}", "{tilevis} cuda --help", "CUDA reference, exact arithmetic",
       ProducerKind::visibility, false, "gpu"},
      {"cuda_float", cuda + "float -o {out}", "{tilevis} cuda --help", "CUDA reference, float32 (as SVGPU)",
       ProducerKind::visibility, false, "gpu"},
  };
  return p;
}

const Producer& Sweep::producer(const std::string& name) const {
  for (const Producer& p : producers)
    if (p.name == name) return p;
  throw SweepError("no producer " + name);
}

fs::path source_dir() {
  if (const char* env = std::getenv("TILEVIS_SOURCE_DIR"); env && *env) return env;  // a relocated checkout
  return TILEVIS_SOURCE_DIR;
}
fs::path default_scenes_dir() { return source_dir() / "traces" / "scenes"; }

Sweep load_sweep(const fs::path& file) {
  Sweep sw;
  sw.file = file;
  const std::string file_name = file.string();
  sw.source = tilevis::json::parse_file(file_name, &raise_sweep_error);
  Node root(sw.source, "$", file_name, &raise_sweep_error);
  root.allow_only({"description", "scenes_dir", "scenes", "resolutions", "samples", "tiles", "modes", "producers",
                   "configs", "grids", "compare"});
  sw.description = root.string_or("description", "");
  const fs::path base = file.parent_path();
  fs::path scenes_dir = root.has("scenes_dir") ? base / root.at("scenes_dir").string() : default_scenes_dir();
  if (!fs::is_directory(scenes_dir)) {
    if (root.has("scenes_dir")) root.at("scenes_dir").fail(fmt::format("no folder {}", scenes_dir.string()));
    throw SweepError(fmt::format("{}: the built-in scene folder {} is missing", file_name, scenes_dir.string()));
  }

  // Producers: the built-ins, then the file's (a name given again replaces the built-in).
  sw.producers = builtin_producers();
  if (root.has("producers")) {
    Node ps = root.at("producers");
    for (const std::string& name : ps.keys()) {
      Node p = ps.at(name.c_str());
      if (!is_name(name)) p.fail("expected a producer name of letters, digits, '_', '-', '.'");
      p.allow_only({"command", "probe", "kind", "description", "probe_lists_params", "exclusive"});
      Producer pr;
      pr.name = name;
      pr.command = p.at("command").string();
      check_template(p.at("command"), pr.command, false);
      pr.probe = p.string_or("probe", "");
      if (!pr.probe.empty()) check_template(p.at("probe"), pr.probe, true);
      pr.description = p.string_or("description", "");
      pr.probe_lists_params = p.boolean_or("probe_lists_params", false);
      pr.exclusive = p.string_or("exclusive", "");
      if (!pr.exclusive.empty() && !is_name(pr.exclusive))
        p.at("exclusive").fail("expected a resource name of letters, digits, '_', '-', '.'");
      std::string kind = p.string_or("kind", "visibility");
      if (kind == "visibility") pr.kind = ProducerKind::visibility;
      else if (kind == "truth") pr.kind = ProducerKind::truth;
      else if (kind == "timing") pr.kind = ProducerKind::timing;
      else p.at("kind").fail("expected visibility, truth or timing");
      auto it = std::find_if(sw.producers.begin(), sw.producers.end(), [&](const Producer& q) { return q.name == name; });
      if (it != sw.producers.end()) *it = pr;
      else sw.producers.push_back(pr);
    }
  }
  auto producer_name = [&](const Node& n) {
    std::string s = n.string();
    if (std::none_of(sw.producers.begin(), sw.producers.end(), [&](const Producer& p) { return p.name == s; })) {
      std::string list;
      for (const Producer& p : sw.producers) list += (list.empty() ? "" : ", ") + p.name;
      n.fail(fmt::format("unknown producer \"{}\" (expected one of: {})", s, list));
    }
    return s;
  };

  // Unit configurations: name -> {"key": value}, passed as -p key=value.
  sw.configs["default"] = {};
  if (root.has("configs")) {
    Node cs = root.at("configs");
    for (const std::string& name : cs.keys()) {
      Node c = cs.at(name.c_str());
      if (!is_name(name)) c.fail("expected a configuration name of letters, digits, '_', '-', '.'");
      std::vector<std::pair<std::string, std::string>> params;
      for (const std::string& key : c.keys()) {
        Node v = c.at(key.c_str());
        bool key_ok = !key.empty() && std::all_of(key.begin(), key.end(), [](char ch) {
          return std::islower(static_cast<unsigned char>(ch)) || std::isdigit(static_cast<unsigned char>(ch)) ||
                 ch == '_' || ch == '.';
        });
        if (!key_ok) v.fail("expected a parameter name such as evu.reject.lanes");
        std::string value;
        if (v.is_string()) value = v.string();
        else if (v.value().is_number() || v.value().is_boolean()) value = v.value().dump();
        else v.fail("expected a number, true/false or a string");
        if (value.empty() || value.find_first_of(" \t\n") != std::string::npos) v.fail("expected a value without spaces");
        params.emplace_back(key, value);
      }
      sw.configs[name] = params;
    }
  }

  // Scenes: names in scenes_dir, paths (relative to the sweep file), or "all".
  auto scene_list = [&](const Node& n) {
    std::vector<std::string> names;
    auto add = [&](const Node& at, const std::string& name, const fs::path& path) {
      if (!fs::is_regular_file(path)) at.fail(fmt::format("no scene file {}", path.string()));
      auto it = sw.scenes.find(name);
      if (it != sw.scenes.end() && fs::weakly_canonical(it->second.file) != fs::weakly_canonical(path))
        at.fail(fmt::format("two scene files named {}: {} and {}", name, it->second.file.string(), path.string()));
      sw.scenes[name] = {name, path};
      if (std::find(names.begin(), names.end(), name) != names.end()) at.fail("duplicate scene");
      names.push_back(name);
    };
    if (n.is_string() && n.string() == "all") {
      std::vector<fs::path> files;
      for (const auto& e : fs::directory_iterator(scenes_dir))
        if (e.path().extension() == ".json") files.push_back(e.path());
      std::sort(files.begin(), files.end());
      if (files.empty()) n.fail(fmt::format("expected scene files in {}", scenes_dir.string()));
      for (const fs::path& f : files) add(n, f.stem().string(), f);
      return names;
    }
    if (n.array_size() == 0) n.fail("expected \"all\" or a non-empty array of scene names or files");
    for (size_t i = 0; i < n.array_size(); ++i) {
      Node s = n.at(i);
      std::string text = s.string();
      bool is_path = text.find('/') != std::string::npos || fs::path(text).extension() == ".json";
      fs::path path = is_path ? base / text : scenes_dir / (text + ".json");
      std::string name = fs::path(text).stem().string();
      if (!is_name(name)) s.fail("expected a scene name of letters, digits, '_', '-', '.'");
      add(s, name, path);
    }
    return names;
  };

  // Top-level axes are the defaults of every grid.
  Grid defaults;
  defaults.resolutions = {Size{1920, 1080}};
  defaults.samples = {1};
  defaults.tiles = {Size{32, 32}};
  defaults.modes = {"analytic"};
  defaults.configs = {"default"};
  if (root.has("scenes")) defaults.scenes = scene_list(root.at("scenes"));
  if (root.has("resolutions")) defaults.resolutions = list_of<Size>(root.at("resolutions"), resolution_of);
  if (root.has("samples")) defaults.samples = list_of<uint32_t>(root.at("samples"), samples_of);
  if (root.has("tiles")) defaults.tiles = list_of<Size>(root.at("tiles"), tile_of);
  if (root.has("modes")) defaults.modes = list_of<std::string>(root.at("modes"), name_of);

  Node grids = root.at("grids");
  if (grids.array_size() == 0) grids.fail("expected a non-empty array of grids");
  std::set<std::string> grid_names;
  for (size_t i = 0; i < grids.array_size(); ++i) {
    Node g = grids.at(i);
    g.allow_only({"name", "description", "scenes", "resolutions", "samples", "tiles", "producers", "modes", "configs"});
    Grid grid = defaults;
    grid.name = name_of(g.at("name"));
    if (!grid_names.insert(grid.name).second) g.at("name").fail("duplicate grid name");
    grid.description = g.string_or("description", "");
    if (g.has("scenes")) grid.scenes = scene_list(g.at("scenes"));
    if (grid.scenes.empty()) g.fail("missing required member \"scenes\" (here or at the top level)");
    if (g.has("resolutions")) grid.resolutions = list_of<Size>(g.at("resolutions"), resolution_of);
    if (g.has("samples")) grid.samples = list_of<uint32_t>(g.at("samples"), samples_of);
    if (g.has("tiles")) grid.tiles = list_of<Size>(g.at("tiles"), tile_of);
    if (g.has("modes")) grid.modes = list_of<std::string>(g.at("modes"), name_of);
    grid.producers = list_of<std::string>(g.at("producers"), producer_name);
    if (g.has("configs"))
      grid.configs = list_of<std::string>(g.at("configs"), [&](const Node& n) {
        std::string s = n.string();
        if (!sw.configs.contains(s)) n.fail(fmt::format("unknown configuration \"{}\" (define it in $.configs)", s));
        return s;
      });
    sw.grids.push_back(std::move(grid));
  }

  if (root.has("compare")) {
    Node cs = root.at("compare");
    for (size_t i = 0; i < cs.array_size(); ++i) {
      Node c = cs.at(i);
      c.allow_only({"a", "b", "explain", "grids", "modes"});
      CompareRule r{producer_name(c.at("a")), producer_name(c.at("b")), c.boolean_or("explain", false), {}, {}};
      if (r.a == r.b) c.fail("expected two different producers");
      if (c.has("grids"))
        r.grids = list_of<std::string>(c.at("grids"), [&](const Node& n) {
          std::string s = n.string();
          if (!grid_names.contains(s)) n.fail(fmt::format("unknown grid \"{}\"", s));
          return s;
        });
      if (c.has("modes")) {
        if (!sw.producer(r.a).uses_mode()) c.at("modes").fail(fmt::format("producer {} has no {{mode}}", r.a));
        r.modes = list_of<std::string>(c.at("modes"), name_of);
      }
      sw.compares.push_back(r);
    }
  }
  return sw;
}

Plan make_plan(const Sweep& sw) {
  Plan plan;
  std::map<fs::path, size_t> by_dir;
  std::set<fs::path> traces;
  for (const Grid& g : sw.grids)
    for (const std::string& scene : g.scenes)
      for (Size res : g.resolutions)
        for (uint32_t samples : g.samples) {
          fs::path trace = fs::path("traces") / trace_file_name(scene, res, samples);
          for (const std::string& pname : g.producers) {
            const Producer& pr = sw.producer(pname);
            std::vector<std::string> modes = pr.uses_mode() ? g.modes : std::vector<std::string>{""};
            std::vector<std::string> configs = pr.uses_params() ? g.configs : std::vector<std::string>{"default"};
            for (Size tile : g.tiles)
              for (const std::string& mode : modes)
                for (const std::string& config : configs) {
                  Point p;
                  p.scene = scene;
                  p.producer = pname;
                  p.mode = mode;
                  p.config = config;
                  p.grid = g.name;
                  p.resolution = res;
                  p.tile = tile;
                  p.samples = samples;
                  p.trace = trace;
                  p.dir = fs::path("points") / scene / fmt::format("{}-s{}", res.text(), samples) /
                          (mode.empty() ? pname : pname + "-" + mode) /
                          (config == "default" ? "t" + tile.text() : "t" + tile.text() + "-" + config);
                  if (by_dir.contains(p.dir)) continue;
                  by_dir[p.dir] = plan.points.size();
                  plan.points.push_back(p);
                  if (traces.insert(trace).second) plan.traces.push_back({scene, res, samples, trace});
                }
          }
        }

  // Comparisons: each point of a against the point of b with the same scene, resolution and
  // samples, preferring the same tile, mode and configuration.
  for (const CompareRule& r : sw.compares)
    for (size_t i = 0; i < plan.points.size(); ++i) {
      const Point& a = plan.points[i];
      if (a.producer != r.a) continue;
      if (!r.grids.empty() && std::find(r.grids.begin(), r.grids.end(), a.grid) == r.grids.end()) continue;
      if (!r.modes.empty() && std::find(r.modes.begin(), r.modes.end(), a.mode) == r.modes.end()) continue;
      std::optional<size_t> best;
      int best_score = -1;
      for (size_t j = 0; j < plan.points.size(); ++j) {
        const Point& b = plan.points[j];
        if (b.producer != r.b || b.scene != a.scene || b.resolution != a.resolution || b.samples != a.samples) continue;
        int score = 4 * (b.tile == a.tile) + 2 * (b.mode == a.mode || b.mode.empty()) + (b.config == a.config);
        if (score > best_score) best_score = score, best = j;
      }
      if (best) plan.compares.push_back({i, *best, r.explain, a.dir / ("vs-" + r.b)});
    }
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
    s = replace_all(s, "{tile}", p.tile.text());
    s = replace_all(s, "{samples}", std::to_string(p.samples));
    s = replace_all(s, "{mode}", p.mode);
    s = replace_all(s, "{scene}", p.scene);
    s = replace_all(s, "{resolution}", p.resolution.text());
    c.argv.push_back(s);
  }
  return c;
}

Command compare_command(const Plan& plan, const CompareJob& job, const std::string& tilevis, const fs::path& out) {
  const Point& a = plan.points[job.a];
  const Point& b = plan.points[job.b];
  const fs::path dir = out / job.dir, part = dir / ".part";
  Command c;
  c.argv = {tilevis, "compare", (out / a.dir).string(), (out / b.dir).string(), "-o", part.string()};
  if (job.explain) {
    c.argv.push_back("--explain");
    c.argv.push_back((out / a.trace).string());
  }
  c.renames = {{part / "compare.json", dir / "compare.json"}};
  return c;
}

bool trace_done(const TraceJob& job, const fs::path& out) { return fs::is_regular_file(out / job.file); }

bool point_done(const Point& p, const fs::path& out) { return fs::is_regular_file(out / p.dir / "stats.json"); }

bool compare_done(const Plan& plan, const CompareJob& job, const fs::path& out) {
  std::error_code ec;
  const fs::path c = out / job.dir / "compare.json";
  const fs::path a = out / plan.points[job.a].dir / "stats.json", b = out / plan.points[job.b].dir / "stats.json";
  if (!fs::is_regular_file(c, ec) || !fs::is_regular_file(a, ec) || !fs::is_regular_file(b, ec)) return false;
  auto tc = fs::last_write_time(c, ec);
  return tc >= fs::last_write_time(a, ec) && tc >= fs::last_write_time(b, ec);
}

// ---------------------------------------------------------------- processes

namespace {

struct Spawned {
  pid_t pid = -1;
  std::string error;
};

// Starts argv with stdin from /dev/null and stdout + stderr into `log`. The child asks the
// kernel to kill it when the sweep dies (PR_SET_PDEATHSIG), so a sweep killed with SIGKILL
// leaves no point writing into its folder; between fork and exec only async-signal-safe calls.
Spawned spawn(const std::vector<std::string>& argv, const fs::path& log) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const std::string log_path = log.string();
  const pid_t parent = getpid();
  int err_pipe[2];
  Spawned s;
  if (pipe2(err_pipe, O_CLOEXEC) != 0) {
    s.error = fmt::format("cannot start {}: {}", argv[0], std::strerror(errno));
    return s;
  }
  s.pid = fork();
  if (s.pid == 0) {
    int e = 0;
    if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || getppid() != parent) _exit(127);  // the sweep is gone already
    const int in = open("/dev/null", O_RDONLY);
    const int out = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (in < 0 || out < 0 || dup2(in, 0) < 0 || dup2(out, 1) < 0 || dup2(out, 2) < 0) {
      e = errno;
    } else {
      execvp(args[0], args.data());
      e = errno;
    }
    (void)!write(err_pipe[1], &e, sizeof e);
    _exit(127);
  }
  close(err_pipe[1]);
  if (s.pid < 0) {
    s.error = fmt::format("cannot start {}: {}", argv[0], std::strerror(errno));
    close(err_pipe[0]);
    return s;
  }
  int e = 0;
  ssize_t n;
  while ((n = read(err_pipe[0], &e, sizeof e)) < 0 && errno == EINTR) {
  }
  close(err_pipe[0]);
  if (n == ssize_t(sizeof e)) {  // exec failed: the child has exited
    int status = 0;
    while (waitpid(s.pid, &status, 0) < 0 && errno == EINTR) {
    }
    s.pid = -1;
    s.error = fmt::format("cannot start {}: {}", argv[0], std::strerror(e));
  }
  return s;
}

// Runs argv to completion; its stdout and stderr in `output`. Returns the exit status (-1: not run).
int run_capture(const std::vector<std::string>& argv, std::string* output) {
  char name[] = "/tmp/tilevis-sweep-XXXXXX";
  int fd = mkstemp(name);
  if (fd < 0) return -1;
  close(fd);
  Spawned s = spawn(argv, name);
  int status = -1;
  if (s.pid > 0) {
    while (waitpid(s.pid, &status, 0) < 0 && errno == EINTR) {
    }
  }
  if (output) {
    std::ifstream in(name);
    std::stringstream ss;
    ss << in.rdbuf();
    *output = ss.str();
  }
  std::remove(name);
  if (s.pid <= 0) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

std::string last_line(const fs::path& file) {
  std::ifstream in(file);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

std::string now_iso() {
  std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S%z", std::localtime(&t));
  return buf;
}

void write_json_atomically(const fs::path& file, const nlohmann::json& j) {
  const fs::path tmp = file.string() + ".tmp";
  {
    errno = 0;
    std::ofstream o(tmp);
    if (!o) throw SweepError(fmt::format("cannot write {}: {}", tmp.string(), std::strerror(errno ? errno : EIO)));
    o << j.dump(2) << '\n';
    if (!o) throw SweepError(fmt::format("cannot write {}: {}", tmp.string(), std::strerror(errno ? errno : EIO)));
  }
  std::error_code ec;
  fs::rename(tmp, file, ec);
  if (ec) throw SweepError(fmt::format("cannot rename {} to {}: {}", tmp.string(), file.string(), ec.message()));
}

std::string duration_text(double s) {
  if (!(s >= 0) || s > 1e7) return "?";
  auto t = static_cast<long>(s + 0.5);
  return t >= 3600 ? fmt::format("{}:{:02}:{:02}", t / 3600, t / 60 % 60, t % 60) : fmt::format("{}:{:02}", t / 60, t % 60);
}

std::atomic<int> g_stop_signal{0};
void on_stop_signal(int sig) { g_stop_signal = sig; }

}  // namespace

nlohmann::json machine_info() {
  nlohmann::json m;
  utsname u{};
  if (uname(&u) == 0) {
    m["host"] = u.nodename;
    m["os"] = fmt::format("{} {} {}", u.sysname, u.release, u.machine);
  }
  std::ifstream cpu("/proc/cpuinfo");
  for (std::string line; std::getline(cpu, line);)
    if (line.rfind("model name", 0) == 0) {
      auto colon = line.find(':');
      m["cpu"] = colon == std::string::npos ? line : line.substr(colon + 2);
      break;
    }
  m["cores"] = std::thread::hardware_concurrency();
  std::ifstream mem("/proc/meminfo");
  for (std::string line; std::getline(mem, line);)
    if (line.rfind("MemTotal:", 0) == 0) {
      m["memory_gib"] = std::round(std::stod(line.substr(9)) / (1 << 20) * 10) / 10;
      break;
    }
  return m;
}

std::string source_commit() {
  if (const char* env = std::getenv("TILEVIS_COMMIT"); env && *env) return env;  // a copy without .git
  std::string head, status;
  const std::string dir = source_dir().string();
  if (run_capture({"git", "-C", dir, "rev-parse", "--short", "HEAD"}, &head) != 0) return "unknown";
  head.erase(head.find_last_not_of(" \n\r\t") + 1);
  if (run_capture({"git", "-C", dir, "status", "--porcelain", "--untracked-files=no"}, &status) == 0 && !status.empty())
    head += "-dirty";
  return head;
}

std::map<std::string, Availability> probe_producers(const Sweep& sw, const Plan& plan, const std::string& tilevis) {
  std::map<std::string, Availability> av;
  for (const Point& p : plan.points) {
    if (av.contains(p.producer)) continue;
    const Producer& pr = sw.producer(p.producer);
    Availability a;
    if (!pr.probe.empty()) {
      std::vector<std::string> argv;
      for (const std::string& w : split_words(pr.probe)) argv.push_back(replace_all(w, "{tilevis}", tilevis));
      std::string output;
      int rc = run_capture(argv, &output);
      if (rc != 0) {
        a.available = false;
        std::string last;
        std::istringstream lines(output);
        for (std::string l; std::getline(lines, l);)
          if (!l.empty()) last = l;
        a.why = fmt::format("`{}` exited {}{}", pr.probe, rc, last.empty() ? "" : ": " + last);
      } else if (pr.probe_lists_params) {
        std::istringstream lines(output);
        for (std::string l; std::getline(lines, l);) {
          std::istringstream words(l);
          std::string first;
          if (words >> first) a.param_names.push_back(first);
        }
      }
    }
    av[p.producer] = a;
  }
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
  nlohmann::json m;
  const fs::path file = opt.out / "sweep.json";
  nlohmann::json runs = nlohmann::json::array();
  if (fs::is_regular_file(file)) {
    try {
      std::ifstream in(file);
      nlohmann::json old = nlohmann::json::parse(in);
      if (old.contains("runs") && old["runs"].is_array()) runs = old["runs"];
    } catch (const std::exception&) {
      // an unreadable old manifest only loses the run history
    }
  }
  m["sweep_file"] = fs::absolute(sw.file).string();
  m["sweep"] = sw.source;
  m["description"] = sw.description;
  m["tilevis"] = opt.tilevis;
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
  nlohmann::json grids = nlohmann::json::array();
  for (const Grid& g : sw.grids) grids.push_back({{"name", g.name}, {"description", g.description}});
  m["grids"] = grids;
  nlohmann::json points = nlohmann::json::array();
  for (const Point& p : plan.points) {
    const Command c = point_command(sw, p, opt.tilevis, opt.out);
    nlohmann::json params = nlohmann::json::object();
    if (sw.producer(p.producer).uses_params())
      for (const auto& [k, v] : sw.configs.at(p.config)) params[k] = v;
    points.push_back({{"dir", p.dir.string()},
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
                      {"command", c.shell()}});
  }
  m["points"] = points;
  nlohmann::json compares = nlohmann::json::array();
  for (const CompareJob& c : plan.compares)
    compares.push_back({{"a", plan.points[c.a].dir.string()},
                        {"b", plan.points[c.b].dir.string()},
                        {"dir", c.dir.string()},
                        {"explain", c.explain}});
  m["compares"] = compares;
  if (summary) {
    runs.push_back({{"finished", now_iso()},
                    {"commit", source_commit()},
                    {"machine", machine_info()},
                    {"jobs", opt.jobs},
                    {"total", summary->total},
                    {"already_done", summary->already_done},
                    {"ran", summary->ran},
                    {"failed", summary->failed},
                    {"unavailable", summary->unavailable},
                    {"skipped", summary->skipped},
                    {"interrupted", summary->interrupted},
                    {"wall_seconds", summary->wall_seconds}});
  }
  m["runs"] = runs;
  write_json_atomically(file, m);
}

// ---------------------------------------------------------------- the runner

namespace {

enum class JobState { pending, running, done, failed, unavailable, skipped };

struct Job {
  enum class Kind { trace, point, compare } kind;
  size_t index = 0;             // into plan.traces / points / compares
  std::string label, producer;  // producer: the ETA class ("trace", "compare" or the producer)
  std::string exclusive;        // the producer's exclusive resource, if any
  Command command;
  fs::path log;
  std::vector<size_t> deps;
  double work = 1;              // megasamples, for the ETA
  JobState state = JobState::pending;
  pid_t pid = -1;
  std::chrono::steady_clock::time_point started;
};

Job make_job(Job::Kind kind, size_t index, std::string label, std::string producer, Command command, fs::path log,
             std::vector<size_t> deps, double work) {
  Job j{};
  j.kind = kind;
  j.index = index;
  j.label = std::move(label);
  j.producer = std::move(producer);
  j.command = std::move(command);
  j.log = std::move(log);
  j.deps = std::move(deps);
  j.work = work;
  return j;
}

double megasamples(Size r, uint32_t samples) { return double(r.width) * r.height * samples / 1e6; }

}  // namespace

namespace {

// One sweep at a time per output folder: an exclusive flock on OUT/.sweep.lock, held until the
// run ends. Its descriptor is inherited by the points (no close-on-exec), so should a point
// outlive its sweep, a re-run is refused instead of starting the same point in the same folder.
class FolderLock {
 public:
  explicit FolderLock(const fs::path& out) {
    std::error_code ec;
    fs::create_directories(out, ec);
    const fs::path file = out / ".sweep.lock";
    m_fd = open(file.c_str(), O_RDWR | O_CREAT, 0644);
    if (m_fd < 0) throw SweepError(fmt::format("cannot open {}: {}", file.string(), std::strerror(errno)));
    if (flock(m_fd, LOCK_EX | LOCK_NB) != 0) {
      const int e = errno;
      close(m_fd);
      if (e == EWOULDBLOCK)
        throw SweepError(fmt::format("{} is in use by another sweep, or by points of a sweep that was killed and "
                                     "are still running: wait for them to end (they hold {})",
                                     out.string(), file.string()));
      throw SweepError(fmt::format("cannot lock {}: {}", file.string(), std::strerror(e)));
    }
  }
  ~FolderLock() { close(m_fd); }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int m_fd = -1;
};

}  // namespace

RunSummary run_plan(const Sweep& sw, const Plan& plan, std::map<std::string, Availability>& av, const RunOptions& opt) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const fs::path& out = opt.out;
  const FolderLock lock(out);
  const std::string commit = source_commit();
  const nlohmann::json machine = machine_info();
  std::vector<Job> jobs;
  std::vector<size_t> trace_job(plan.traces.size()), point_job(plan.points.size());
  for (size_t i = 0; i < plan.traces.size(); ++i) {
    const TraceJob& t = plan.traces[i];
    Job j = make_job(Job::Kind::trace, i, fmt::format("trace {} {} s{}", t.scene, t.resolution.text(), t.samples), "trace",
          trace_command(sw, t, opt.tilevis, out), out / (t.file.string() + ".log"), {}, megasamples(t.resolution, t.samples));
    if (trace_done(t, out)) j.state = JobState::done;
    trace_job[i] = jobs.size();
    jobs.push_back(std::move(j));
  }
  std::map<fs::path, size_t> trace_by_file;
  for (size_t i = 0; i < plan.traces.size(); ++i) trace_by_file[plan.traces[i].file] = trace_job[i];
  for (size_t i = 0; i < plan.points.size(); ++i) {
    const Point& p = plan.points[i];
    Job j = make_job(Job::Kind::point, i,
          fmt::format("{} {} {} s{} t{}{}{}", p.producer, p.scene, p.resolution.text(), p.samples, p.tile.text(),
                      p.mode.empty() ? "" : " " + p.mode, p.config == "default" ? "" : " " + p.config),
          p.producer, point_command(sw, p, opt.tilevis, out), out / p.dir / "run.log", {trace_by_file.at(p.trace)},
          megasamples(p.resolution, p.samples));
    j.exclusive = sw.producer(p.producer).exclusive;
    if (point_done(p, out)) j.state = JobState::done;
    else if (!av.at(p.producer).available) j.state = JobState::unavailable;
    point_job[i] = jobs.size();
    jobs.push_back(std::move(j));
  }
  for (size_t i = 0; i < plan.compares.size(); ++i) {
    const CompareJob& c = plan.compares[i];
    const Point &a = plan.points[c.a], &b = plan.points[c.b];
    Job j = make_job(Job::Kind::compare, i, fmt::format("compare {} vs {}", a.dir.string(), b.producer), "compare",
          compare_command(plan, c, opt.tilevis, out), out / c.dir / "compare.log", {point_job[c.a], point_job[c.b]},
          megasamples(a.resolution, a.samples));
    if (compare_done(plan, c, out)) j.state = JobState::done;
    jobs.push_back(std::move(j));
  }

  RunSummary sum;
  sum.total = jobs.size();
  for (const Job& j : jobs) sum.already_done += j.state == JobState::done;

  // Seconds per megasample, by ETA class, from the jobs that finished in this run.
  std::map<std::string, std::pair<double, double>> rate;  // class -> (seconds, megasamples)
  auto estimate = [&](const Job& j) {
    auto it = rate.find(j.producer);
    double s = 0, w = 0;
    if (it != rate.end()) s = it->second.first, w = it->second.second;
    else
      for (const auto& [k, v] : rate) s += v.first, w += v.second;
    return w > 0 ? s / w * j.work : -1.0;
  };
  auto status_line = [&](const std::string& event) {
    size_t finished = 0, running = 0;
    double remaining = 0;
    bool known = true;
    const auto now = Clock::now();
    for (const Job& j : jobs) {
      if (j.state == JobState::pending || j.state == JobState::running) {
        double e = estimate(j);
        if (e < 0) known = false;
        if (j.state == JobState::running) {
          ++running;
          e -= std::chrono::duration<double>(now - j.started).count();
        }
        remaining += std::max(e, 0.0);
      } else {
        ++finished;
      }
    }
    double elapsed = std::chrono::duration<double>(now - t0).count();
    std::string eta = known ? duration_text(remaining / std::max(1u, opt.jobs)) : "?";
    return fmt::format("[{}/{}] {:3.0f} %  elapsed {}  ETA {}  running {}{}{}", finished, jobs.size(),
                       100.0 * double(finished) / double(std::max<size_t>(1, jobs.size())), duration_text(elapsed),
                       eta, running, event.empty() ? "" : "  ", event);
  };
  auto report = [&](const std::string& event) {
    if (opt.progress) opt.progress(status_line(event), !event.empty());
  };

  struct sigaction sa {}, old_int {}, old_term {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;
  g_stop_signal = 0;
  sigaction(SIGINT, &sa, &old_int);
  sigaction(SIGTERM, &sa, &old_term);

  auto mark_producer_unavailable = [&](const std::string& producer, const std::string& why) {
    av[producer].available = false;
    av[producer].why = why;
    for (Job& k : jobs)
      if (k.kind == Job::Kind::point && k.producer == producer && k.state == JobState::pending)
        k.state = JobState::unavailable;
  };
  auto deps_state = [&](const Job& j) {
    bool all_done = true;
    for (size_t d : j.deps) {
      JobState s = jobs[d].state;
      if (s == JobState::failed || s == JobState::unavailable || s == JobState::skipped) return JobState::skipped;
      all_done = all_done && s == JobState::done;
    }
    return all_done ? JobState::done : JobState::pending;
  };

  report(sum.already_done ? fmt::format("{} already done", sum.already_done) : "");
  size_t running = 0;
  std::set<std::string> held;  // exclusive resources in use
  auto last_report = Clock::now();
  while (true) {
    if (g_stop_signal) break;
    // Start the ready jobs, the largest first (traces before anything else).
    std::vector<size_t> ready;
    for (size_t i = 0; i < jobs.size(); ++i) {
      Job& j = jobs[i];
      if (j.state != JobState::pending) continue;
      JobState d = deps_state(j);
      if (d == JobState::skipped) {
        j.state = JobState::skipped;
        continue;
      }
      if (d == JobState::done) ready.push_back(i);
    }
    std::stable_sort(ready.begin(), ready.end(), [&](size_t a, size_t b) {
      if ((jobs[a].kind == Job::Kind::trace) != (jobs[b].kind == Job::Kind::trace))
        return jobs[a].kind == Job::Kind::trace;
      return jobs[a].work > jobs[b].work;
    });
    for (size_t i : ready) {
      if (running >= opt.jobs) break;
      Job& j = jobs[i];
      if (!j.exclusive.empty() && held.count(j.exclusive)) continue;
      std::error_code ec;
      fs::create_directories(j.log.parent_path(), ec);
      for (const auto& [from, to] : j.command.renames) fs::create_directories(from.parent_path(), ec);
      Spawned s = spawn(j.command.argv, j.log);
      if (s.pid < 0) {
        j.state = JobState::failed;
        sum.failures.push_back(fmt::format("{}: {}", j.label, s.error));
        continue;
      }
      j.pid = s.pid;
      j.state = JobState::running;
      j.started = Clock::now();
      if (!j.exclusive.empty()) held.insert(j.exclusive);
      ++running;
    }
    if (running == 0) break;

    int status = 0;
    rusage ru{};
    pid_t pid = wait4(-1, &status, WNOHANG, &ru);
    if (pid == 0 || (pid < 0 && errno == EINTR)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      if (Clock::now() - last_report > std::chrono::seconds(1)) {
        last_report = Clock::now();
        report("");
      }
      continue;
    }
    if (pid < 0) break;
    auto it = std::find_if(jobs.begin(), jobs.end(), [&](const Job& j) { return j.pid == pid && j.state == JobState::running; });
    if (it == jobs.end()) continue;
    Job& j = *it;
    --running;
    held.erase(j.exclusive);
    j.pid = -1;
    const double wall = std::chrono::duration<double>(Clock::now() - j.started).count();
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::string event;
    if (code == 0) {
      std::error_code ec;
      for (const auto& [from, to] : j.command.renames) {
        fs::rename(from, to, ec);
        if (ec) break;
      }
      bool complete = !ec;
      if (j.kind == Job::Kind::point) complete = complete && point_done(plan.points[j.index], out);
      if (complete) {
        j.state = JobState::done;
        ++sum.ran;
        auto& r = rate[j.producer];
        r.first += wall;
        r.second += j.work;
        if (j.kind == Job::Kind::point) {
          const double cpu = double(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
                             1e-6 * double(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
          write_json_atomically(out / plan.points[j.index].dir / "process.json",
                                {{"command", j.command.shell()},
                                 {"wall_seconds", wall},
                                 {"cpu_seconds", cpu},
                                 {"max_rss_mib", double(ru.ru_maxrss) / 1024.0},
                                 {"finished", now_iso()},
                                 {"commit", commit},
                                 {"machine", machine}});
        }
        event = fmt::format("done {} ({:.1f} s)", j.label, wall);
      } else {
        j.state = JobState::failed;
        sum.failures.push_back(fmt::format("{}: exited 0 but left no complete result{} (log {})", j.label,
                                           ec ? ": " + ec.message() : "", j.log.string()));
        event = "FAILED " + j.label;
      }
    } else if (code == 2 && j.kind == Job::Kind::point && !point_done(plan.points[j.index], out)) {
      // Exit status 2 with nothing written: the producer cannot run here (e.g. no GPU).
      j.state = JobState::unavailable;
      mark_producer_unavailable(j.producer, last_line(j.log));
      event = fmt::format("{} unavailable here: {}", j.producer, last_line(j.log));
    } else if (g_stop_signal || (WIFSIGNALED(status) && WTERMSIG(status) == SIGINT)) {
      // Ctrl-C reaches the whole process group: the job was interrupted with the sweep
      // (perhaps reaped before our own handler ran) and runs again next time.
      if (!g_stop_signal) g_stop_signal = SIGINT;
      j.state = JobState::pending;
    } else {
      j.state = JobState::failed;
      std::string why = WIFSIGNALED(status) ? fmt::format("killed by signal {}", WTERMSIG(status))
                                            : fmt::format("exit status {}", code);
      sum.failures.push_back(fmt::format("{}: {}: {} (log {})", j.label, why, last_line(j.log), j.log.string()));
      event = "FAILED " + j.label;
    }
    last_report = Clock::now();
    report(event);
  }

  if (g_stop_signal) {
    sum.interrupted = true;
    for (Job& j : jobs)
      if (j.state == JobState::running && j.pid > 0) kill(j.pid, SIGTERM);
    for (Job& j : jobs)
      if (j.state == JobState::running && j.pid > 0) {
        int status = 0;
        while (waitpid(j.pid, &status, 0) < 0 && errno == EINTR) {
        }
        j.state = JobState::pending;
      }
  }
  sigaction(SIGINT, &old_int, nullptr);
  sigaction(SIGTERM, &old_term, nullptr);

  for (const Job& j : jobs) {
    sum.failed += j.state == JobState::failed;
    sum.unavailable += j.state == JobState::unavailable;
    sum.skipped += j.state == JobState::skipped;
  }
  sum.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return sum;
}

void write_jobs_file(const Sweep& sw, const Plan& plan, const std::map<std::string, Availability>& av,
                     const RunOptions& opt, const fs::path& file) {
  std::ostringstream o;
  const std::string sweep_file = fs::absolute(sw.file).lexically_normal().string();
  o << "# tilevis sweep " << sweep_file << " -o " << opt.out.string() << ": one command line per job not yet done.\n"
    << "# Lines within a stage are independent of each other; run the stages in order. A point is done when its\n"
    << "# stats.json exists (written last, atomically); afterwards make the report with:\n"
    << "#   " << shell_quote(opt.tilevis) << " sweep " << shell_quote(sweep_file) << " -o "
    << shell_quote(opt.out.string()) << " --report-only\n";
  size_t n = 0;
  o << "# stage 1: traces\n";
  for (const TraceJob& t : plan.traces)
    if (!trace_done(t, opt.out)) {
      o << "mkdir -p " << shell_quote((opt.out / t.file).parent_path().string()) << " && "
        << trace_command(sw, t, opt.tilevis, opt.out).shell() << '\n';
      ++n;
    }
  o << "# stage 2: points\n";
  for (const Point& p : plan.points) {
    if (point_done(p, opt.out)) continue;
    const Availability& a = av.at(p.producer);
    if (!a.available) {
      o << "# unavailable here (" << a.why << "): " << point_command(sw, p, opt.tilevis, opt.out).shell() << '\n';
      continue;
    }
    o << point_command(sw, p, opt.tilevis, opt.out).shell();
    if (const std::string& r = sw.producer(p.producer).exclusive; !r.empty())
      o << "  # exclusive: " << r << " (one such job at a time, for honest timings)";
    o << '\n';
    ++n;
  }
  o << "# stage 3: comparisons\n";
  for (const CompareJob& c : plan.compares) {
    if (compare_done(plan, c, opt.out) || !av.at(plan.points[c.a].producer).available ||
        !av.at(plan.points[c.b].producer).available)
      continue;
    o << compare_command(plan, c, opt.tilevis, opt.out).shell() << '\n';
    ++n;
  }
  o << "# " << n << " jobs\n";
  if (file.has_parent_path()) fs::create_directories(file.parent_path());
  std::ofstream f(file);
  f << o.str();
  if (!f) throw SweepError("cannot write " + file.string());
}

}  // namespace tilevis::sweep
