// The sweep file: reading and validating it (reports/sweeps/README.md). Every error names the
// file and the JSON path, e.g. "demo.json: $.grids[2].tiles[0]: expected ...".
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "sweep/detail.h"
#include "tilevis/json_node.h"
#include "tilevis/trace.h"

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
  static const std::vector<std::string> names = {"tilevis", "trace", "out",   "tile",       "samples",
                                                 "mode",    "params", "scene", "resolution", "frame",
                                                 "functional_cache"};
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
                                                  "{scene}, {resolution}, {frame}, {functional_cache}"));
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
bool Producer::uses_frame() const { return command.find("{frame}") != std::string::npos; }

std::vector<Producer> builtin_producers() {
  const std::string golden = "{tilevis} golden {trace} --frame {frame} --tile {tile} --samples {samples}";
  // The sweep's points of one trace, frame, tile size, mode and functional parameters share one
  // functional pass (sim.functional_cache): the first computes it, the others replay it.
  const std::string sim =
      "{tilevis} sim {trace} --frame {frame} --tile {tile} --samples {samples} -p sim.mode={mode} "
      "-p sim.functional_cache={functional_cache} -p sim.fidelity=";
  const std::string cuda = "{tilevis} cuda {trace} --frame {frame} --tile {tile} --samples {samples} --precision ";
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

namespace {

const char* const kNameRule = "letters, digits, '_', '-', '.'";

ProducerKind kind_of(const Node& p) {
  const std::string kind = p.string_or("kind", "visibility");
  if (kind == "visibility") return ProducerKind::visibility;
  if (kind == "truth") return ProducerKind::truth;
  if (kind == "timing") return ProducerKind::timing;
  p.at("kind").fail("expected visibility, truth or timing");
}

Producer producer_of(const std::string& name, const Node& p) {
  if (!is_name(name)) p.fail(fmt::format("expected a producer name of {}", kNameRule));
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
    p.at("exclusive").fail(fmt::format("expected a resource name of {}", kNameRule));
  pr.kind = kind_of(p);
  return pr;
}

// One unit configuration: {"key": value} -> key=value pairs for -p.
std::vector<std::pair<std::string, std::string>> params_of(const Node& c) {
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
  return params;
}

// Reads one sweep file into `sw`, part by part, in the order the parts depend on each other.
class Loader {
 public:
  Loader(Sweep& sw, const Node& root, fs::path out)
      : m_sw(sw), m_root(root), m_base(sw.file.parent_path()), m_out(std::move(out)) {}

  void load() {
    m_root.allow_only({"description", "scenes_dir", "scenes", "resolutions", "samples", "tiles", "modes", "producers",
                       "configs", "traces", "grids", "compare"});
    m_sw.description = m_root.string_or("description", "");
    find_scenes_dir();
    read_producers();
    read_configs();
    read_trace_sets();
    read_grids(read_defaults());
    check_workloads();
    read_compares();
  }

 private:
  void find_scenes_dir() {
    m_scenes_dir = m_root.has("scenes_dir") ? m_base / m_root.at("scenes_dir").string() : default_scenes_dir();
    if (fs::is_directory(m_scenes_dir)) return;
    if (m_root.has("scenes_dir")) m_root.at("scenes_dir").fail(fmt::format("no folder {}", m_scenes_dir.string()));
    throw SweepError(
        fmt::format("{}: the built-in scene folder {} is missing", m_sw.file.string(), m_scenes_dir.string()));
  }

  // The built-ins, then the file's (a name given again replaces the built-in).
  void read_producers() {
    m_sw.producers = builtin_producers();
    if (!m_root.has("producers")) return;
    Node ps = m_root.at("producers");
    for (const std::string& name : ps.keys()) {
      Producer pr = producer_of(name, ps.at(name.c_str()));
      auto it = std::find_if(m_sw.producers.begin(), m_sw.producers.end(),
                             [&](const Producer& q) { return q.name == name; });
      if (it != m_sw.producers.end()) *it = pr;
      else m_sw.producers.push_back(pr);
    }
  }

  std::string producer_name(const Node& n) const {
    std::string s = n.string();
    const auto& ps = m_sw.producers;
    if (std::none_of(ps.begin(), ps.end(), [&](const Producer& p) { return p.name == s; })) {
      std::string list;
      for (const Producer& p : ps) list += (list.empty() ? "" : ", ") + p.name;
      n.fail(fmt::format("unknown producer \"{}\" (expected one of: {})", s, list));
    }
    return s;
  }

  // Unit configurations: name -> {"key": value}, passed as -p key=value.
  void read_configs() {
    m_sw.configs["default"] = {};
    if (!m_root.has("configs")) return;
    Node cs = m_root.at("configs");
    for (const std::string& name : cs.keys()) {
      Node c = cs.at(name.c_str());
      if (!is_name(name)) c.fail(fmt::format("expected a configuration name of {}", kNameRule));
      m_sw.configs[name] = params_of(c);
    }
  }

  void add_scene(std::vector<std::string>& names, const Node& at, const std::string& name, const fs::path& path) {
    if (!fs::is_regular_file(path)) at.fail(fmt::format("no scene file {}", path.string()));
    auto it = m_sw.scenes.find(name);
    if (it != m_sw.scenes.end() && fs::weakly_canonical(it->second.file) != fs::weakly_canonical(path))
      at.fail(fmt::format("two scene files named {}: {} and {}", name, it->second.file.string(), path.string()));
    m_sw.scenes[name] = {name, path};
    if (std::find(names.begin(), names.end(), name) != names.end()) at.fail("duplicate scene");
    names.push_back(name);
  }

  // Scenes: names in scenes_dir, paths (relative to the sweep file), or "all".
  std::vector<std::string> scene_list(const Node& n) {
    std::vector<std::string> names;
    if (n.is_string() && n.string() == "all") {
      std::vector<fs::path> files;
      for (const auto& e : fs::directory_iterator(m_scenes_dir))
        if (e.path().extension() == ".json") files.push_back(e.path());
      std::sort(files.begin(), files.end());
      if (files.empty()) n.fail(fmt::format("expected scene files in {}", m_scenes_dir.string()));
      for (const fs::path& f : files) add_scene(names, n, f.stem().string(), f);
      return names;
    }
    if (n.array_size() == 0) n.fail("expected \"all\" or a non-empty array of scene names or files");
    for (size_t i = 0; i < n.array_size(); ++i) {
      Node s = n.at(i);
      std::string text = s.string();
      bool is_path = text.find('/') != std::string::npos || fs::path(text).extension() == ".json";
      fs::path path = is_path ? m_base / text : m_scenes_dir / (text + ".json");
      std::string name = fs::path(text).stem().string();
      if (!is_name(name)) s.fail(fmt::format("expected a scene name of {}", kNameRule));
      add_scene(names, s, name, path);
    }
    return names;
  }

  // ---- Workloads given as traces ("traces": {"NAME": {"path": ..., "optional": ..., "make": ...}})

  // {out} in a trace set's text: the sweep's output folder.
  std::string expand_out(const Node& at, const std::string& text) const {
    if (text.find("{out}") == std::string::npos) return text;
    if (m_out.empty()) at.fail("{out} needs the sweep's output folder");
    return detail::replace_all(text, "{out}", m_out.string());
  }

  void read_trace_sets() {
    if (!m_root.has("traces")) return;
    Node sets = m_root.at("traces");
    sets.expect_object();
    for (const std::string& name : sets.keys()) {
      Node t = sets.at(name.c_str());
      if (!is_name(name)) t.fail(fmt::format("expected a trace set name of {}", kNameRule));
      t.allow_only({"path", "optional", "make", "description"});
      TraceSet set;
      set.name = name;
      set.description = t.string_or("description", "");
      set.optional = t.boolean_or("optional", false);
      set.path_text = t.at("path").string();
      if (set.path_text.empty()) t.at("path").fail("expected a .tvt file or a folder of them");
      for (const char* key : {"path", "make"})
        if (t.has(key) && detail::replace_all(t.at(key).string(), "{out}", "").find('{') != std::string::npos)
          t.at(key).fail("unknown placeholder (expected only {out})");
      set.path = m_base / expand_out(t.at("path"), set.path_text);
      set.make = t.has("make") ? expand_out(t.at("make"), t.at("make").string()) : "";
      find_traces(t, set);
      m_sw.trace_sets[name] = set;
    }
  }

  // The trace files of a set: the file, or every .tvt in the folder (sorted). Missing: an
  // error naming how to make them, or (optional) the set is recorded as missing.
  void find_traces(const Node& t, TraceSet& set) {
    std::error_code ec;
    std::vector<fs::path> files;
    std::string missing;
    if (fs::is_directory(set.path, ec)) {
      for (const auto& e : fs::directory_iterator(set.path, ec))
        if (e.path().extension() == ".tvt" && e.is_regular_file(ec)) files.push_back(e.path());
      std::sort(files.begin(), files.end());
      if (files.empty()) missing = fmt::format("the folder {} holds no .tvt file", set.path.string());
    } else if (fs::is_regular_file(set.path, ec)) {
      files.push_back(set.path);
    } else {
      missing = fmt::format("no trace file or folder {}", set.path.string());
    }
    const std::string how = set.make.empty() ? "make traces with `tilevis capture` (traces/capture/README.md)"
                                             : "make them with: " + set.make;
    if (!missing.empty()) {
      if (!set.optional) t.at("path").fail(fmt::format("{}; {}", missing, how));
      set.missing = missing;
      return;
    }
    for (const fs::path& f : files) {
      Workload w;
      w.name = f.stem().string();
      w.set = set.name;
      w.file = fs::absolute(f).lexically_normal();
      if (!is_name(w.name))
        t.at("path").fail(fmt::format("trace {}: expected a file name of {} (it names the workload)", f.string(),
                                      kNameRule));
      if (auto it = m_sw.workloads.find(w.name); it != m_sw.workloads.end())
        t.at("path").fail(fmt::format("two traces named {}: {} and {}", w.name, it->second.file.string(),
                                      w.file.string()));
      read_trace(t, w, how);
      set.workloads.push_back(w.name);
      m_sw.workloads[w.name] = std::move(w);
    }
  }

  // What a sweep needs of a trace: its frames' viewports, samples and triangle counts. The
  // reader rejects every malformed file with its offset and expectation.
  static void read_trace(const Node& t, Workload& w, const std::string& how) {
    trace::Trace tr;
    try {
      tr = trace::read(w.file.string());
    } catch (const std::exception& e) {
      t.at("path").fail(fmt::format("not a valid trace: {}; {}", e.what(), how));
    }
    w.source = tr.source;
    for (const trace::Frame& f : tr.frames) {
      TraceFrame tf;
      tf.viewport = {f.width, f.height};
      tf.samples = static_cast<uint32_t>(f.samples.size());
      tf.draws = static_cast<uint32_t>(f.draws.size());
      for (const trace::Draw& d : f.draws) {
        tf.triangles += d.triangle_count();
        if (!d.opaque()) tf.non_occluding_triangles += d.triangle_count();
        if (d.per_pixel_only()) tf.per_pixel_triangles += d.triangle_count();
      }
      w.frames.push_back(tf);
    }
  }

  // A grid's "traces": names of trace sets (their workloads, each once).
  std::vector<std::string> trace_list(const Node& n, Grid& g) {
    std::vector<std::string> names;
    g.trace_sets = list_of<std::string>(n, [&](const Node& e) {
      std::string s = e.string();
      if (!m_sw.trace_sets.contains(s)) e.fail(fmt::format("unknown trace set \"{}\" (define it in $.traces)", s));
      return s;
    });
    for (const std::string& s : g.trace_sets) {
      TraceSet& set = m_sw.trace_sets.at(s);
      set.grids.push_back(g.name);
      for (const std::string& w : set.workloads)
        if (std::find(names.begin(), names.end(), w) == names.end()) names.push_back(w);
    }
    return names;
  }

  // A workload's name is its points' folder: no scene may have it. A trace of several frames
  // needs producers that take {frame}.
  void check_workloads() const {
    for (const auto& [name, w] : m_sw.workloads) {
      const Node at = m_root.at("traces").at(w.set.c_str()).at("path");
      if (m_sw.scenes.contains(name))
        at.fail(fmt::format("trace {} has the name of scene {} ({}): rename one", w.file.string(), name,
                            m_sw.scenes.at(name).file.string()));
    }
    for (size_t i = 0; i < m_sw.grids.size(); ++i) {
      const Grid& g = m_sw.grids[i];
      for (const std::string& wname : g.traces) {
        const Workload& w = m_sw.workloads.at(wname);
        if (w.frames.size() < 2) continue;
        for (const std::string& p : g.producers)
          if (!m_sw.producer(p).uses_frame())
            m_root.at("grids").at(i).at("producers").fail(
                fmt::format("producer {} has no {{frame}}, so it cannot run frames other than 0 of trace {} "
                            "({} frames)", p, w.file.string(), w.frames.size()));
      }
    }
  }

  // The axes besides scenes a grid may set; at the top level they are the defaults of every grid.
  void read_axes(const Node& n, Grid& g) {
    if (n.has("resolutions")) g.resolutions = list_of<Size>(n.at("resolutions"), resolution_of);
    if (n.has("samples")) g.samples = list_of<uint32_t>(n.at("samples"), samples_of);
    if (n.has("tiles")) g.tiles = list_of<Size>(n.at("tiles"), tile_of);
    if (n.has("modes")) g.modes = list_of<std::string>(n.at("modes"), name_of);
  }

  Grid read_defaults() {
    Grid defaults;
    defaults.resolutions = {Size{1920, 1080}};
    defaults.samples = {1};
    defaults.tiles = {Size{32, 32}};
    defaults.modes = {"analytic"};
    defaults.configs = {"default"};
    if (m_root.has("scenes")) defaults.scenes = scene_list(m_root.at("scenes"));
    read_axes(m_root, defaults);
    return defaults;
  }

  Grid read_grid(const Node& g, const Grid& defaults) {
    g.allow_only({"name", "description", "scenes", "traces", "resolutions", "samples", "tiles", "producers", "modes",
                  "configs"});
    Grid grid = defaults;
    grid.name = name_of(g.at("name"));
    if (!m_grid_names.insert(grid.name).second) g.at("name").fail("duplicate grid name");
    grid.description = g.string_or("description", "");
    if (g.has("traces")) {
      // A trace keeps its own viewport and samples: a grid of traces has no scenes and no such axes.
      for (const char* key : {"scenes", "resolutions", "samples"})
        if (g.has(key))
          g.at(key).fail(fmt::format("expected no {} in a grid of traces (each trace frame keeps its own viewport and "
                                     "samples)", key));
      grid.scenes.clear();
      grid.traces = trace_list(g.at("traces"), grid);
    } else {
      if (g.has("scenes")) grid.scenes = scene_list(g.at("scenes"));
      if (grid.scenes.empty())
        g.fail("missing required member \"scenes\" (here or at the top level) or \"traces\"");
    }
    read_axes(g, grid);
    grid.producers = list_of<std::string>(g.at("producers"), [&](const Node& n) { return producer_name(n); });
    if (g.has("configs"))
      grid.configs = list_of<std::string>(g.at("configs"), [&](const Node& n) {
        std::string s = n.string();
        if (!m_sw.configs.contains(s)) n.fail(fmt::format("unknown configuration \"{}\" (define it in $.configs)", s));
        return s;
      });
    return grid;
  }

  void read_grids(const Grid& defaults) {
    Node grids = m_root.at("grids");
    if (grids.array_size() == 0) grids.fail("expected a non-empty array of grids");
    for (size_t i = 0; i < grids.array_size(); ++i) m_sw.grids.push_back(read_grid(grids.at(i), defaults));
  }

  CompareRule read_compare(const Node& c) const {
    c.allow_only({"a", "b", "explain", "grids", "modes"});
    CompareRule r{producer_name(c.at("a")), producer_name(c.at("b")), c.boolean_or("explain", false), {}, {}};
    if (r.a == r.b) c.fail("expected two different producers");
    if (c.has("grids"))
      r.grids = list_of<std::string>(c.at("grids"), [&](const Node& n) {
        std::string s = n.string();
        if (!m_grid_names.contains(s)) n.fail(fmt::format("unknown grid \"{}\"", s));
        return s;
      });
    if (c.has("modes")) {
      if (!m_sw.producer(r.a).uses_mode()) c.at("modes").fail(fmt::format("producer {} has no {{mode}}", r.a));
      r.modes = list_of<std::string>(c.at("modes"), name_of);
    }
    return r;
  }

  void read_compares() {
    if (!m_root.has("compare")) return;
    Node cs = m_root.at("compare");
    for (size_t i = 0; i < cs.array_size(); ++i) m_sw.compares.push_back(read_compare(cs.at(i)));
  }

  Sweep& m_sw;
  Node m_root;
  fs::path m_base, m_scenes_dir, m_out;
  std::set<std::string> m_grid_names;
};

}  // namespace

Sweep load_sweep(const fs::path& file, const fs::path& out) {
  Sweep sw;
  sw.file = file;
  const std::string file_name = file.string();
  sw.source = tilevis::json::parse_file(file_name, &raise_sweep_error);
  const Node root(sw.source, "$", file_name, &raise_sweep_error);
  Loader(sw, root, out).load();
  return sw;
}

std::vector<std::string> missing_trace_lines(const Sweep& sw) {
  std::vector<std::string> lines;
  for (const auto& [name, set] : sw.trace_sets) {
    if (set.missing.empty()) continue;
    std::string grids;
    for (const std::string& g : set.grids) grids += (grids.empty() ? "" : ", ") + g;
    lines.push_back(fmt::format("traces \"{}\" ({}) are missing: {}; their points{} are left out{}", name,
                                set.path_text, set.missing, grids.empty() ? "" : " (grids " + grids + ")",
                                set.make.empty() ? "" : ". To make them: " + set.make));
  }
  return lines;
}

}  // namespace tilevis::sweep
