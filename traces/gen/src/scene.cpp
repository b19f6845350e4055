#include "tilevis/scene.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <list>
#include <map>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <fmt/std.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat4x4.hpp>
#include <nlohmann/json.hpp>

#include "json_node.h"
#include "mesh.h"

namespace tilevis::scene {

namespace {
// The folders found at configure time, unless the environment names others (a binary run on
// another machine with the meshes copied along).
std::filesystem::path dir_from_env(const char* name, const char* configured) {
  const char* env = std::getenv(name);
  return env && *env ? env : configured;
}
}  // namespace

std::filesystem::path glmark2_models_dir() { return dir_from_env("TILEVIS_GLMARK2_MODELS", TILEVIS_GLMARK2_MODELS); }
std::filesystem::path cgal_meshes_dir() { return dir_from_env("TILEVIS_CGAL_MESHES", TILEVIS_CGAL_MESHES); }

namespace {

constexpr double kBig = 1e9;

struct Camera {
  glm::dvec3 eye{0, 0, 3}, target{0, 0, 0}, up{0, 1, 0};
  double fov_y_deg = 45, near = 0.1, far = 100;
  uint32_t orbit_frames = 1;
  double orbit_degrees = 360;
  glm::dvec3 orbit_axis{0, 1, 0};
};

struct Object {
  std::string name;
  const Mesh* mesh = nullptr;
  std::vector<glm::dmat4> instances;  // object-to-world, one per draw
  uint32_t flags = 0;
  float shader_cycles = 1;
  uint32_t varying_bytes = 16, texture_bytes = 0;
};

glm::dmat4 parse_transform(const Node& n) {
  n.allow_only({"translate", "rotate_deg", "scale"});
  glm::dvec3 t = vec3_or(n, "translate", {0, 0, 0});
  glm::dvec3 r = vec3_or(n, "rotate_deg", {0, 0, 0});
  glm::dvec3 s = n.has("scale") ? vec3_or_scalar(n.at("scale")) : glm::dvec3(1);
  if (s.x == 0 || s.y == 0 || s.z == 0) n.at("scale").fail("expected a non-zero scale");
  glm::dmat4 m = glm::translate(glm::dmat4(1), t);
  m = glm::rotate(m, glm::radians(r.z), {0, 0, 1});
  m = glm::rotate(m, glm::radians(r.y), {0, 1, 0});
  m = glm::rotate(m, glm::radians(r.x), {1, 0, 0});
  return glm::scale(m, s);
}

Camera parse_camera(const Node& n) {
  n.allow_only({"eye", "target", "up", "fov_y_deg", "near", "far", "orbit"});
  Camera c;
  c.eye = vec3_or(n, "eye", c.eye);
  c.target = vec3_or(n, "target", c.target);
  c.up = vec3_or(n, "up", c.up);
  c.fov_y_deg = n.number_or("fov_y_deg", c.fov_y_deg, 1, 179);
  c.near = n.number_or("near", c.near, 1e-6, kBig);
  c.far = n.number_or("far", c.far, 1e-6, kBig);
  if (c.far <= c.near) n.at("far").fail(fmt::format("expected far > near ({})", c.near));
  if (glm::length(c.eye - c.target) == 0) n.at("eye").fail("expected eye != target");
  if (glm::length(glm::cross(c.target - c.eye, c.up)) == 0) n.at("up").fail("expected up not parallel to the view direction");
  if (n.has("orbit")) {
    Node o = n.at("orbit");
    o.allow_only({"frames", "degrees", "axis"});
    c.orbit_frames = o.integer_or("frames", 1, 1, 10000);
    c.orbit_degrees = o.number_or("degrees", 360, -36000, 36000);
    c.orbit_axis = vec3_or(o, "axis", c.orbit_axis);
    if (glm::length(c.orbit_axis) == 0) o.at("axis").fail("expected a non-zero axis");
  }
  return c;
}

uint32_t parse_flags(const Node& n) {
  static const std::map<std::string, uint32_t> names = {
      {"opaque", 0},
      {"alpha_tested", trace::kAlphaTested},
      {"blended", trace::kBlended},
      {"writes_depth", trace::kShaderWritesDepth},
      {"discards", trace::kShaderDiscards},
      {"soup", trace::kTriangleSoup},
      {"sample_rate", trace::kSampleRateShading}};
  uint32_t flags = 0;
  for (size_t i = 0; i < n.array_size(); ++i) {
    Node f = n.at(i);
    auto it = names.find(f.string());
    if (it == names.end()) f.fail("expected one of opaque, alpha_tested, blended, writes_depth, discards, soup");
    flags |= it->second;
  }
  return flags;
}

class SceneBuilder {
 public:
  SceneBuilder(const std::filesystem::path& file, const BuildOptions& options)
      : m_file(file.string()), m_dir(file.parent_path()), m_options(options) {}

  trace::Trace build() {
    const nlohmann::json doc = json::parse_file(m_file, &raise_scene_error);
    Node root(doc, "$", m_file, &raise_scene_error);
    root.allow_only({"description", "viewport", "samples", "depth_range", "camera", "objects"});

    trace::Frame proto;
    if (root.has("viewport")) {
      Node v = root.at("viewport");
      if (v.array_size() != 2) v.fail("expected [width, height]");
      proto.width = v.at(size_t{0}).integer(1, trace::kMaxViewport);
      proto.height = v.at(1).integer(1, trace::kMaxViewport);
    }
    uint32_t samples = root.integer_or("samples", 1, 1, trace::kMaxSamples);
    if (root.has("depth_range")) {
      Node d = root.at("depth_range");
      if (d.array_size() != 2) d.fail("expected [near, far]");
      proto.depth_near = static_cast<float>(d.at(size_t{0}).number(0, 1));
      proto.depth_far = static_cast<float>(d.at(1).number(0, 1));
    }
    if (m_options.width) proto.width = *m_options.width;
    if (m_options.height) proto.height = *m_options.height;
    if (m_options.samples) samples = *m_options.samples;
    try {
      proto.samples = trace::standard_samples(samples, proto.subpixel_bits);
    } catch (const std::invalid_argument&) {
      throw SceneError(fmt::format("{}: $.samples: expected 1, 2, 4, 8 or 16, got {}", m_file, samples));
    }

    Camera camera = root.has("camera") ? parse_camera(root.at("camera")) : Camera{};
    Node objects = root.at("objects");
    std::vector<Object> objs;
    for (size_t i = 0; i < objects.array_size(); ++i) objs.push_back(parse_object(objects.at(i)));

    trace::Trace t;
    t.source = fmt::format("tilevis trace {}", m_file);
    for (uint32_t f = 0; f < camera.orbit_frames; ++f) {
      trace::Frame frame = proto;
      double angle = glm::radians(camera.orbit_degrees) * f / camera.orbit_frames;
      glm::dmat4 orbit = glm::rotate(glm::dmat4(1), angle, glm::normalize(camera.orbit_axis));
      glm::dvec3 eye = camera.target + glm::dvec3(orbit * glm::dvec4(camera.eye - camera.target, 0));
      glm::dmat4 view = glm::lookAt(eye, camera.target, camera.up);
      glm::dmat4 proj = glm::perspective(glm::radians(camera.fov_y_deg), double(frame.width) / frame.height,
                                         camera.near, camera.far);
      for (const Object& o : objs) {
        const size_t n_parts = std::max<size_t>(1, o.mesh->parts.size());
        for (size_t k = 0; k < o.instances.size(); ++k)
          for (size_t part = 0; part < n_parts; ++part) {
          trace::Draw d;
          d.name = o.instances.size() == 1 ? o.name : fmt::format("{}#{}", o.name, k);
          if (!o.mesh->parts.empty()) d.name += "/" + o.mesh->parts[part].name;
          d.flags = o.flags;
          d.shader_cycles_per_fragment = o.shader_cycles;
          d.varying_bytes_per_vertex = o.varying_bytes;
          d.texture_bytes_per_fragment = o.texture_bytes;
          glm::dmat4 mvp = proj * view * o.instances[k];
          d.vertices.reserve(o.mesh->positions.size());
          for (size_t vi = 0; vi < o.mesh->positions.size(); ++vi) {
            const glm::dvec3& p = o.mesh->positions[vi];
            glm::dvec4 c = mvp * glm::dvec4(p, 1);
            const double big = std::max({std::fabs(c.x), std::fabs(c.y), std::fabs(c.z), std::fabs(c.w)});
            if (!(big <= double(std::numeric_limits<float>::max())))
              throw SceneError(fmt::format("{}: object \"{}\": vertex {} at ({}, {}, {}): expected a finite position "
                                           "whose clip-space coordinates fit in float (got {})",
                                           m_file, o.name, vi, p.x, p.y, p.z, big));
            d.vertices.push_back({float(c.x), float(c.y), float(c.z), float(c.w)});
          }
          d.indices = o.mesh->indices;
          if (!o.mesh->parts.empty()) {  // this part's triangles over the vertices they use
            const Mesh::Part& p = o.mesh->parts[part];
            std::vector<uint32_t> local(d.vertices.size(), ~0u);
            std::vector<trace::Vec4> used;
            d.indices.clear();
            for (size_t i = p.first; i < p.first + p.count; ++i) {
              const uint32_t vi = o.mesh->indices[i];
              if (local[vi] == ~0u) {
                local[vi] = uint32_t(used.size());
                used.push_back(d.vertices[vi]);
              }
              d.indices.push_back(local[vi]);
            }
            d.vertices = std::move(used);
          }
          // A mirroring transform (negative determinant: an odd number of negative scales) turns
          // the mesh inside out; keep its outside facing out by reversing the winding.
          if (glm::determinant(glm::dmat3(o.instances[k])) < 0) {
            for (size_t i = 0; i + 2 < d.indices.size(); i += 3) std::swap(d.indices[i + 1], d.indices[i + 2]);
            if (f == 0 && m_options.warn)
              m_options.warn(fmt::format("{}: object \"{}\"{}: its transform mirrors it (negative determinant); "
                                         "triangle winding reversed so that its front faces stay in front",
                                         m_file, o.name, o.instances.size() == 1 ? "" : fmt::format(" instance {}", k)));
          }
          frame.draws.push_back(std::move(d));
          }
      }
      t.frames.push_back(std::move(frame));
      report(fmt::format("frame {}/{} built", f + 1, camera.orbit_frames));
    }
    trace::validate(t, m_file);
    return t;
  }

 private:
  void report(const std::string& what) const {
    if (m_options.progress) m_options.progress(what);
  }

  const Mesh* load_mesh(const Node& n, bool fit) {
    std::string ref = n.string();
    std::filesystem::path path;
    if (ref.starts_with("glmark2/"))
      path = glmark2_models_dir() / ref.substr(8);
    else if (ref.starts_with("cgal/"))
      path = cgal_meshes_dir() / ref.substr(5);
    else
      path = m_dir / ref;
    std::string key = path.string() + (fit ? "#fit" : "");
    auto it = m_meshes.find(key);
    if (it != m_meshes.end()) return &it->second;
    if (!std::filesystem::is_regular_file(path)) {
      const auto dir = path.parent_path();
      std::string hint;
      if (ref.starts_with("glmark2/") || ref.starts_with("cgal/")) {
        if (!std::filesystem::is_directory(dir)) {
          hint = ref.starts_with("glmark2/") ? " (install Debian package glmark2-data)"
                                             : " (install libcgal-demo and re-run cmake)";
        } else {  // the package is there: name what it holds
          std::vector<std::string> names;
          for (const auto& e : std::filesystem::directory_iterator(dir))
            if (e.is_regular_file() && e.path().filename().string()[0] != '.') names.push_back(e.path().filename());
          std::sort(names.begin(), names.end());
          if (names.size() > 12) names.resize(12), names.push_back("...");
          hint = fmt::format(" (no such mesh in {}; it holds {})", dir, fmt::join(names, ", "));
        }
      }
      n.fail(fmt::format("mesh file {} not found{}", path, hint));
    }
    Mesh m;
    try {
      m = import_mesh(path);
    } catch (const std::exception& e) {
      n.fail(e.what());
    }
    if (fit) m.fit_unit();
    report(fmt::format("loaded {} ({} triangles)", ref, m.triangle_count()));
    return &m_meshes.emplace(key, std::move(m)).first->second;
  }

  const Mesh* make_primitive(const Node& p) {
    std::string type = p.at("type").string();
    Mesh m;
    if (type == "box") {
      p.allow_only({"type", "size"});
      m = make_box(p.has("size") ? vec3_or_scalar(p.at("size")) : glm::dvec3(1));
    } else if (type == "plane") {
      p.allow_only({"type", "size", "subdivisions"});
      m = make_plane(p.has("size") ? vec2_or_scalar(p.at("size")) : glm::dvec2(1),
                     p.integer_or("subdivisions", 1, 1, 4096));
    } else if (type == "sphere") {
      p.allow_only({"type", "radius", "segments", "rings"});
      m = make_sphere(p.number_or("radius", 0.5, 1e-9, kBig), p.integer_or("segments", 32, 3, 8192),
                      p.integer_or("rings", 16, 2, 8192));
    } else if (type == "quads") {
      p.allow_only({"type", "count", "size", "origin", "step"});
      m = make_quads(p.integer_or("count", 1, 1, 10'000'000),
                     p.has("size") ? vec2_or_scalar(p.at("size")) : glm::dvec2(1), vec3_or(p, "origin", {0, 0, 0}),
                     vec3_or(p, "step", {0, 0, -0.01}));
    } else if (type == "cornell_box") {
      p.allow_only({"type", "size"});
      m = make_cornell_box(p.has("size") ? vec3_or_scalar(p.at("size")) : glm::dvec3(1));
    } else {
      p.at("type").fail("expected one of box, plane, sphere, quads, cornell_box");
    }
    m_primitives.push_back(std::move(m));
    return &m_primitives.back();
  }

  Object parse_object(const Node& n) {
    n.allow_only({"name", "mesh", "fit", "primitive", "transform", "instances", "grid", "flags", "shader_cycles",
                  "varying_bytes", "texture_bytes"});
    Object o;
    o.name = n.has("name") ? n.at("name").string() : fmt::format("object{}", m_object_count);
    ++m_object_count;
    if (o.name.size() > 200) n.at("name").fail("expected at most 200 bytes");
    if (n.has("mesh") == n.has("primitive")) n.fail("expected exactly one of \"mesh\" and \"primitive\"");
    if (n.has("mesh")) {
      bool fit = n.has("fit") ? n.at("fit").boolean() : true;
      o.mesh = load_mesh(n.at("mesh"), fit);
    } else {
      o.mesh = make_primitive(n.at("primitive"));
    }
    glm::dmat4 model = n.has("transform") ? parse_transform(n.at("transform")) : glm::dmat4(1);
    if (n.has("instances") && n.has("grid")) n.fail("expected at most one of \"instances\" and \"grid\"");
    if (n.has("instances")) {
      Node list = n.at("instances");
      for (size_t i = 0; i < list.array_size(); ++i) o.instances.push_back(parse_transform(list.at(i)) * model);
      if (o.instances.empty()) list.fail("expected at least one instance");
    } else if (n.has("grid")) {
      Node g = n.at("grid");
      g.allow_only({"count", "spacing"});
      Node c = g.at("count");
      if (c.array_size() != 3) c.fail("expected [nx, ny, nz]");
      uint32_t nx = c.at(size_t{0}).integer(1, 1000), ny = c.at(1).integer(1, 1000), nz = c.at(2).integer(1, 1000);
      if (uint64_t(nx) * ny * nz > 100000) c.fail("expected at most 100000 instances");
      glm::dvec3 sp = vec3_or(g, "spacing", {1, 1, 1});
      for (uint32_t z = 0; z < nz; ++z)
        for (uint32_t y = 0; y < ny; ++y)
          for (uint32_t x = 0; x < nx; ++x) {
            glm::dvec3 off((x - (nx - 1) * 0.5) * sp.x, (y - (ny - 1) * 0.5) * sp.y, (z - (nz - 1) * 0.5) * sp.z);
            o.instances.push_back(glm::translate(glm::dmat4(1), off) * model);
          }
    } else {
      o.instances.push_back(model);
    }
    if (n.has("flags")) o.flags = parse_flags(n.at("flags"));
    o.shader_cycles = static_cast<float>(n.number_or("shader_cycles", 1, 0, 1e6));
    o.varying_bytes = n.integer_or("varying_bytes", 16, 0, 1u << 16);
    o.texture_bytes = n.integer_or("texture_bytes", 0, 0, 1u << 16);
    return o;
  }

  std::string m_file;
  std::filesystem::path m_dir;
  const BuildOptions& m_options;
  std::map<std::string, Mesh> m_meshes;
  std::list<Mesh> m_primitives;
  size_t m_object_count = 0;
};

}  // namespace

trace::Trace build_trace(const std::filesystem::path& scene_file, const BuildOptions& options) {
  return SceneBuilder(scene_file, options).build();
}

}  // namespace tilevis::scene
