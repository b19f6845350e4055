// tilevis capture: runs an OpenGL program under TileVis's interposer (traces/capture) and
// turns the draws of the chosen frames into a trace; tilevis compare-depth: the captured
// application's own depth buffer against the exact truth's depth of that trace (issue 17).
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

#include <fmt/format.h>

#include "commands.h"
#include "dump.h"
#include "geom/homogeneous.h"
#include "tilevis/trace.h"
#include "visibility/setup.h"
#include "visibility/truth.h"

namespace tilevis::app {
namespace {

namespace fs = std::filesystem;
using namespace tilevis::capture;

// ---- the depth file written beside the trace (OUT.depth) --------------------------------
// "TVDEPTH1", u32 frame_count, then per frame: u32 width, u32 height, f32 clear, u32 bits,
// u32 draw_count, u8 per draw (kDepth* bits), f32 depth[width × height] rows top-down (the
// trace's window rows). Host byte order: it is read on the machine that captured it.
constexpr char kDepthMagic[8] = {'T', 'V', 'D', 'E', 'P', 'T', 'H', '1'};
enum DrawDepthBit : uint8_t {
  kDepthWrites = 1,         // depth test on, depth writes on: the application's depth holds it
  kDepthPolygonOffset = 2,
  kDepthClamp = 4,
  kDepthScissor = 8,
  kDepthStencil = 16,
  kDepthCleared = 32,       // drawn before a later depth clear of the same frame
};

struct AppDepth {
  uint32_t width = 0, height = 0, bits = 0;
  float clear = 1.0f;
  std::vector<uint8_t> draw_bits;
  std::vector<float> depth;  // rows top-down
};

void write_depth_file(const std::string& path, const std::vector<AppDepth>& frames) {
  std::ofstream f(path, std::ios::binary);
  auto u32 = [&](uint32_t v) { f.write(reinterpret_cast<const char*>(&v), 4); };
  f.write(kDepthMagic, 8);
  u32(uint32_t(frames.size()));
  for (const auto& d : frames) {
    u32(d.width), u32(d.height);
    f.write(reinterpret_cast<const char*>(&d.clear), 4);
    u32(d.bits), u32(uint32_t(d.draw_bits.size()));
    f.write(reinterpret_cast<const char*>(d.draw_bits.data()), std::streamsize(d.draw_bits.size()));
    f.write(reinterpret_cast<const char*>(d.depth.data()), std::streamsize(d.depth.size() * 4));
  }
  if (!f) throw std::runtime_error(path + ": cannot write");
}

std::vector<AppDepth> read_depth_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path + ": cannot read");
  char magic[8];
  f.read(magic, 8);
  if (!f || memcmp(magic, kDepthMagic, 8) != 0) throw std::runtime_error(path + ": not a TileVis depth file");
  auto u32 = [&] {
    uint32_t v = 0;
    f.read(reinterpret_cast<char*>(&v), 4);
    if (!f) throw std::runtime_error(path + ": truncated");
    return v;
  };
  std::vector<AppDepth> frames(u32());
  for (auto& d : frames) {
    d.width = u32(), d.height = u32();
    if (d.width > trace::kMaxViewport || d.height > trace::kMaxViewport) throw std::runtime_error(path + ": bad size");
    f.read(reinterpret_cast<char*>(&d.clear), 4);
    d.bits = u32();
    d.draw_bits.resize(u32());
    f.read(reinterpret_cast<char*>(d.draw_bits.data()), std::streamsize(d.draw_bits.size()));
    d.depth.resize(size_t(d.width) * d.height);
    f.read(reinterpret_cast<char*>(d.depth.data()), std::streamsize(d.depth.size() * 4));
    if (!f) throw std::runtime_error(path + ": truncated");
  }
  return frames;
}

// ---- reading the interposer's dump --------------------------------------------------------

class DumpReader {
 public:
  explicit DumpReader(const std::string& path) : m_path(path), m_f(path, std::ios::binary) {
    char magic[8];
    m_f.read(magic, 8);
    if (!m_f || memcmp(magic, kDumpMagic, 8) != 0)
      throw std::runtime_error(path + ": the capture wrote nothing (did the program draw with OpenGL?)");
  }
  bool next_tag(uint32_t& tag) {
    m_f.read(reinterpret_cast<char*>(&tag), 4);
    return bool(m_f);
  }
  uint32_t u32() {
    uint32_t v = 0;
    read(&v, 4);
    return v;
  }
  float f32() {
    float v = 0;
    read(&v, 4);
    return v;
  }
  std::string str() {
    std::string s(u32(), '\0');
    if (s.size() > (1u << 20)) throw std::runtime_error(m_path + ": corrupt record");
    read(s.data(), s.size());
    return s;
  }
  template <class T>
  void array(std::vector<T>& v, size_t n) {
    if (n > (size_t(1) << 31)) throw std::runtime_error(m_path + ": corrupt record");
    v.resize(n);
    read(v.data(), n * sizeof(T));
  }

 private:
  void read(void* p, size_t n) {
    m_f.read(static_cast<char*>(p), std::streamsize(n));
    if (!m_f) throw std::runtime_error(m_path + ": ends inside a record (the program stopped mid-frame)");
  }
  std::string m_path;
  std::ifstream m_f;
};

std::string state_names(uint32_t s) {
  std::string r;
  auto add = [&](const std::string& t) { r += " " + t; };
  if (!(s & kStateDepthTest)) add("depth-test-off");
  else if (s & kStateDepthFuncAlways) add("depth-always");
  else if (s & kStateDepthFuncOther) add("depth-func-other");
  if (!(s & kStateDepthWrite)) add("depth-write-off");
  if (s & kStateBlend) add("blend");
  if (s & kStateAlphaTest) add("alpha-test");
  if (!(s & kStateCullEnabled)) add("cull-off");
  else if ((s & kStateCullFront) && (s & kStateCullBack)) add("cull-all");
  else if (s & kStateCullFront) add("cull-front");
  if (s & kStateFrontCw) add("front-cw");
  if (s & kStateScissor) add("scissor");
  if (s & kStateColorMaskNone) add("colour-mask-none");
  if (s & kStatePolygonOffset) add("polygon-offset");
  if (s & kStateDepthClamp) add("depth-clamp");
  if (s & kStateStencil) add("stencil");
  return r;
}

struct CaptureSummary {
  std::map<std::string, uint64_t> skipped;  // reason -> draws
  uint64_t draws = 0, triangles = 0, non_occluding_draws = 0, non_occluding_triangles = 0;
};

// One dump draw into a trace draw of a frame of `width` x `height` (the window) with depth
// range [near, far]: the draw's viewport and depth range become affine maps of clip space,
// and GL's facing rules become the trace's (counter-clockwise in NDC is front, back faces are
// culled): triangles GL draws are turned front-facing, those it culls back-facing.
// A frame whose depth_near is negative takes the first draw's depth range.
trace::Draw convert_draw(DumpReader& in, trace::Frame& frame, uint32_t& state) {
  const uint32_t width = frame.width, height = frame.height;
  float range_out[2];
  trace::Draw d;
  d.name = in.str();
  d.flags = in.u32();
  state = in.u32();
  int32_t vp[4];
  for (auto& v : vp) v = int32_t(in.u32());
  range_out[0] = in.f32(), range_out[1] = in.f32();
  if (frame.depth_near < 0) frame.depth_near = range_out[0], frame.depth_far = range_out[1];
  const float near = frame.depth_near, far = frame.depth_far;
  std::vector<float> v;
  in.array(v, size_t(in.u32()) * 4);
  in.array(d.indices, in.u32());
  // Viewport: window x = vx + (ndc + 1) vw / 2 = (ndc' + 1) W / 2, so ndc' = ndc·vw/W +
  // (2vx + vw)/W − 1, which is x' = x·vw/W + w·((2vx + vw)/W − 1) in clip space (y alike, GL's
  // window y is up and so is NDC's).
  const double sx = double(vp[2]) / width, ox = (2.0 * vp[0] + vp[2]) / width - 1.0;
  const double sy = double(vp[3]) / height, oy = (2.0 * vp[1] + vp[3]) / height - 1.0;
  // Depth range: d = n + (f − n)(z/w + 1)/2 must equal n' + (f' − n')(z'/w + 1)/2.
  const double n = range_out[0], f = range_out[1];
  const double sz = (far != near) ? (f - n) / (double(far) - near) : 1.0;
  const double oz = (far != near) ? (n + f - near - far) / (double(far) - near) : 0.0;
  const bool identity = vp[0] == 0 && vp[1] == 0 && uint32_t(vp[2]) == width && uint32_t(vp[3]) == height &&
                        n == near && f == far;
  d.vertices.resize(v.size() / 4);
  for (size_t i = 0; i < d.vertices.size(); ++i) {
    const double x = v[4 * i], y = v[4 * i + 1], z = v[4 * i + 2], w = v[4 * i + 3];
    auto& o = d.vertices[i];
    o.w = float(w);
    if (identity) {
      o.x = float(x), o.y = float(y), o.z = float(z);
    } else {
      o.x = float(x * sx + w * ox);
      o.y = float(y * sy + w * oy);
      o.z = float(z * sz + w * oz);
    }
    if (!std::isfinite(o.x) || !std::isfinite(o.y) || !std::isfinite(o.z) || !std::isfinite(o.w)) o = {0, 0, 0, 1};
  }
  for (uint32_t idx : d.indices)
    if (idx >= d.vertices.size()) throw std::runtime_error("capture: an index outside its draw's vertices");
  // Facing. GL front = counter-clockwise in window space unless glFrontFace(GL_CW).
  const bool cull = state & kStateCullEnabled;
  for (size_t t = 0; t + 2 < d.indices.size(); t += 3) {
    const auto& a = d.vertices[d.indices[t]];
    const auto& b = d.vertices[d.indices[t + 1]];
    const auto& c = d.vertices[d.indices[t + 2]];
    const int o = geom::homogeneous_orientation(a.x, a.y, a.w, b.x, b.y, b.w, c.x, c.y, c.w);
    if (o == 0) continue;  // edge-on: setup culls it whatever its winding
    const bool gl_front = (o > 0) != bool(state & kStateFrontCw);
    const bool drawn = !cull || (gl_front ? !(state & kStateCullFront) : !(state & kStateCullBack));
    const bool want_ccw = drawn;  // drawn: front-facing for the trace; culled: back-facing
    if ((o > 0) != want_ccw) std::swap(d.indices[t + 1], d.indices[t + 2]);
  }
  // What does not write depth in the application never occludes there: non-opaque in the trace.
  if (!(state & kStateDepthTest) || !(state & kStateDepthWrite)) d.flags |= trace::kBlended;
  d.name += state_names(state);
  return d;
}

uint8_t depth_bits_of(uint32_t state) {
  uint8_t b = 0;
  if ((state & kStateDepthTest) && (state & kStateDepthWrite)) b |= kDepthWrites;
  if (state & kStatePolygonOffset) b |= kDepthPolygonOffset;
  if (state & kStateDepthClamp) b |= kDepthClamp;
  if (state & kStateScissor) b |= kDepthScissor;
  if (state & kStateStencil) b |= kDepthStencil;
  return b;
}

std::string library_path() {
  if (const char* p = getenv("TILEVIS_CAPTURE_LIBRARY"); p && *p) return p;
  return TILEVIS_CAPTURE_LIBRARY;
}

bool on_path(const std::string& name) {
  const char* path = getenv("PATH");
  if (!path) return false;
  std::string p = path;
  size_t s = 0;
  while (s <= p.size()) {
    size_t e = p.find(':', s);
    if (e == std::string::npos) e = p.size();
    if (access((p.substr(s, e - s) + "/" + name).c_str(), X_OK) == 0) return true;
    s = e + 1;
  }
  return false;
}

int run_program(const std::vector<std::string>& argv, int timeout_s) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("capture: fork failed");
  if (pid == 0) {
    setpgid(0, 0);
    execvp(args[0], args.data());
    fmt::print(stderr, "tilevis: error: capture: cannot run {}: {}\n", args[0], strerror(errno));
    _exit(127);
  }
  setpgid(pid, pid);
  int status = 0;
  for (int waited = 0;; ++waited) {
    const pid_t r = waitpid(pid, &status, WNOHANG);
    if (r == pid) break;
    if (waited >= timeout_s * 10) {
      kill(-pid, SIGTERM);
      usleep(500000);
      kill(-pid, SIGKILL);
      waitpid(pid, &status, 0);
      throw std::runtime_error(fmt::format("capture: the program ran past --timeout {} s", timeout_s));
    }
    usleep(100000);
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// ---- the comparison -------------------------------------------------------------------

// Window depth of the plane of clip-space triangle (a, b, c) at the pixel centre (px, py) in
// NDC: λ = M⁻¹ (px, py, 1) with M's columns (x, y, w) of the vertices gives the homogeneous
// barycentrics whose w sum is 1, so z/w = Σ λ z (no division by a vertex w: valid behind
// the eye too).
bool plane_depth(const trace::Vec4& a, const trace::Vec4& b, const trace::Vec4& c, double px, double py, double& zndc) {
  const double m[3][3] = {{a.x, b.x, c.x}, {a.y, b.y, c.y}, {a.w, b.w, c.w}};
  const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  if (det == 0) return false;
  const double r[3] = {px, py, 1.0};
  double l[3];
  for (int k = 0; k < 3; ++k) {  // Cramer's rule
    double mk[3][3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) mk[i][j] = j == k ? r[i] : m[i][j];
    l[k] = (mk[0][0] * (mk[1][1] * mk[2][2] - mk[1][2] * mk[2][1]) - mk[0][1] * (mk[1][0] * mk[2][2] - mk[1][2] * mk[2][0]) +
            mk[0][2] * (mk[1][0] * mk[2][1] - mk[1][1] * mk[2][0])) / det;
  }
  zndc = l[0] * a.z + l[1] * b.z + l[2] * c.z;
  return std::isfinite(zndc);
}

struct DepthImage {
  std::vector<int32_t> ids;    // per pixel: the owner (triangle id), -1 none
  std::vector<double> depth;   // per pixel: the owner's window depth
};

DepthImage truth_depth(const trace::Frame& frame) {
  const vis::Setup setup = vis::primitive_setup(frame, vis::SetupConfig{});
  const vis::TruthResult truth = vis::zbuffer_truth(setup, vis::TruthConfig{});
  std::vector<std::pair<uint32_t, uint32_t>> tri;  // id -> (draw, first index)
  for (uint32_t d = 0; d < frame.draws.size(); ++d)
    for (uint32_t t = 0; t < frame.draws[d].triangle_count(); ++t) tri.emplace_back(d, 3 * t);
  DepthImage r;
  r.ids = truth.ids;
  r.depth.assign(r.ids.size(), 1.0);
  const double n = frame.depth_near, f = frame.depth_far;
  for (uint32_t y = 0; y < frame.height; ++y)
    for (uint32_t x = 0; x < frame.width; ++x) {
      const size_t p = size_t(y) * frame.width + x;
      if (r.ids[p] < 0) continue;
      const auto [d, i] = tri[size_t(r.ids[p])];
      const auto& dr = frame.draws[d];
      double z = 0;
      const double px = 2.0 * (x + 0.5) / frame.width - 1.0, py = 1.0 - 2.0 * (y + 0.5) / frame.height;
      if (plane_depth(dr.vertices[dr.indices[i]], dr.vertices[dr.indices[i + 1]], dr.vertices[dr.indices[i + 2]], px, py, z))
        r.depth[p] = std::clamp(n + (f - n) * (z + 1.0) * 0.5, std::min(n, f), std::max(n, f));
    }
  return r;
}

nlohmann::json compare_frame(const trace::Frame& frame, const AppDepth& app, double tolerance) {
  nlohmann::json j;
  if (app.width != frame.width || app.height != frame.height)
    throw std::runtime_error(fmt::format("compare-depth: the application's depth is {}x{}, the trace's frame {}x{} "
                                         "(capture without --viewport to compare)", app.width, app.height,
                                         frame.width, frame.height));
  if (frame.samples.size() != 1) throw std::runtime_error("compare-depth: needs a frame of 1 sample per pixel");
  // The truth of the trace as it is (opaque draws own samples), and the truth under the
  // application's rule (every draw that tests and writes depth owns samples, blended or not).
  const DepthImage exact = truth_depth(frame);
  trace::Frame gl_frame = frame;
  for (size_t d = 0; d < gl_frame.draws.size(); ++d) {
    const uint8_t bits = d < app.draw_bits.size() ? app.draw_bits[d] : 0;
    auto& flags = gl_frame.draws[d].flags;
    if ((bits & kDepthCleared) || !(bits & kDepthWrites)) {
      // A later depth clear removes it from the application's depth buffer.
      if (bits & kDepthCleared) gl_frame.draws[d].vertices.assign(gl_frame.draws[d].vertices.size(), {0, 0, 0, 1}), flags |= trace::kBlended;
    } else if (!(flags & (trace::kShaderDiscards | trace::kShaderWritesDepth | trace::kAlphaTested))) {
      flags &= ~uint32_t(trace::kBlended);
    }
  }
  const DepthImage gl = truth_depth(gl_frame);
  std::vector<uint32_t> triangle_draw;
  for (uint32_t d = 0; d < frame.draws.size(); ++d) triangle_draw.insert(triangle_draw.end(), frame.draws[d].triangle_count(), d);

  const uint32_t w = frame.width, h = frame.height;
  auto app_covered = [&](size_t p) { return app.depth[p] != app.clear; };
  // Window depth of triangle `id`'s plane at pixel (x, y).
  std::vector<std::pair<uint32_t, uint32_t>> tri;  // id -> (draw, first index)
  for (uint32_t d = 0; d < frame.draws.size(); ++d)
    for (uint32_t t = 0; t < frame.draws[d].triangle_count(); ++t) tri.emplace_back(d, 3 * t);
  const double dn = frame.depth_near, df = frame.depth_far;
  auto depth_of = [&](int32_t id, uint32_t x, uint32_t y, double& out) {
    const auto [d, i] = tri[size_t(id)];
    const auto& dr = frame.draws[d];
    double z = 0;
    const double px = 2.0 * (x + 0.5) / frame.width - 1.0, py = 1.0 - 2.0 * (y + 0.5) / frame.height;
    if (!plane_depth(dr.vertices[dr.indices[i]], dr.vertices[dr.indices[i + 1]], dr.vertices[dr.indices[i + 2]], px, py, z))
      return false;
    out = std::clamp(dn + (df - dn) * (z + 1.0) * 0.5, std::min(dn, df), std::max(dn, df));
    return true;
  };
  // A triangle-edge difference, verified: the owner differs within one pixel, and the
  // application's depth (or its background) is what a neighbouring owner gives here, so the
  // two rasterisers gave a boundary pixel to different triangles (llvmpipe's rule against the
  // 16.8 snap and top-left rule).
  auto edge = [&](uint32_t x, uint32_t y, const DepthImage& im, bool app_has, float app_z) {
    const int32_t id = im.ids[size_t(y) * w + x];
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int64_t nx = int64_t(x) + dx, ny = int64_t(y) + dy;
        if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
        const int32_t other = im.ids[size_t(ny) * w + size_t(nx)];
        if (other == id) continue;
        if (other < 0) {
          if (!app_has) return true;  // the application left it background, as a neighbour is
          continue;
        }
        double z = 0;
        if (app_has && depth_of(other, x, y, z) && std::fabs(z - app_z) <= tolerance) return true;
      }
    return false;
  };
  uint64_t covered = 0, within = 0, gl_covered = 0, gl_within = 0;
  std::map<std::string, uint64_t> causes, by_draw;
  nlohmann::json unexplained = nlohmann::json::array();  // the first few, for a look
  double max_abs = 0;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const size_t p = size_t(y) * w + x;
      const bool a = app_covered(p), t = exact.ids[p] >= 0;
      if (a || gl.ids[p] >= 0) {
        ++gl_covered;
        gl_within += a && gl.ids[p] >= 0 && std::fabs(app.depth[p] - gl.depth[p]) <= tolerance;
      }
      if (!a && !t) continue;
      ++covered;
      if (a && t && std::fabs(app.depth[p] - exact.depth[p]) <= tolerance) {
        ++within;
        max_abs = std::max(max_abs, std::fabs(app.depth[p] - exact.depth[p]));
        continue;
      }
      // Explain the difference, first cause that fits.
      const bool g = gl.ids[p] >= 0;
      const uint8_t bits = g && size_t(triangle_draw[size_t(gl.ids[p])]) < app.draw_bits.size()
                               ? app.draw_bits[triangle_draw[size_t(gl.ids[p])]] : 0;
      const bool exact_cleared = t && triangle_draw[size_t(exact.ids[p])] < app.draw_bits.size() &&
                                 (app.draw_bits[triangle_draw[size_t(exact.ids[p])]] & kDepthCleared);
      std::string cause;
      if (exact_cleared && !(a && g && std::fabs(app.depth[p] - gl.depth[p]) > tolerance))
        cause = "depth_cleared_mid_frame";  // its owner was drawn before a depth clear of the frame
      else if (a && g && std::fabs(app.depth[p] - gl.depth[p]) <= tolerance)
        cause = "non_opaque_draw_writes_depth";  // blended/discarding draws write depth in the application
      else if (!a && ((g && std::fabs(gl.depth[p] - app.clear) <= tolerance) || (t && std::fabs(exact.depth[p] - app.clear) <= tolerance)))
        cause = "at_clear_depth";  // the surface lies within tolerance of the clear value: it reads as background
      else if (bits & kDepthPolygonOffset)
        cause = "polygon_offset";
      else if (bits & kDepthClamp)
        cause = "depth_clamp";
      else if (bits & kDepthScissor)
        cause = "scissor";
      else if (bits & kDepthStencil)
        cause = "stencil";
      else if (edge(x, y, gl, a, app.depth[p]) || edge(x, y, exact, a, app.depth[p]))
        cause = "triangle_edge";  // rasterisation at a boundary: llvmpipe's rule vs the 16.8 snap + top-left rule
      else if (a && g && std::fabs(app.depth[p] - gl.depth[p]) <= 10 * tolerance)
        cause = "within_10x_tolerance";  // same surface, the application's float depth interpolation (steep triangles)
      else if (a && !g)
        cause = "not_in_trace";  // drawn by something the capture skipped (see capture.json)
      else if (!a && g)
        cause = "not_in_application_depth";
      else
        cause = "unexplained";
      if (cause == "unexplained" && unexplained.size() < 20)
        unexplained.push_back({{"x", x}, {"y", y}, {"application", a ? double(app.depth[p]) : -1.0},
                               {"truth", t ? exact.depth[p] : -1.0}, {"gl_rule", g ? gl.depth[p] : -1.0}});
      ++causes[cause];
      // Which draw owns the pixel (GL's rule first, else the trace's): names carry the state.
      const int32_t owner = g ? gl.ids[p] : t ? exact.ids[p] : -1;
      ++by_draw[cause + " | " + (owner < 0 ? std::string("(no owner)") : frame.draws[triangle_draw[size_t(owner)]].name)];
    }
  j["covered_pixels"] = covered;
  j["within_tolerance"] = within;
  j["agreement"] = covered ? double(within) / double(covered) : 1.0;
  j["max_abs_difference_within"] = max_abs;
  // Against the truth under the application's rule (blended draws that write depth own samples).
  j["covered_pixels_gl_rule"] = gl_covered;
  j["within_tolerance_gl_rule"] = gl_within;
  j["agreement_gl_rule"] = gl_covered ? double(gl_within) / double(gl_covered) : 1.0;
  j["differences"] = causes;
  std::vector<std::pair<uint64_t, std::string>> top;
  for (const auto& [k, n] : by_draw) top.emplace_back(n, k);
  std::sort(top.rbegin(), top.rend());
  if (top.size() > 20) top.resize(20);
  nlohmann::json tops = nlohmann::json::array();
  for (const auto& [n, k] : top) tops.push_back({{"cause | owning draw", k}, {"pixels", n}});
  j["differences_by_draw"] = tops;
  j["unexplained_pixels"] = unexplained;
  j["application_depth_bits"] = app.bits;
  return j;
}

}  // namespace

Command add_capture_command(CLI::App& app) {
  struct Args {
    uint32_t frames = 1, skip = 0;
    std::string viewport, out;
    int timeout = 300;
    bool offscreen = false;
    std::vector<std::string> command;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("capture", "Run an OpenGL program and capture frames of it as a trace");
  cmd->add_option("--frames", args->frames, "Frames to capture (a frame ends at a buffer swap)")->capture_default_str();
  cmd->add_option("--skip", args->skip, "Frames to let pass before the first captured one")->capture_default_str();
  cmd->add_option("--viewport", args->viewport,
                  "WxH: the trace's viewport (default: the window's); under Xvfb also the screen size");
  cmd->add_option("-o,--output", args->out, "Trace to write (OUT.depth and OUT.capture.json beside it)")->required();
  cmd->add_option("--timeout", args->timeout, "Seconds the program may run")->capture_default_str();
  cmd->add_flag("--offscreen", args->offscreen,
                "Also capture draws into framebuffer objects: each render pass becomes a trace frame of its own");
  cmd->add_option("command", args->command, "The program and its arguments (after --)")->required();
  return {cmd, [args]() {
            uint32_t vw = 0, vh = 0;
            if (!args->viewport.empty() && !parse_size(args->viewport, vw, vh))
              throw std::runtime_error("--viewport: expected WxH, got " + args->viewport);
            if (args->frames == 0) throw std::runtime_error("--frames: at least 1");
            const std::string lib = library_path();
            if (access(lib.c_str(), R_OK) != 0)
              throw std::runtime_error("capture: interposer " + lib + " not found (build target tilevis_capture)");
            const std::string dump = args->out + ".dump";
            std::vector<std::string> argv;
            const char* display = getenv("DISPLAY");
            if (!display || !*display) {
              if (!on_path("xvfb-run"))
                throw std::runtime_error("capture: no DISPLAY and no xvfb-run (Debian package xvfb)");
              const std::string screen = fmt::format("-screen 0 {}x{}x24", std::max(vw, 1280u), std::max(vh, 1024u));
              argv = {"xvfb-run", "-a", "-s", screen};
            }
            const char* preload = getenv("LD_PRELOAD");
            argv.insert(argv.end(), {"env", "LD_PRELOAD=" + lib + (preload && *preload ? std::string(":") + preload : ""),
                                     "TILEVIS_CAPTURE_OUT=" + dump, fmt::format("TILEVIS_CAPTURE_SKIP={}", args->skip),
                                     fmt::format("TILEVIS_CAPTURE_FRAMES={}", args->frames), "TILEVIS_CAPTURE_EXIT=1",
                                     args->offscreen ? "TILEVIS_CAPTURE_OFFSCREEN=1" : "TILEVIS_CAPTURE_OFFSCREEN=0"});
            argv.insert(argv.end(), args->command.begin(), args->command.end());
            fs::remove(dump);
            const int rc = run_program(argv, args->timeout);

            // Dump -> trace.
            if (!fs::exists(dump) || fs::file_size(dump) <= sizeof kDumpMagic)
              throw std::runtime_error(fmt::format("capture: nothing captured: the program exited with status {} before "
                                                   "frame {} ended (or it draws without OpenGL)", rc, args->skip + 1));
            DumpReader in(dump);
            trace::Trace tr;
            tr.source = "tilevis capture:";
            for (const auto& a : args->command) tr.source += " " + a;
            std::vector<AppDepth> depth;
            CaptureSummary sum;
            uint32_t tag = 0;
            // Two passes over the dump: pass sizes first (a pass's end follows its draws).
            using PassKey = std::pair<uint32_t, uint32_t>;  // frame, pass
            struct PassInfo {
              uint32_t framebuffer = 0, width = 0, height = 0;
            };
            std::map<PassKey, PassInfo> sizes;
            {
              DumpReader scan(dump);
              while (scan.next_tag(tag)) {
                if (tag == kTagDraw) {
                  scan.u32(), scan.u32();
                  scan.str();
                  scan.u32(), scan.u32();
                  for (int i = 0; i < 6; ++i) scan.u32();
                  std::vector<float> v;
                  scan.array(v, size_t(scan.u32()) * 4);
                  std::vector<uint32_t> ix;
                  scan.array(ix, scan.u32());
                } else if (tag == kTagSkip) {
                  scan.u32();
                  scan.str();
                } else if (tag == kTagDepthClear) {
                  scan.u32(), scan.u32(), scan.u32();
                } else if (tag == kTagPassEnd) {
                  const uint32_t frame = scan.u32(), pass = scan.u32();
                  PassInfo info;
                  info.framebuffer = scan.u32(), info.width = scan.u32(), info.height = scan.u32();
                  scan.f32(), scan.u32();
                  const uint32_t dw = scan.u32(), dh = scan.u32();
                  std::vector<float> v;
                  scan.array(v, size_t(dw) * dh);
                  sizes[{frame, pass}] = info;
                } else {
                  throw std::runtime_error(dump + ": unknown record");
                }
              }
            }
            if (sizes.empty())
              throw std::runtime_error(fmt::format("capture: no frame was captured (the program exited with {} before "
                                                   "{} buffer swaps)", rc, args->skip + args->frames));
            std::map<PassKey, size_t> frame_index;
            trace::Frame* cur = nullptr;
            AppDepth* cur_depth = nullptr;
            std::map<std::string, uint64_t> states;
            std::map<PassKey, uint32_t> clears;  // pass -> the frame's draw calls before its last depth clear
            std::vector<std::vector<uint32_t>> call_numbers;  // per trace frame and draw: the frame's draw call number
            nlohmann::json passes = nlohmann::json::array();
            while (in.next_tag(tag)) {
              if (tag == kTagSkip) {
                in.u32();
                std::string reason = in.str();
                const size_t colon = reason.find(": ");
                const std::string call = reason.substr(0, reason.find('('));
                ++sum.skipped[call + (colon == std::string::npos ? "" : reason.substr(colon))];
                continue;
              }
              if (tag == kTagDepthClear) {
                const uint32_t frame = in.u32(), pass = in.u32(), before = in.u32();
                clears[{frame, pass}] = before;  // the last one counts
                continue;
              }
              const uint32_t frame = in.u32(), pass = in.u32();
              const PassKey key{frame, pass};
              if (!frame_index.count(key)) {
                if (!sizes.count(key)) break;  // a pass the program did not finish
                frame_index[key] = tr.frames.size();
                call_numbers.emplace_back();
                tr.frames.emplace_back();
                depth.emplace_back();
                auto& f = tr.frames.back();
                const PassInfo& info = sizes[key];
                if (info.width == 0 || info.height == 0 || info.width > trace::kMaxViewport || info.height > trace::kMaxViewport)
                  throw std::runtime_error(fmt::format("capture: frame {} pass {}: framebuffer {} has no usable size ({}x{})",
                                                       frame, pass, info.framebuffer, info.width, info.height));
                f.width = info.width, f.height = info.height;
                f.samples = trace::standard_samples(1, f.subpixel_bits);
                f.depth_near = -1;  // set by the first draw
                passes.push_back({{"trace_frame", tr.frames.size() - 1}, {"frame", frame}, {"pass", pass},
                                  {"framebuffer", info.framebuffer}, {"width", info.width}, {"height", info.height}});
              }
              const size_t k = frame_index[key];
              cur = &tr.frames[k];
              cur_depth = &depth[k];
              if (tag == kTagDraw) {
                uint32_t state = 0;
                trace::Draw d = convert_draw(in, *cur, state);
                sum.triangles += d.triangle_count();
                ++sum.draws;
                if (!d.opaque() || d.per_pixel_only()) ++sum.non_occluding_draws, sum.non_occluding_triangles += d.triangle_count();
                ++states[state_names(state).empty() ? "(default)" : state_names(state).substr(1)];
                const size_t hash = d.name.find(" #");
                call_numbers[k].push_back(hash == std::string::npos ? 0 : uint32_t(std::stoul(d.name.substr(hash + 2))));
                cur->draws.push_back(std::move(d));
                cur_depth->draw_bits.push_back(depth_bits_of(state));
              } else if (tag == kTagPassEnd) {
                in.u32(), in.u32(), in.u32();  // framebuffer and size: read in the first pass
                cur_depth->clear = in.f32();
                cur_depth->bits = in.u32();
                cur_depth->width = in.u32(), cur_depth->height = in.u32();
                std::vector<float> bottom_up;
                in.array(bottom_up, size_t(cur_depth->width) * cur_depth->height);
                cur_depth->depth.resize(bottom_up.size());
                for (uint32_t y = 0; y < cur_depth->height; ++y)
                  std::copy_n(&bottom_up[size_t(cur_depth->height - 1 - y) * cur_depth->width], cur_depth->width,
                              &cur_depth->depth[size_t(y) * cur_depth->width]);
                if (cur->depth_near < 0) cur->depth_near = 0, cur->depth_far = 1;
                passes[k]["draws"] = cur->draws.size();
                passes[k]["triangles"] = cur->triangle_count();
              }
            }
            const size_t complete = std::count_if(passes.begin(), passes.end(), [](const auto& p) { return p.contains("draws"); });
            tr.frames.resize(complete), depth.resize(complete), passes.erase(passes.begin() + long(complete), passes.end());
            uint64_t cleared_draws = 0;
            for (const auto& [key, before] : clears) {
              if (!frame_index.count(key) || frame_index[key] >= tr.frames.size()) continue;
              const size_t k = frame_index[key];
              for (size_t d = 0; d < call_numbers[k].size(); ++d)
                if (call_numbers[k][d] < before) {
                  depth[k].draw_bits[d] |= kDepthCleared;
                  tr.frames[k].draws[d].name += " before-depth-clear";
                  ++cleared_draws;
                }
            }
            if (vw) {  // the trace's viewport: clip space is resolution-free, only the window's size changes
              for (size_t k = 0; k < tr.frames.size(); ++k)
                if (passes[k]["framebuffer"] == 0) tr.frames[k].width = vw, tr.frames[k].height = vh;
            }
            trace::write(tr, args->out);
            write_depth_file(args->out + ".depth", depth);
            nlohmann::json j;
            j["command"] = args->command;
            j["exit_code"] = rc;
            j["frames"] = tr.frames.size();
            j["draws"] = sum.draws;
            j["triangles"] = sum.triangles;
            j["non_occluding_draws"] = sum.non_occluding_draws;
            j["non_occluding_triangles"] = sum.non_occluding_triangles;
            j["viewport"] = tr.frames.empty() ? std::vector<uint32_t>{} : std::vector<uint32_t>{tr.frames[0].width, tr.frames[0].height};
            j["skipped_draws"] = sum.skipped;
            j["draws_before_a_depth_clear"] = cleared_draws;
            j["draw_states"] = states;
            j["passes"] = passes;
            std::ofstream(args->out + ".capture.json") << j.dump(2) << "\n";
            fs::remove(dump);
            fmt::print("{}: {} trace frames, {} draws, {} triangles ({} draws non-occluding)\n", args->out, tr.frames.size(),
                       sum.draws, sum.triangles, sum.non_occluding_draws);
            for (const auto& [reason, n] : sum.skipped) fmt::print("  not in the trace: {} x {}\n", n, reason);
            return 0;
          }};
}

Command add_compare_depth_command(CLI::App& app) {
  struct Args {
    std::string trace, depth, out;
    double tolerance = 1e-5;
    double min_agreement = -1;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("compare-depth",
                                 "The application's depth buffer (tilevis capture) against the exact truth's depth");
  cmd->add_option("trace", args->trace, "Captured trace")->required()->check(CLI::ExistingFile);
  cmd->add_option("--depth", args->depth, "Depth file (default: TRACE.depth)");
  cmd->add_option("--tolerance", args->tolerance, "Largest window-depth difference counted as equal")->capture_default_str();
  cmd->add_option("-o,--output", args->out, "JSON file for the result");
  cmd->add_option("--min-agreement", args->min_agreement,
                  "Exit 3 when a frame's share of covered pixels within tolerance is below this");
  return {cmd, [args]() {
            const trace::Trace tr = trace::read(args->trace);
            const auto app_depth = read_depth_file(args->depth.empty() ? args->trace + ".depth" : args->depth);
            if (app_depth.size() != tr.frames.size())
              throw std::runtime_error("compare-depth: the depth file's frames do not match the trace's");
            nlohmann::json all = nlohmann::json::array();
            bool below = false;
            for (size_t k = 0; k < tr.frames.size(); ++k) {
              if (app_depth[k].width == 0) {  // a pass into a framebuffer without depth: nothing to compare
                fmt::print("frame {}: no depth buffer in the application's framebuffer\n", k);
                all.push_back({{"frame", k}, {"no_depth_buffer", true}});
                continue;
              }
              nlohmann::json j = compare_frame(tr.frames[k], app_depth[k], args->tolerance);
              j["frame"] = k;
              fmt::print("frame {}: {} of {} covered pixels within {:g} ({:.4f} %)", k, j["within_tolerance"].get<uint64_t>(),
                         j["covered_pixels"].get<uint64_t>(), args->tolerance, 100.0 * j["agreement"].get<double>());
              for (const auto& [cause, n] : j["differences"].items()) fmt::print(", {} {}", cause, n.get<uint64_t>());
              fmt::print("; under the application's depth-write rule {:.4f} %\n", 100.0 * j["agreement_gl_rule"].get<double>());
              below |= j["agreement"].get<double>() < args->min_agreement;
              all.push_back(j);
            }
            nlohmann::json out{{"trace", args->trace}, {"tolerance", args->tolerance}, {"frames", all}};
            if (!args->out.empty()) std::ofstream(args->out) << out.dump(2) << "\n";
            return below ? 3 : 0;
          }};
}

}  // namespace tilevis::app
