// gl_raster TRACE -o DIR [--frame K] [--runs N] [--truth DIR]: the hardware-raster baseline. The
// trace's clip-space triangles drawn by the GPU's own rasteriser through OpenGL 4.5 core on a
// headless EGL display (the device platform, else the default display), depth test on (less,
// 32-bit float depth, glDepthRange = the trace's), back faces culled (front = counter-clockwise
// in NDC, as the trace says), the opaque draws only (as the truth's owners), the triangle id out
// through gl_PrimitiveID into a 32-bit integer target. Timed with GL_TIME_ELAPSED around the
// clear and the draws (median of --runs after 3 warm-ups; upload excluded), like the CUDA
// pipeline's events. Writes DIR/ids.exr and DIR/stats.json (hw_raster_ms, the GL renderer). A
// trace of more than one sample per pixel is drawn into multisample targets of that many samples
// (the GL's sample positions) and timed alike; only stats.json is written then.
//
// With --truth (a `tilevis golden --truth` directory): every sample whose id differs from the
// exact truth's is classified by exact geometry on the snapped triangles (visibility/setup):
//   edge_tie      the sample lies exactly on an edge of either triangle: OpenGL's fill rule on
//                 exact ties is not the truth's top-left rule (see shared notes: bottom/left);
//   edge_snap     within one sub-pixel unit of such an edge: the GL's own snapping of float
//                 window coordinates versus the truth's exact snap of double ones;
//   depth_tie     both triangles cover the sample (not on an edge) and their exact depths
//                 there differ by at most 16 units of 24-bit depth (2^-20): float depth;
//   other         everything else (counted, with examples).
//
// EGL and GL are loaded at run time (dlopen, eglGetProcAddress): no GL headers or libraries are
// needed to build this; without a GL driver it says so and exits 2.
#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "geom/depth.h"
#include "geom/predicates.h"
#include "tilevis/outputs.h"
#include "tilevis/trace.h"
#include "visibility/setup.h"
#include "visibility/svgpu.h"
#include "visibility/zbuffer.h"

namespace {

using EGLDisplay = void*;
using EGLConfig = void*;
using EGLContext = void*;
using EGLSurface = void*;
using EGLDeviceEXT = void*;
using EGLint = int32_t;
using EGLBoolean = uint32_t;
using EGLenum = uint32_t;

constexpr EGLint EGL_NONE = 0x3038, EGL_SURFACE_TYPE = 0x3033, EGL_PBUFFER_BIT = 0x0001,
                 EGL_RENDERABLE_TYPE = 0x3040, EGL_OPENGL_BIT = 0x0008, EGL_CONTEXT_MAJOR_VERSION = 0x3098,
                 EGL_CONTEXT_MINOR_VERSION = 0x30FB, EGL_CONTEXT_OPENGL_PROFILE_MASK = 0x30FD,
                 EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT = 0x0001;
constexpr EGLenum EGL_OPENGL_API = 0x30A2, EGL_PLATFORM_DEVICE_EXT = 0x313F;

using GLuint = uint32_t;
using GLint = int32_t;
using GLenum = uint32_t;
using GLsizei = int32_t;
using GLuint64 = uint64_t;
using GLsizeiptr = intptr_t;

constexpr GLenum GL_VERTEX_SHADER = 0x8B31, GL_FRAGMENT_SHADER = 0x8B30, GL_COMPILE_STATUS = 0x8B81,
                 GL_LINK_STATUS = 0x8B82, GL_ARRAY_BUFFER = 0x8892, GL_ELEMENT_ARRAY_BUFFER = 0x8893,
                 GL_STATIC_DRAW = 0x88E4, GL_FLOAT = 0x1406, GL_UNSIGNED_INT = 0x1405, GL_TRIANGLES = 0x0004,
                 GL_FRAMEBUFFER = 0x8D40, GL_RENDERBUFFER = 0x8D41, GL_COLOR_ATTACHMENT0 = 0x8CE0,
                 GL_DEPTH_ATTACHMENT = 0x8D00, GL_R32UI = 0x8236, GL_DEPTH_COMPONENT32F = 0x8CAC,
                 GL_FRAMEBUFFER_COMPLETE = 0x8CD5, GL_DEPTH_TEST = 0x0B71, GL_LESS = 0x0201, GL_CULL_FACE = 0x0B44,
                 GL_BACK = 0x0405, GL_CCW = 0x0901, GL_COLOR = 0x1800, GL_DEPTH = 0x1801, GL_RED_INTEGER = 0x8D94,
                 GL_TIME_ELAPSED = 0x88BF, GL_QUERY_RESULT = 0x8866, GL_RENDERER = 0x1F01, GL_VERSION = 0x1F02,
                 GL_VENDOR = 0x1F00, GL_PACK_ALIGNMENT = 0x0D05, GL_DITHER = 0x0BD0;

struct Egl {
  void* lib = nullptr;
  void* (*GetProcAddress)(const char*) = nullptr;
  EGLDisplay (*GetDisplay)(void*) = nullptr;
  EGLBoolean (*Initialize)(EGLDisplay, EGLint*, EGLint*) = nullptr;
  EGLBoolean (*ChooseConfig)(EGLDisplay, const EGLint*, EGLConfig*, EGLint, EGLint*) = nullptr;
  EGLBoolean (*BindAPI)(EGLenum) = nullptr;
  EGLContext (*CreateContext)(EGLDisplay, EGLConfig, EGLContext, const EGLint*) = nullptr;
  EGLBoolean (*MakeCurrent)(EGLDisplay, EGLSurface, EGLSurface, EGLContext) = nullptr;
  EGLBoolean (*Terminate)(EGLDisplay) = nullptr;
  EGLint (*GetError)() = nullptr;
  EGLBoolean (*QueryDevicesEXT)(EGLint, EGLDeviceEXT*, EGLint*) = nullptr;
  EGLDisplay (*GetPlatformDisplayEXT)(EGLenum, void*, const EGLint*) = nullptr;
};

#define GL_FUNCS(X)                                                                     \
  X(GLuint, CreateShader, GLenum)                                                       \
  X(void, ShaderSource, GLuint, GLsizei, const char* const*, const GLint*)              \
  X(void, CompileShader, GLuint)                                                        \
  X(void, GetShaderiv, GLuint, GLenum, GLint*)                                          \
  X(void, GetShaderInfoLog, GLuint, GLsizei, GLsizei*, char*)                           \
  X(GLuint, CreateProgram)                                                              \
  X(void, AttachShader, GLuint, GLuint)                                                 \
  X(void, LinkProgram, GLuint)                                                          \
  X(void, GetProgramiv, GLuint, GLenum, GLint*)                                         \
  X(void, GetProgramInfoLog, GLuint, GLsizei, GLsizei*, char*)                          \
  X(void, UseProgram, GLuint)                                                           \
  X(GLint, GetUniformLocation, GLuint, const char*)                                     \
  X(void, Uniform1ui, GLint, GLuint)                                                    \
  X(void, GenVertexArrays, GLsizei, GLuint*)                                            \
  X(void, BindVertexArray, GLuint)                                                      \
  X(void, GenBuffers, GLsizei, GLuint*)                                                 \
  X(void, BindBuffer, GLenum, GLuint)                                                   \
  X(void, BufferData, GLenum, GLsizeiptr, const void*, GLenum)                          \
  X(void, EnableVertexAttribArray, GLuint)                                              \
  X(void, VertexAttribPointer, GLuint, GLint, GLenum, uint8_t, GLsizei, const void*)    \
  X(void, GenFramebuffers, GLsizei, GLuint*)                                            \
  X(void, BindFramebuffer, GLenum, GLuint)                                              \
  X(void, GenRenderbuffers, GLsizei, GLuint*)                                           \
  X(void, BindRenderbuffer, GLenum, GLuint)                                             \
  X(void, RenderbufferStorage, GLenum, GLenum, GLsizei, GLsizei)                        \
  X(void, RenderbufferStorageMultisample, GLenum, GLsizei, GLenum, GLsizei, GLsizei)    \
  X(void, FramebufferRenderbuffer, GLenum, GLenum, GLenum, GLuint)                      \
  X(GLenum, CheckFramebufferStatus, GLenum)                                             \
  X(void, Viewport, GLint, GLint, GLsizei, GLsizei)                                     \
  X(void, Enable, GLenum)                                                               \
  X(void, Disable, GLenum)                                                              \
  X(void, DepthFunc, GLenum)                                                            \
  X(void, DepthRangef, float, float)                                                    \
  X(void, CullFace, GLenum)                                                             \
  X(void, FrontFace, GLenum)                                                            \
  X(void, ClearBufferuiv, GLenum, GLint, const GLuint*)                                 \
  X(void, ClearBufferfv, GLenum, GLint, const float*)                                   \
  X(void, DrawElements, GLenum, GLsizei, GLenum, const void*)                           \
  X(void, ReadPixels, GLint, GLint, GLsizei, GLsizei, GLenum, GLenum, void*)            \
  X(void, PixelStorei, GLenum, GLint)                                                   \
  X(void, Finish)                                                                       \
  X(void, GenQueries, GLsizei, GLuint*)                                                 \
  X(void, BeginQuery, GLenum, GLuint)                                                   \
  X(void, EndQuery, GLenum)                                                             \
  X(void, GetQueryObjectui64v, GLuint, GLenum, GLuint64*)                               \
  X(const uint8_t*, GetString, GLenum)                                                  \
  X(GLenum, GetError)

struct Gl {
#define GL_MEMBER(ret, name, ...) ret (*name)(__VA_ARGS__) = nullptr;
  GL_FUNCS(GL_MEMBER)
#undef GL_MEMBER
};

[[noreturn]] void no_gl(const std::string& why) {
  std::fprintf(stderr, "gl_raster: no usable OpenGL through EGL (%s); nothing written\n", why.c_str());
  std::exit(2);
}

template <class F>
void sym(void* lib, const char* name, F& f) {
  f = reinterpret_cast<F>(dlsym(lib, name));
  if (!f) no_gl(std::string("libEGL has no ") + name);
}

Egl load_egl() {
  Egl e;
  e.lib = dlopen("libEGL.so.1", RTLD_NOW | RTLD_GLOBAL);
  if (!e.lib) no_gl(std::string("dlopen libEGL.so.1: ") + dlerror());
  sym(e.lib, "eglGetProcAddress", e.GetProcAddress);
  sym(e.lib, "eglGetDisplay", e.GetDisplay);
  sym(e.lib, "eglInitialize", e.Initialize);
  sym(e.lib, "eglChooseConfig", e.ChooseConfig);
  sym(e.lib, "eglBindAPI", e.BindAPI);
  sym(e.lib, "eglCreateContext", e.CreateContext);
  sym(e.lib, "eglMakeCurrent", e.MakeCurrent);
  sym(e.lib, "eglTerminate", e.Terminate);
  sym(e.lib, "eglGetError", e.GetError);
  e.QueryDevicesEXT = reinterpret_cast<decltype(e.QueryDevicesEXT)>(e.GetProcAddress("eglQueryDevicesEXT"));
  e.GetPlatformDisplayEXT =
      reinterpret_cast<decltype(e.GetPlatformDisplayEXT)>(e.GetProcAddress("eglGetPlatformDisplayEXT"));
  return e;
}

// A current OpenGL 4.5 core context without a surface; returns the display used.
std::string make_context(Egl& e) {
  EGLDisplay dpy = nullptr;
  std::string how;
  if (e.QueryDevicesEXT && e.GetPlatformDisplayEXT) {
    EGLDeviceEXT devs[16];
    EGLint n = 0;
    if (e.QueryDevicesEXT(16, devs, &n) && n > 0)
      for (EGLint i = 0; i < n && !dpy; ++i) {
        EGLDisplay d = e.GetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devs[i], nullptr);
        EGLint major = 0, minor = 0;
        if (d && e.Initialize(d, &major, &minor)) {
          dpy = d;
          how = "EGL device " + std::to_string(i) + " of " + std::to_string(n);
        }
      }
  }
  if (!dpy) {
    EGLDisplay d = e.GetDisplay(nullptr);
    EGLint major = 0, minor = 0;
    if (d && e.Initialize(d, &major, &minor)) {
      dpy = d;
      how = "EGL default display";
    }
  }
  if (!dpy) no_gl("no EGL display could be initialised");
  const EGLint attrs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig cfg = nullptr;
  EGLint ncfg = 0;
  if (!e.ChooseConfig(dpy, attrs, &cfg, 1, &ncfg) || ncfg < 1) no_gl("no EGL config with OpenGL");
  if (!e.BindAPI(EGL_OPENGL_API)) no_gl("eglBindAPI(OpenGL) failed");
  const EGLint ctx_attrs[] = {EGL_CONTEXT_MAJOR_VERSION,       4, EGL_CONTEXT_MINOR_VERSION, 5,
                              EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
  EGLContext ctx = e.CreateContext(dpy, cfg, nullptr, ctx_attrs);
  if (!ctx) no_gl("no OpenGL 4.5 core context (EGL error " + std::to_string(e.GetError()) + ")");
  if (!e.MakeCurrent(dpy, nullptr, nullptr, ctx)) no_gl("eglMakeCurrent without a surface failed");
  return how;
}

Gl load_gl(Egl& e) {
  Gl g;
#define GL_LOAD(ret, name, ...)                                                                  \
  g.name = reinterpret_cast<ret (*)(__VA_ARGS__)>(e.GetProcAddress("gl" #name));                 \
  if (!g.name) no_gl("no gl" #name);
  GL_FUNCS(GL_LOAD)
#undef GL_LOAD
  return g;
}

GLuint shader(Gl& g, GLenum kind, const char* src) {
  const GLuint s = g.CreateShader(kind);
  g.ShaderSource(s, 1, &src, nullptr);
  g.CompileShader(s);
  GLint ok = 0;
  g.GetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    g.GetShaderInfoLog(s, sizeof log, nullptr, log);
    throw std::runtime_error(std::string("gl_raster: shader: ") + log);
  }
  return s;
}

const char* const kVertex = R"(#version 450 core
layout(location = 0) in vec4 position;
void main() { gl_Position = position; }
)";
const char* const kFragment = R"(#version 450 core
uniform uint first_id;
layout(location = 0) out uint id;
void main() { id = first_id + uint(gl_PrimitiveID); }
)";

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n == 0 ? 0 : n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct Args {
  std::string trace, out, truth;
  uint32_t frame = 0, runs = 20;
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error("gl_raster: " + s + " needs a value");
      return argv[++i];
    };
    if (s == "-o" || s == "--output") a.out = next();
    else if (s == "--truth") a.truth = next();
    else if (s == "--frame") a.frame = uint32_t(std::stoul(next()));
    else if (s == "--runs") a.runs = std::max<uint32_t>(1, uint32_t(std::stoul(next())));
    else if (!s.empty() && s[0] != '-' && a.trace.empty()) a.trace = s;
    else throw std::runtime_error("gl_raster: unknown argument " + s);
  }
  if (a.trace.empty() || a.out.empty())
    throw std::runtime_error("usage: gl_raster TRACE -o DIR [--frame K] [--runs N] [--truth DIR]");
  return a;
}

// Exact classification of the samples where the GL's id differs from the truth's.
nlohmann::json classify(const tilevis::trace::Frame& frame, const std::vector<int32_t>& gl,
                        const std::vector<int32_t>& truth) {
  namespace vis = tilevis::vis;
  namespace geom = tilevis::geom;
  const vis::Setup s = vis::primitive_setup(frame, {});
  std::map<uint32_t, std::vector<size_t>> by_id;  // the front setup triangles of each id
  std::vector<geom::DepthPlane> planes(s.triangles.size());
  for (size_t i = 0; i < s.triangles.size(); ++i) {
    const auto& t = s.triangles[i];
    if (!t.front) continue;
    by_id[t.id].push_back(i);
    planes[i] = vis::svgpu::Triangle::from(t.v[0], t.v[1], t.v[2]).plane;
  }
  const uint32_t S = uint32_t(s.samples.size());
  // Least distance (sub-pixel units) from p to an edge of id's triangles whose closed triangle
  // holds p's neighbourhood; and the setup triangle covering p (top-left), if any.
  auto inspect = [&](int32_t id, geom::Point p, double& dist, int64_t& cover) {
    dist = INFINITY;
    cover = -1;
    if (id < 0) return;
    auto it = by_id.find(uint32_t(id));
    if (it == by_id.end()) return;
    for (size_t i : it->second) {
      const auto& t = s.triangles[i];
      const geom::Point v[3] = {{t.v[0].x, t.v[0].y}, {t.v[1].x, t.v[1].y}, {t.v[2].x, t.v[2].y}};
      const auto tri = tilevis::vis::svgpu::Triangle::from(t.v[0], t.v[1], t.v[2]);
      if (tri.edges.covers(p)) cover = int64_t(i);
      for (int k = 0; k < 3; ++k) {
        const geom::Point a = v[k], b = v[(k + 1) % 3];
        const double dx = double(b.x) - a.x, dy = double(b.y) - a.y, len = std::hypot(dx, dy);
        if (len == 0) continue;
        // Distance to the segment.
        const double u = std::clamp(((double(p.x) - a.x) * dx + (double(p.y) - a.y) * dy) / (len * len), 0.0, 1.0);
        const double d = std::hypot(double(p.x) - (a.x + u * dx), double(p.y) - (a.y + u * dy));
        const int64_t o = (int64_t(b.x) - a.x) * (int64_t(p.y) - a.y) - (int64_t(b.y) - a.y) * (int64_t(p.x) - a.x);
        dist = std::min(dist, o == 0 && u > 0 && u < 1 ? 0.0 : d);
        if (o == 0 && (p.x == a.x && p.y == a.y)) dist = 0;
      }
    }
  };
  uint64_t compared = 0, differ = 0, edge_tie = 0, edge_snap = 0, depth_tie = 0, other = 0;
  nlohmann::json examples = nlohmann::json::array();
  for (uint32_t py = 0; py < s.height; ++py)
    for (uint32_t px = 0; px < s.width; ++px)
      for (uint32_t k = 0; k < S; ++k) {
        const size_t idx = (size_t(py) * s.width + px) * S + k;
        const int32_t t = truth[idx], g = gl[idx];
        if (t < 0 && g < 0) continue;
        ++compared;
        if (t == g) continue;
        ++differ;
        const geom::Point p = vis::zbuffer::sample_point(s, px, py, k);
        double dt = 0, dg = 0;
        int64_t ct = -1, cg = -1;
        inspect(t, p, dt, ct);
        inspect(g, p, dg, cg);
        const double d = std::min(dt, dg);
        std::string cls;
        if (d == 0) cls = "edge_tie", ++edge_tie;
        else if (d <= 1.0) cls = "edge_snap", ++edge_snap;
        else if (ct >= 0 && cg >= 0) {
          const auto& pt = planes[size_t(ct)];
          const auto& pg = planes[size_t(cg)];
          const double zt = double(geom::depth_numerator(pt, p)) / double(pt.area);
          const double zg = double(geom::depth_numerator(pg, p)) / double(pg.area);
          if (std::fabs(zt - zg) <= 16.0 * double(1u << s.depth_bits) / double(1u << 24)) cls = "depth_tie", ++depth_tie;
          else cls = "other", ++other;
        } else {
          cls = "other", ++other;
        }
        if (cls == "other" && examples.size() < 10)
          examples.push_back({{"x", px}, {"y", py}, {"sample", k}, {"truth", t}, {"gl", g}, {"edge_distance", d}});
      }
  return {{"samples_compared", compared}, {"mismatched_samples", differ},
          {"sample_agreement", compared ? 1.0 - double(differ) / double(compared) : 1.0},
          {"edge_tie", edge_tie}, {"edge_snap", edge_snap}, {"depth_tie", depth_tie}, {"other", other},
          {"other_examples", examples}};
}

}  // namespace

int main(int argc, char** argv) try {
  const Args a = parse(argc, argv);
  const tilevis::trace::Trace tr = tilevis::trace::read(a.trace);
  if (a.frame >= tr.frames.size()) throw std::runtime_error("gl_raster: " + a.trace + ": no frame " + std::to_string(a.frame));
  const tilevis::trace::Frame& f = tr.frames[a.frame];
  // More than one sample: a multisample id and depth target of that many samples (the GL's own
  // sample positions, not the trace's), timed alike; its ids are not read back or compared.
  const GLsizei S = GLsizei(f.samples.size());
  Egl egl = load_egl();
  const std::string display = make_context(egl);
  Gl g = load_gl(egl);
  const std::string renderer = reinterpret_cast<const char*>(g.GetString(GL_RENDERER));
  const std::string version = reinterpret_cast<const char*>(g.GetString(GL_VERSION));
  const std::string vendor = reinterpret_cast<const char*>(g.GetString(GL_VENDOR));

  // One vertex buffer and one index buffer for the frame; a draw call per opaque draw.
  std::vector<float> verts;
  std::vector<uint32_t> idx;
  struct Call {
    GLsizei count;
    size_t offset;  // bytes into the index buffer
    uint32_t first_id;
  };
  std::vector<Call> calls;
  uint32_t first_id = 0;
  for (const auto& d : f.draws) {
    const uint32_t base = uint32_t(verts.size() / 4);
    for (const auto& v : d.vertices) verts.insert(verts.end(), {v.x, v.y, v.z, v.w});
    if (d.opaque() && !d.per_pixel_only() && !d.indices.empty()) {
      calls.push_back({GLsizei(d.indices.size()), idx.size() * 4, first_id});
      for (uint32_t i : d.indices) idx.push_back(base + i);
    }
    first_id += uint32_t(d.triangle_count());
  }
  const GLsizei W = GLsizei(f.width), H = GLsizei(f.height);
  GLuint vao = 0, vbo = 0, ibo = 0, fbo = 0, rb[2] = {0, 0};
  g.GenVertexArrays(1, &vao);
  g.BindVertexArray(vao);
  g.GenBuffers(1, &vbo);
  g.BindBuffer(GL_ARRAY_BUFFER, vbo);
  g.BufferData(GL_ARRAY_BUFFER, GLsizeiptr(verts.size() * 4), verts.data(), GL_STATIC_DRAW);
  g.EnableVertexAttribArray(0);
  g.VertexAttribPointer(0, 4, GL_FLOAT, 0, 16, nullptr);
  g.GenBuffers(1, &ibo);
  g.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
  g.BufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(idx.size() * 4), idx.data(), GL_STATIC_DRAW);
  g.GenFramebuffers(1, &fbo);
  g.BindFramebuffer(GL_FRAMEBUFFER, fbo);
  g.GenRenderbuffers(2, rb);
  g.BindRenderbuffer(GL_RENDERBUFFER, rb[0]);
  if (S > 1) g.RenderbufferStorageMultisample(GL_RENDERBUFFER, S, GL_R32UI, W, H);
  else g.RenderbufferStorage(GL_RENDERBUFFER, GL_R32UI, W, H);
  g.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
  g.BindRenderbuffer(GL_RENDERBUFFER, rb[1]);
  if (S > 1) g.RenderbufferStorageMultisample(GL_RENDERBUFFER, S, GL_DEPTH_COMPONENT32F, W, H);
  else g.RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, W, H);
  g.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
  if (g.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("gl_raster: framebuffer incomplete");
  const GLuint prog = g.CreateProgram();
  g.AttachShader(prog, shader(g, GL_VERTEX_SHADER, kVertex));
  g.AttachShader(prog, shader(g, GL_FRAGMENT_SHADER, kFragment));
  g.LinkProgram(prog);
  GLint linked = 0;
  g.GetProgramiv(prog, GL_LINK_STATUS, &linked);
  if (!linked) throw std::runtime_error("gl_raster: program did not link");
  g.UseProgram(prog);
  const GLint loc = g.GetUniformLocation(prog, "first_id");
  g.Viewport(0, 0, W, H);
  g.DepthRangef(f.depth_near, f.depth_far);
  g.Enable(GL_DEPTH_TEST);
  g.DepthFunc(GL_LESS);
  g.Enable(GL_CULL_FACE);
  g.CullFace(GL_BACK);
  g.FrontFace(GL_CCW);
  g.Disable(GL_DITHER);

  GLuint query = 0;
  g.GenQueries(1, &query);
  const GLuint clear_id[4] = {0xffffffffu, 0, 0, 0};
  const float clear_depth = 1.0f;
  auto draw = [&] {
    g.ClearBufferuiv(GL_COLOR, 0, clear_id);
    g.ClearBufferfv(GL_DEPTH, 0, &clear_depth);
    for (const Call& c : calls) {
      g.Uniform1ui(loc, c.first_id);
      g.DrawElements(GL_TRIANGLES, c.count, GL_UNSIGNED_INT, reinterpret_cast<const void*>(c.offset));
    }
  };
  std::vector<double> ms;
  for (uint32_t r = 0; r < a.runs + 3; ++r) {
    g.BeginQuery(GL_TIME_ELAPSED, query);
    draw();
    g.EndQuery(GL_TIME_ELAPSED);
    GLuint64 ns = 0;
    g.GetQueryObjectui64v(query, GL_QUERY_RESULT, &ns);
    if (r >= 3) ms.push_back(double(ns) / 1e6);
  }
  if (GLenum e = g.GetError()) throw std::runtime_error("gl_raster: GL error " + std::to_string(e));
  const nlohmann::json timing = {{"renderer", renderer},
                                 {"gl_version", version},
                                 {"gl_vendor", vendor},
                                 {"display", display},
                                 {"hw_raster_ms", median(ms)},
                                 {"hw_raster_min_ms", *std::min_element(ms.begin(), ms.end())},
                                 {"runs", a.runs},
                                 {"timing", "GL_TIME_ELAPSED around the clear and the draws, median of runs after 3 "
                                            "warm-ups; upload excluded"}};
  if (S > 1) {
    nlohmann::json st = {{"tool", "gl_raster"}, {"trace", a.trace}, {"frame", a.frame},
                         {"config", {{"depth", "32-bit float, less"}, {"cull", "back"}, {"samples", S},
                                     {"sample_positions", "the GL's own (multisample renderbuffers)"}}},
                         {"totals", {{"triangles_in", f.triangle_count()}}},
                         {"ids", "not read back at more than one sample"}};
    st.update(timing);
    std::filesystem::create_directories(a.out);
    std::ofstream(std::filesystem::path(a.out) / "stats.json") << st.dump(2) << '\n';
    std::printf("gl_raster %s on %s, %d samples: %.3f ms (median of %u)\n", a.trace.c_str(), renderer.c_str(), int(S),
                median(ms), a.runs);
    return 0;
  }
  std::vector<uint32_t> img(size_t(W) * H);
  g.PixelStorei(GL_PACK_ALIGNMENT, 1);
  g.ReadPixels(0, 0, W, H, GL_RED_INTEGER, GL_UNSIGNED_INT, img.data());
  g.Finish();

  tilevis::outputs::Result out;
  out.width = f.width;
  out.height = f.height;
  out.samples = 1;
  out.ids.resize(img.size());
  uint64_t covered = 0;
  for (uint32_t y = 0; y < f.height; ++y)  // GL's rows run bottom up; the canonical layout's top down
    for (uint32_t x = 0; x < f.width; ++x) {
      const uint32_t v = img[size_t(f.height - 1 - y) * f.width + x];
      out.ids[size_t(y) * f.width + x] = v == 0xffffffffu ? -1 : int32_t(v);
      covered += v == 0xffffffffu ? 0 : 1;
    }
  out.stats = {{"tool", "gl_raster"},
               {"trace", a.trace},
               {"frame", a.frame},
               {"config", {{"depth", "32-bit float, less"}, {"cull", "back"}, {"samples", 1}}},
               {"totals", {{"samples_covered", covered}, {"triangles_in", f.triangle_count()}}}};
  out.stats.update(timing);
  if (!a.truth.empty()) {
    const tilevis::outputs::Result t = tilevis::outputs::read_result(a.truth);
    if (t.ids.size() != out.ids.size()) throw std::runtime_error("gl_raster: " + a.truth + ": other size than the trace");
    out.stats["vs_truth"] = classify(f, out.ids, t.ids);
  }
  tilevis::outputs::write_result(out, a.out);
  std::printf("gl_raster %s on %s: %.3f ms (median of %u)%s\n", a.trace.c_str(), renderer.c_str(), median(ms), a.runs,
              out.stats.contains("vs_truth")
                  ? (", vs truth: " + out.stats["vs_truth"]["mismatched_samples"].dump() + " of " +
                     out.stats["vs_truth"]["samples_compared"].dump() + " samples differ (edge_tie " +
                     out.stats["vs_truth"]["edge_tie"].dump() + ", edge_snap " + out.stats["vs_truth"]["edge_snap"].dump() +
                     ", depth_tie " + out.stats["vs_truth"]["depth_tie"].dump() + ", other " +
                     out.stats["vs_truth"]["other"].dump() + ")")
                        .c_str()
                  : "");
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "%s\n", e.what());
  return 1;
}
