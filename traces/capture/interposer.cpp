// libtilevis_capture.so: the LD_PRELOAD interposer behind `tilevis capture` (issue 17).
//
// Programs reach GL three ways, and each is wrapped (the approach of apitrace's tracers):
// symbols linked at start-up (the exported functions below take precedence under LD_PRELOAD),
// pointers from glXGetProcAddress[ARB] / eglGetProcAddress, and dlopen + dlsym of libGL at
// run time (glmark2-x11 never links libGL). Every entry point that matters returns our wrapper;
// the wrappers call the real functions, resolved through the real libGL.
//
// Per draw of the chosen frames (frames end at a buffer swap), the wrapper first draws the
// same call again as points with transform feedback of gl_Position and rasteriser discard,
// so the positions are the program's own vertex stage output (same shaders, attribute
// bindings, uniform values and vertex arrays), then reads back the indices as drawn and the
// visibility state, and writes one record of the dump (dump.h). The feedback varying is set on
// the application's program just before its link (glLinkProgram below): feedback is inactive
// unless begun, so the application's rendering is unchanged, and uniform values need no copy.
// At each captured swap it reads the application's depth buffer.
//
// Environment: TILEVIS_CAPTURE_OUT (dump path; unset: pass-through), TILEVIS_CAPTURE_SKIP
// (frames before the first captured one), TILEVIS_CAPTURE_FRAMES (frames captured; 0: none),
// TILEVIS_CAPTURE_EXIT (1: end the process once the last frame is written, the default).
#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include <EGL/egl.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/glx.h>

#include "dump.h"

#define EXPORT extern "C" __attribute__((visibility("default")))

namespace {

using namespace tilevis::capture;

// ---- the real dynamic loader ------------------------------------------------------------

using DlsymFn = void* (*)(void*, const char*);
using DlopenFn = void* (*)(const char*, int);

DlsymFn real_dlsym() {
  static DlsymFn fn = [] {
    // dlvsym is not wrapped, so it reaches glibc's dlsym whichever version the process uses.
    void* p = dlvsym(RTLD_NEXT, "dlsym", "GLIBC_2.34");
    if (!p) p = dlvsym(RTLD_NEXT, "dlsym", "GLIBC_2.2.5");
    return reinterpret_cast<DlsymFn>(p);
  }();
  return fn;
}

DlopenFn real_dlopen() {
  static DlopenFn fn = [] {
    void* p = dlvsym(RTLD_NEXT, "dlopen", "GLIBC_2.34");
    if (!p) p = dlvsym(RTLD_NEXT, "dlopen", "GLIBC_2.2.5");
    return reinterpret_cast<DlopenFn>(p);
  }();
  return fn;
}

void* libgl() {
  static void* h = real_dlopen()("libGL.so.1", RTLD_LAZY | RTLD_GLOBAL);
  return h;
}
void* libegl() {
  static void* h = real_dlopen()("libEGL.so.1", RTLD_LAZY | RTLD_GLOBAL);
  return h;
}

using GetProcFn = void (*(*)(const GLubyte*))();
using EglGetProcFn = void (*(*)(const char*))();

void* real_gl(const char* name) {
  static GetProcFn gpa = reinterpret_cast<GetProcFn>(real_dlsym()(libgl(), "glXGetProcAddressARB"));
  void* p = real_dlsym()(libgl(), name);
  if (!p && gpa) p = reinterpret_cast<void*>(gpa(reinterpret_cast<const GLubyte*>(name)));
  return p;
}
void* real_egl(const char* name) {
  void* p = real_dlsym()(libegl(), name);
  return p;
}

template <class F>
F gl(F& slot, const char* name) {
  if (!slot) slot = reinterpret_cast<F>(real_gl(name));
  return slot;
}
#define REAL(type, name)                 \
  static type real_##name = nullptr;     \
  static type name##_() { return gl(real_##name, #name); }

// Functions the capture itself calls.
REAL(decltype(&::glGetIntegerv), glGetIntegerv)
REAL(PFNGLGETINTEGERI_VPROC, glGetIntegeri_v)
REAL(decltype(&::glGetFloatv), glGetFloatv)
REAL(decltype(&::glGetBooleanv), glGetBooleanv)
REAL(decltype(&::glIsEnabled), glIsEnabled)
REAL(decltype(&::glEnable), glEnable)
REAL(decltype(&::glDisable), glDisable)
REAL(PFNGLGENBUFFERSPROC, glGenBuffers)
REAL(PFNGLBINDBUFFERPROC, glBindBuffer)
REAL(PFNGLBINDBUFFERBASEPROC, glBindBufferBase)
REAL(PFNGLBUFFERDATAPROC, glBufferData)
REAL(PFNGLGETBUFFERSUBDATAPROC, glGetBufferSubData)
REAL(PFNGLBEGINTRANSFORMFEEDBACKPROC, glBeginTransformFeedback)
REAL(PFNGLENDTRANSFORMFEEDBACKPROC, glEndTransformFeedback)
REAL(PFNGLTRANSFORMFEEDBACKVARYINGSPROC, glTransformFeedbackVaryings)
REAL(PFNGLGETPROGRAMIVPROC, glGetProgramiv)
REAL(PFNGLGETATTACHEDSHADERSPROC, glGetAttachedShaders)
REAL(PFNGLGETSHADERIVPROC, glGetShaderiv)
REAL(PFNGLGETSHADERSOURCEPROC, glGetShaderSource)
REAL(PFNGLGENQUERIESPROC, glGenQueries)
REAL(PFNGLBEGINQUERYPROC, glBeginQuery)
REAL(PFNGLENDQUERYPROC, glEndQuery)
REAL(PFNGLGETQUERYOBJECTUIVPROC, glGetQueryObjectuiv)
REAL(decltype(&::glReadPixels), glReadPixels)
REAL(decltype(&::glPixelStorei), glPixelStorei)
REAL(PFNGLBINDFRAMEBUFFERPROC, glBindFramebuffer)
REAL(decltype(&::glReadBuffer), glReadBuffer)
REAL(decltype(&::glGetError), glGetError)
REAL(PFNGLGETNAMEDFRAMEBUFFERATTACHMENTPARAMETERIVPROC, glGetNamedFramebufferAttachmentParameteriv)
REAL(PFNGLGETTEXTURELEVELPARAMETERIVPROC, glGetTextureLevelParameteriv)
REAL(PFNGLGETNAMEDRENDERBUFFERPARAMETERIVPROC, glGetNamedRenderbufferParameteriv)
REAL(PFNGLCREATESHADERPROC, glCreateShader)
REAL(PFNGLSHADERSOURCEPROC, glShaderSource)
REAL(PFNGLCOMPILESHADERPROC, glCompileShader)
REAL(PFNGLCREATEPROGRAMPROC, glCreateProgram)
REAL(PFNGLATTACHSHADERPROC, glAttachShader)
REAL(PFNGLUSEPROGRAMPROC, glUseProgram)

// Functions the application calls and we wrap.
REAL(decltype(&::glDrawArrays), glDrawArrays)
REAL(decltype(&::glDrawElements), glDrawElements)
REAL(PFNGLDRAWRANGEELEMENTSPROC, glDrawRangeElements)
REAL(PFNGLDRAWARRAYSINSTANCEDPROC, glDrawArraysInstanced)
REAL(PFNGLDRAWELEMENTSINSTANCEDPROC, glDrawElementsInstanced)
REAL(PFNGLDRAWELEMENTSBASEVERTEXPROC, glDrawElementsBaseVertex)
REAL(PFNGLLINKPROGRAMPROC, glLinkProgram)
REAL(decltype(&::glBegin), glBegin)
REAL(decltype(&::glClear), glClear)

using SwapFn = void (*)(Display*, GLXDrawable);
using QueryDrawableFn = void (*)(Display*, GLXDrawable, int, unsigned int*);
using EglSwapFn = EGLBoolean (*)(EGLDisplay, EGLSurface);
using EglQuerySurfaceFn = EGLBoolean (*)(EGLDisplay, EGLSurface, EGLint, EGLint*);

// ---- configuration and the dump ----------------------------------------------------------

struct Config {
  FILE* out = nullptr;
  uint32_t skip = 0, frames = 1;
  bool exit_after = true;
  bool offscreen = false;  // framebuffer-object passes too, each a trace frame of its own
};

Config& config() {
  static Config config = [] {
    Config c;
    if (const char* p = getenv("TILEVIS_CAPTURE_OUT"); p && *p) {
      c.out = fopen(p, "wb");
      if (!c.out) fprintf(stderr, "tilevis capture: cannot write %s\n", p);
      else fwrite(kDumpMagic, 1, sizeof kDumpMagic, c.out);
    }
    if (const char* p = getenv("TILEVIS_CAPTURE_SKIP")) c.skip = uint32_t(strtoul(p, nullptr, 10));
    if (const char* p = getenv("TILEVIS_CAPTURE_FRAMES")) c.frames = uint32_t(strtoul(p, nullptr, 10));
    if (const char* p = getenv("TILEVIS_CAPTURE_EXIT")) c.exit_after = strcmp(p, "0") != 0;
    if (const char* p = getenv("TILEVIS_CAPTURE_OFFSCREEN")) c.offscreen = strcmp(p, "1") == 0;
    return c;
  }();
  return config;
}

std::recursive_mutex g_mutex;
uint32_t g_frame = 0;   // buffer swaps so far
bool g_inside = false;  // inside a capture: our own draws are not captured again

bool capturing() {
  const Config& c = config();
  return c.out && !g_inside && g_frame >= c.skip && g_frame - c.skip < c.frames;
}

void put_u32(uint32_t v) { fwrite(&v, 4, 1, config().out); }
void put_i32(int32_t v) { fwrite(&v, 4, 1, config().out); }
void put_f32(float v) { fwrite(&v, 4, 1, config().out); }
void put_str(const std::string& s) {
  put_u32(uint32_t(s.size()));
  fwrite(s.data(), 1, s.size(), config().out);
}

void skip_record(const std::string& reason) {
  put_u32(kTagSkip);
  put_u32(g_frame);
  put_str(reason);
}

// ---- programs: the feedback varying and what the fragment shader does -------------------

struct ProgramInfo {
  bool feedback = false;      // linked with gl_Position as its one feedback varying
  bool discards = false;      // a fragment shader with `discard`
  bool writes_depth = false;  // a fragment shader writing gl_FragDepth
};
std::unordered_map<GLuint, ProgramInfo> g_programs;

// Source without comments, so `discard` in a comment does not count.
std::string strip_comments(const std::string& s) {
  std::string r;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s.compare(i, 2, "//") == 0) {
      while (i < s.size() && s[i] != '\n') ++i;
      r += '\n';
    } else if (s.compare(i, 2, "/*") == 0) {
      size_t e = s.find("*/", i + 2);
      i = e == std::string::npos ? s.size() : e + 1;
      r += ' ';
    } else {
      r += s[i];
    }
  }
  return r;
}

bool has_word(const std::string& s, const char* w) {
  const size_t n = strlen(w);
  for (size_t p = s.find(w); p != std::string::npos; p = s.find(w, p + 1)) {
    auto ident = [](char c) { return isalnum(static_cast<unsigned char>(c)) || c == '_'; };
    if ((p == 0 || !ident(s[p - 1])) && (p + n >= s.size() || !ident(s[p + n]))) return true;
  }
  return false;
}

ProgramInfo inspect_program(GLuint program) {
  ProgramInfo info;
  GLuint shaders[16];
  GLsizei n = 0;
  glGetAttachedShaders_()(program, 16, &n, shaders);
  for (GLsizei i = 0; i < n; ++i) {
    GLint type = 0, length = 0;
    glGetShaderiv_()(shaders[i], GL_SHADER_TYPE, &type);
    if (type != GL_FRAGMENT_SHADER) continue;
    glGetShaderiv_()(shaders[i], GL_SHADER_SOURCE_LENGTH, &length);
    std::string src(size_t(length > 0 ? length : 0), '\0');
    if (length > 0) glGetShaderSource_()(shaders[i], length, nullptr, src.data());
    src = strip_comments(src);
    info.discards |= has_word(src, "discard");
    info.writes_depth |= has_word(src, "gl_FragDepth");
  }
  return info;
}

// The fixed-function vertex stage as a program: ftransform() is the fixed-function transform
// of gl_Vertex by the current modelview and projection matrices (GLSL 1.20 §7.1), which a
// compatibility context's built-in uniforms track. Null where it cannot be built (core).
GLuint fixed_function_program() {
  static GLuint program = [] {
    const char* src = "#version 120\nvoid main() { gl_Position = ftransform(); }\n";
    GLuint vs = glCreateShader_()(GL_VERTEX_SHADER);
    if (!vs) return GLuint(0);
    glShaderSource_()(vs, 1, &src, nullptr);
    glCompileShader_()(vs);
    GLuint p = glCreateProgram_()();
    glAttachShader_()(p, vs);
    const char* varying = "gl_Position";
    glTransformFeedbackVaryings_()(p, 1, &varying, GL_INTERLEAVED_ATTRIBS);
    glLinkProgram_()(p);
    GLint ok = 0;
    glGetProgramiv_()(p, GL_LINK_STATUS, &ok);
    glGetError_()();
    return ok ? p : GLuint(0);
  }();
  return program;
}

// ---- one draw ----------------------------------------------------------------------------

const char* mode_name(GLenum mode) {
  switch (mode) {
    case GL_POINTS: return "POINTS";
    case GL_LINES: return "LINES";
    case GL_LINE_LOOP: return "LINE_LOOP";
    case GL_LINE_STRIP: return "LINE_STRIP";
    case GL_TRIANGLES: return "TRIANGLES";
    case GL_TRIANGLE_STRIP: return "TRIANGLE_STRIP";
    case GL_TRIANGLE_FAN: return "TRIANGLE_FAN";
    case GL_QUADS: return "QUADS";
    case GL_QUAD_STRIP: return "QUAD_STRIP";
    case GL_POLYGON: return "POLYGON";
    default: return "other";
  }
}

bool is_triangle_mode(GLenum mode) {
  switch (mode) {
    case GL_TRIANGLES: case GL_TRIANGLE_STRIP: case GL_TRIANGLE_FAN:
    case GL_QUADS: case GL_QUAD_STRIP: case GL_POLYGON:
      return true;
    default:
      return false;
  }
}

// Triangles of one run of vertices (no restart inside), as positions in the run. Strips
// alternate so that every triangle keeps the strip's winding (GL 4.6 §10.1.7).
void triangulate(GLenum mode, size_t n, std::vector<uint32_t>& out, uint32_t base) {
  auto tri = [&](size_t a, size_t b, size_t c) {
    out.push_back(base + uint32_t(a));
    out.push_back(base + uint32_t(b));
    out.push_back(base + uint32_t(c));
  };
  switch (mode) {
    case GL_TRIANGLES:
      for (size_t i = 0; i + 2 < n; i += 3) tri(i, i + 1, i + 2);
      break;
    case GL_TRIANGLE_STRIP:
      for (size_t i = 0; i + 2 < n; ++i) (i % 2 == 0) ? tri(i, i + 1, i + 2) : tri(i + 1, i, i + 2);
      break;
    case GL_TRIANGLE_FAN:
    case GL_POLYGON:
      for (size_t i = 1; i + 1 < n; ++i) tri(0, i, i + 1);
      break;
    case GL_QUADS:
      for (size_t i = 0; i + 3 < n; i += 4) tri(i, i + 1, i + 2), tri(i, i + 2, i + 3);
      break;
    case GL_QUAD_STRIP:
      for (size_t i = 0; i + 3 < n; i += 2) tri(i, i + 1, i + 3), tri(i, i + 3, i + 2);
      break;
    default:
      break;
  }
}

uint32_t state_bits() {
  uint32_t s = 0;
  GLint v = 0;
  if (glIsEnabled_()(GL_CULL_FACE)) s |= kStateCullEnabled;
  glGetIntegerv_()(GL_CULL_FACE_MODE, &v);
  if (v == GL_FRONT || v == GL_FRONT_AND_BACK) s |= kStateCullFront;
  if (v == GL_BACK || v == GL_FRONT_AND_BACK) s |= kStateCullBack;
  glGetIntegerv_()(GL_FRONT_FACE, &v);
  if (v == GL_CW) s |= kStateFrontCw;
  if (glIsEnabled_()(GL_DEPTH_TEST)) s |= kStateDepthTest;
  GLboolean mask = GL_TRUE;
  glGetBooleanv_()(GL_DEPTH_WRITEMASK, &mask);
  if (mask) s |= kStateDepthWrite;
  glGetIntegerv_()(GL_DEPTH_FUNC, &v);
  if (v == GL_ALWAYS) s |= kStateDepthFuncAlways;
  else if (v != GL_LESS && v != GL_LEQUAL) s |= kStateDepthFuncOther;
  if (glIsEnabled_()(GL_BLEND)) {
    // Blending with source ONE, destination ZERO replaces the colour: opaque.
    GLint src = 0, dst = 0, src_a = 0, dst_a = 0;
    glGetIntegerv_()(GL_BLEND_SRC_RGB, &src);
    glGetIntegerv_()(GL_BLEND_DST_RGB, &dst);
    glGetIntegerv_()(GL_BLEND_SRC_ALPHA, &src_a);
    glGetIntegerv_()(GL_BLEND_DST_ALPHA, &dst_a);
    if (!(src == GL_ONE && dst == GL_ZERO && src_a == GL_ONE && dst_a == GL_ZERO)) s |= kStateBlend;
  }
  if (glIsEnabled_()(GL_ALPHA_TEST)) s |= kStateAlphaTest;
  glGetError_()();  // GL_ALPHA_TEST is not an enum of core contexts
  if (glIsEnabled_()(GL_SCISSOR_TEST)) s |= kStateScissor;
  GLboolean cm[4] = {GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE};
  glGetBooleanv_()(GL_COLOR_WRITEMASK, cm);
  if (!cm[0] && !cm[1] && !cm[2] && !cm[3]) s |= kStateColorMaskNone;
  if (glIsEnabled_()(GL_POLYGON_OFFSET_FILL)) s |= kStatePolygonOffset;
  if (glIsEnabled_()(GL_DEPTH_CLAMP)) s |= kStateDepthClamp;
  if (glIsEnabled_()(GL_STENCIL_TEST)) s |= kStateStencil;
  return s;
}

// The indices of an element draw, widened to 32 bits, from the bound element buffer or
// client memory.
std::vector<uint32_t> read_indices(GLsizei count, GLenum type, const void* indices) {
  const size_t size = type == GL_UNSIGNED_BYTE ? 1 : type == GL_UNSIGNED_SHORT ? 2 : 4;
  std::vector<uint8_t> bytes(size * size_t(count));
  GLint element_buffer = 0;
  glGetIntegerv_()(GL_ELEMENT_ARRAY_BUFFER_BINDING, &element_buffer);
  if (element_buffer)
    glGetBufferSubData_()(GL_ELEMENT_ARRAY_BUFFER, GLintptr(reinterpret_cast<uintptr_t>(indices)),
                          GLsizeiptr(bytes.size()), bytes.data());
  else if (indices)
    memcpy(bytes.data(), indices, bytes.size());
  std::vector<uint32_t> r(static_cast<size_t>(count));
  for (size_t i = 0; i < r.size(); ++i) {
    if (size == 1) r[i] = bytes[i];
    else if (size == 2) r[i] = uint16_t(bytes[2 * i] | bytes[2 * i + 1] << 8);
    else memcpy(&r[i], &bytes[4 * i], 4);
  }
  return r;
}

GLuint g_feedback_buffer = 0, g_feedback_query = 0;
size_t g_feedback_capacity = 0;
uint32_t g_draw_in_frame = 0;
uint32_t g_last_frame = UINT32_MAX;

// Render passes of the frame: a run of captured draws into one framebuffer (0: the window).
int64_t g_pass_fb = -1;          // the current pass's framebuffer, -1 none
uint32_t g_pass = 0;             // passes ended in this frame
bool g_window_pass_seen = false; // a pass into the window in this frame
GLint g_pass_viewport[4] = {0, 0, 0, 0};
uint32_t g_window_w = 0, g_window_h = 0;

void end_pass();

// Runs `replay` (the application's draw, as points) under transform feedback of gl_Position
// and returns the positions written, `expected` of them.
template <class Replay>
bool feedback(size_t expected, std::vector<float>& out, Replay replay) {
  const size_t bytes = expected * 16;
  if (!g_feedback_buffer) {
    glGenBuffers_()(1, &g_feedback_buffer);
    glGenQueries_()(1, &g_feedback_query);
  }
  GLint saved_generic = 0, saved_indexed = 0;
  glGetIntegerv_()(GL_TRANSFORM_FEEDBACK_BUFFER_BINDING, &saved_generic);
  glGetIntegeri_v_()(GL_TRANSFORM_FEEDBACK_BUFFER_BINDING, 0, &saved_indexed);
  glBindBuffer_()(GL_TRANSFORM_FEEDBACK_BUFFER, g_feedback_buffer);
  if (bytes > g_feedback_capacity) {
    g_feedback_capacity = bytes * 2;
    glBufferData_()(GL_TRANSFORM_FEEDBACK_BUFFER, GLsizeiptr(g_feedback_capacity), nullptr, GL_STREAM_READ);
  }
  glBindBufferBase_()(GL_TRANSFORM_FEEDBACK_BUFFER, 0, g_feedback_buffer);
  const bool discard_was_on = glIsEnabled_()(GL_RASTERIZER_DISCARD);
  glEnable_()(GL_RASTERIZER_DISCARD);
  glBeginQuery_()(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN, g_feedback_query);
  glBeginTransformFeedback_()(GL_POINTS);
  replay();
  glEndTransformFeedback_()();
  glEndQuery_()(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN);
  if (!discard_was_on) glDisable_()(GL_RASTERIZER_DISCARD);
  GLuint written = 0;
  glGetQueryObjectuiv_()(g_feedback_query, GL_QUERY_RESULT, &written);
  out.assign(expected * 4, 0.0f);
  if (written == expected && bytes) glGetBufferSubData_()(GL_TRANSFORM_FEEDBACK_BUFFER, 0, GLsizeiptr(bytes), out.data());
  glBindBufferBase_()(GL_TRANSFORM_FEEDBACK_BUFFER, 0, GLuint(saved_indexed));
  glBindBuffer_()(GL_TRANSFORM_FEEDBACK_BUFFER, GLuint(saved_generic));
  return written == expected;
}

// One draw call: `elements` is null for array draws (then `first`, `count`), else the element
// indices as drawn (restart values included); `base_vertex` is added to each.
void capture_draw(const char* call, GLenum mode, GLint first, GLsizei count, const std::vector<uint32_t>* elements,
                  GLint base_vertex, GLsizei instances, const std::function<void()>& replay_points) {
  if (g_last_frame != g_frame) g_last_frame = g_frame, g_draw_in_frame = 0;
  const uint32_t draw_number = g_draw_in_frame++;
  std::string name = std::string(call) + "(" + mode_name(mode) + ") #" + std::to_string(draw_number);
  if (!is_triangle_mode(mode)) return skip_record(name + ": not triangles");
  if (count <= 0 || instances <= 0) return skip_record(name + ": empty");
  GLint framebuffer = 0;
  glGetIntegerv_()(GL_DRAW_FRAMEBUFFER_BINDING, &framebuffer);
  if (framebuffer != 0 && !config().offscreen)
    return skip_record(name + ": framebuffer object " + std::to_string(framebuffer) + " (off screen)");
  GLint program = 0;
  glGetIntegerv_()(GL_CURRENT_PROGRAM, &program);
  ProgramInfo info;
  GLuint shadow = 0;  // the fixed-function stage's program, used for this draw only
  if (program == 0) {
    shadow = fixed_function_program();
    if (!shadow) return skip_record(name + ": fixed-function vertex stage (no ftransform program in this context)");
    info.feedback = true;
  } else {
    info = g_programs[GLuint(program)];
  }
  if (!info.feedback) return skip_record(name + ": program " + std::to_string(program) + " has no gl_Position feedback");
  GLint active = 0;
  glGetIntegerv_()(GL_TRANSFORM_FEEDBACK_ACTIVE, &active);
  if (active) return skip_record(name + ": the application's transform feedback is active");

  // The vertices as drawn, restart values removed; runs split at restarts.
  std::vector<uint32_t> drawn;
  std::vector<size_t> run_ends;
  if (elements) {
    uint32_t restart = 0;
    bool restart_on = false;
    if (glIsEnabled_()(GL_PRIMITIVE_RESTART_FIXED_INDEX)) {
      restart_on = true;
      restart = 0xffffffffu;  // widened: compared before widening below
    } else if (glIsEnabled_()(GL_PRIMITIVE_RESTART)) {
      GLint r = 0;
      glGetIntegerv_()(GL_PRIMITIVE_RESTART_INDEX, &r);
      restart_on = true;
      restart = uint32_t(r);
    }
    for (uint32_t e : *elements) {
      if (restart_on && e == restart) {
        run_ends.push_back(drawn.size());
        continue;
      }
      drawn.push_back(e + uint32_t(base_vertex));
    }
  } else {
    for (GLsizei i = 0; i < count; ++i) drawn.push_back(uint32_t(first + i));
  }
  run_ends.push_back(drawn.size());

  std::vector<float> positions;
  const size_t expected = drawn.size() * size_t(instances);
  if (shadow) glUseProgram_()(shadow);
  const bool complete = feedback(expected, positions, replay_points);
  if (shadow) glUseProgram_()(0);
  if (!complete) return skip_record(name + ": transform feedback wrote fewer positions than drawn");

  // One trace vertex per distinct index value and instance; triangles over them.
  std::vector<float> vertices;
  std::vector<uint32_t> indices, run_triangles;
  for (GLsizei inst = 0; inst < instances; ++inst) {
    std::unordered_map<uint32_t, uint32_t> slot;
    std::vector<uint32_t> slots(drawn.size());
    for (size_t k = 0; k < drawn.size(); ++k) {
      auto [it, fresh] = slot.emplace(drawn[k], uint32_t(vertices.size() / 4));
      if (fresh) vertices.insert(vertices.end(), &positions[(size_t(inst) * drawn.size() + k) * 4],
                                 &positions[(size_t(inst) * drawn.size() + k) * 4 + 4]);
      slots[k] = it->second;
    }
    size_t begin = 0;
    for (size_t end : run_ends) {
      run_triangles.clear();
      triangulate(mode, end - begin, run_triangles, uint32_t(begin));
      for (uint32_t p : run_triangles) indices.push_back(slots[p]);
      begin = end;
    }
  }

  if (g_pass_fb != framebuffer) {
    if (g_pass_fb >= 0) end_pass();
    g_pass_fb = framebuffer;
    glGetIntegerv_()(GL_VIEWPORT, g_pass_viewport);
    g_window_pass_seen |= framebuffer == 0;
  }
  if (framebuffer != 0) name += " fbo " + std::to_string(framebuffer);
  const uint32_t state = state_bits();
  uint32_t flags = 0;
  if (state & kStateBlend) flags |= 2u;           // kBlended
  if (state & kStateAlphaTest) flags |= 1u;       // kAlphaTested
  if (info.writes_depth) flags |= 4u;             // kShaderWritesDepth
  if (info.discards) flags |= 8u;                 // kShaderDiscards
  if (!elements && mode == GL_TRIANGLES) flags |= 16u;  // kTriangleSoup: no index shares a vertex
  GLint viewport[4] = {0, 0, 0, 0};
  glGetIntegerv_()(GL_VIEWPORT, viewport);
  GLfloat range[2] = {0, 1};
  glGetFloatv_()(GL_DEPTH_RANGE, range);
  name += program ? " program " + std::to_string(program) : " fixed-function";

  put_u32(kTagDraw);
  put_u32(g_frame);
  put_u32(g_pass);
  put_str(name);
  put_u32(flags);
  put_u32(state);
  for (GLint v : viewport) put_i32(v);
  put_f32(range[0]);
  put_f32(range[1]);
  put_u32(uint32_t(vertices.size() / 4));
  fwrite(vertices.data(), 4, vertices.size(), config().out);
  put_u32(uint32_t(indices.size()));
  fwrite(indices.data(), 4, indices.size(), config().out);
}

// Guards one wrapped draw: captures it when its frame is chosen, then runs the real call.
template <class Capture>
void around_draw(Capture capture) {
  std::lock_guard<std::recursive_mutex> lock(g_mutex);
  if (!capturing()) return;
  g_inside = true;
  capture();
  g_inside = false;
}

// ---- the end of a frame ----------------------------------------------------------------

// The size of framebuffer object `fb` from its depth (else first colour) attachment, 0 x 0
// when it has neither.
void framebuffer_size(GLuint fb, uint32_t& w, uint32_t& h) {
  w = h = 0;
  for (GLenum attachment : {GLenum(GL_DEPTH_ATTACHMENT), GLenum(GL_DEPTH_STENCIL_ATTACHMENT), GLenum(GL_COLOR_ATTACHMENT0)}) {
    GLint type = GL_NONE, name = 0, level = 0, iw = 0, ih = 0;
    glGetNamedFramebufferAttachmentParameteriv_()(fb, attachment, GL_FRAMEBUFFER_ATTACHMENT_OBJECT_TYPE, &type);
    if (type == GL_NONE) continue;
    glGetNamedFramebufferAttachmentParameteriv_()(fb, attachment, GL_FRAMEBUFFER_ATTACHMENT_OBJECT_NAME, &name);
    if (type == GL_TEXTURE) {
      glGetNamedFramebufferAttachmentParameteriv_()(fb, attachment, GL_FRAMEBUFFER_ATTACHMENT_TEXTURE_LEVEL, &level);
      glGetTextureLevelParameteriv_()(GLuint(name), level, GL_TEXTURE_WIDTH, &iw);
      glGetTextureLevelParameteriv_()(GLuint(name), level, GL_TEXTURE_HEIGHT, &ih);
    } else if (type == GL_RENDERBUFFER) {
      glGetNamedRenderbufferParameteriv_()(GLuint(name), GL_RENDERBUFFER_WIDTH, &iw);
      glGetNamedRenderbufferParameteriv_()(GLuint(name), GL_RENDERBUFFER_HEIGHT, &ih);
    }
    if (iw > 0 && ih > 0) {
      w = uint32_t(iw), h = uint32_t(ih);
      return;
    }
  }
}

// Ends the current pass: its size and the depth its framebuffer holds now.
void end_pass() {
  const Config& c = config();
  const GLuint fb = GLuint(g_pass_fb < 0 ? 0 : g_pass_fb);
  uint32_t width = 0, height = 0;
  glGetError_()();
  if (fb == 0) width = g_window_w, height = g_window_h;
  else framebuffer_size(fb, width, height);
  glGetError_()();
  if (width == 0 || height == 0) {  // unknown: the extent of the pass's first viewport
    width = uint32_t(std::max(0, g_pass_viewport[0] + g_pass_viewport[2]));
    height = uint32_t(std::max(0, g_pass_viewport[1] + g_pass_viewport[3]));
  }
  GLint read_fb = 0, read_buffer = 0, pack_buffer = 0, alignment = 4, row_length = 0, skip_rows = 0, skip_pixels = 0;
  glGetIntegerv_()(GL_READ_FRAMEBUFFER_BINDING, &read_fb);
  glGetIntegerv_()(GL_READ_BUFFER, &read_buffer);
  glGetIntegerv_()(GL_PIXEL_PACK_BUFFER_BINDING, &pack_buffer);
  glGetIntegerv_()(GL_PACK_ALIGNMENT, &alignment);
  glGetIntegerv_()(GL_PACK_ROW_LENGTH, &row_length);
  glGetIntegerv_()(GL_PACK_SKIP_ROWS, &skip_rows);
  glGetIntegerv_()(GL_PACK_SKIP_PIXELS, &skip_pixels);
  glBindFramebuffer_()(GL_READ_FRAMEBUFFER, fb);
  if (fb == 0) glReadBuffer_()(GL_BACK);
  glBindBuffer_()(GL_PIXEL_PACK_BUFFER, 0);
  glPixelStorei_()(GL_PACK_ALIGNMENT, 4);
  glPixelStorei_()(GL_PACK_ROW_LENGTH, 0);
  glPixelStorei_()(GL_PACK_SKIP_ROWS, 0);
  glPixelStorei_()(GL_PACK_SKIP_PIXELS, 0);
  uint32_t dw = width, dh = height;
  std::vector<float> depth(size_t(dw) * dh);
  glGetError_()();
  glReadPixels_()(0, 0, GLsizei(dw), GLsizei(dh), GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
  if (glGetError_()() != GL_NO_ERROR) dw = dh = 0, depth.clear();  // no depth buffer there
  GLfloat clear = 1.0f;
  glGetFloatv_()(GL_DEPTH_CLEAR_VALUE, &clear);
  GLint bits = 0;
  if (fb == 0) glGetIntegerv_()(GL_DEPTH_BITS, &bits);
  glGetError_()();  // GL_DEPTH_BITS is not in core contexts
  glBindFramebuffer_()(GL_READ_FRAMEBUFFER, GLuint(read_fb));
  if (fb == 0) glReadBuffer_()(GLenum(read_buffer));
  glGetError_()();
  glBindBuffer_()(GL_PIXEL_PACK_BUFFER, GLuint(pack_buffer));
  glPixelStorei_()(GL_PACK_ALIGNMENT, alignment);
  glPixelStorei_()(GL_PACK_ROW_LENGTH, row_length);
  glPixelStorei_()(GL_PACK_SKIP_ROWS, skip_rows);
  glPixelStorei_()(GL_PACK_SKIP_PIXELS, skip_pixels);
  put_u32(kTagPassEnd);
  put_u32(g_frame);
  put_u32(g_pass);
  put_u32(fb);
  put_u32(width);
  put_u32(height);
  put_f32(clear);
  put_u32(uint32_t(bits));
  put_u32(dw);
  put_u32(dh);
  fwrite(depth.data(), 4, depth.size(), c.out);
  ++g_pass;
  g_pass_fb = -1;
}

void end_frame(uint32_t width, uint32_t height) {
  std::lock_guard<std::recursive_mutex> lock(g_mutex);
  Config& c = config();
  if (width && height) g_window_w = width, g_window_h = height;
  if (capturing()) {
    g_inside = true;
    if (g_pass_fb >= 0) end_pass();
    if (!g_window_pass_seen) {  // the window's pass, empty: the frame exists, with its depth
      g_pass_fb = 0;
      g_pass_viewport[2] = GLint(width), g_pass_viewport[3] = GLint(height);
      end_pass();
    }
    fflush(c.out);
    g_inside = false;
  }
  g_pass_fb = -1;
  g_pass = 0;
  g_window_pass_seen = false;
  ++g_frame;
  if (c.out && c.exit_after && c.frames > 0 && g_frame == c.skip + c.frames) {
    fclose(c.out);
    c.out = nullptr;
    _exit(0);
  }
}

}  // namespace

// ---- wrapped GL entry points -------------------------------------------------------------

EXPORT void glLinkProgram(GLuint program) {
  std::lock_guard<std::recursive_mutex> lock(g_mutex);
  if (!config().out) return glLinkProgram_()(program);
  const char* varying = "gl_Position";
  glTransformFeedbackVaryings_()(program, 1, &varying, GL_INTERLEAVED_ATTRIBS);
  glLinkProgram_()(program);
  GLint ok = 0;
  glGetProgramiv_()(program, GL_LINK_STATUS, &ok);
  ProgramInfo info;
  if (ok) {
    info.feedback = true;
  } else {  // the feedback varying must not make a program fail: link it as the application asked
    glTransformFeedbackVaryings_()(program, 0, nullptr, GL_INTERLEAVED_ATTRIBS);
    glLinkProgram_()(program);
  }
  const ProgramInfo shader = inspect_program(program);
  info.discards = shader.discards;
  info.writes_depth = shader.writes_depth;
  g_programs[program] = info;
}

// A depth clear inside a frame: what was drawn before it no longer occludes what follows.
EXPORT void glClear(GLbitfield mask) {
  {
    std::lock_guard<std::recursive_mutex> lock(g_mutex);
    GLint framebuffer = 0;
    if (capturing() && (mask & GL_DEPTH_BUFFER_BIT)) {
      glGetIntegerv_()(GL_DRAW_FRAMEBUFFER_BINDING, &framebuffer);
      if (framebuffer == g_pass_fb) {  // a clear before a pass's first draw clears nothing captured
        if (g_last_frame != g_frame) g_last_frame = g_frame, g_draw_in_frame = 0;
        put_u32(kTagDepthClear);
        put_u32(g_frame);
        put_u32(g_pass);
        put_u32(g_draw_in_frame);
      }
    }
  }
  glClear_()(mask);
}

// Immediate mode is not captured; counted so the capture says what it left out.
EXPORT void glBegin(GLenum mode) {
  {
    std::lock_guard<std::recursive_mutex> lock(g_mutex);
    if (capturing()) skip_record(std::string("glBegin(") + mode_name(mode) + "): immediate mode");
  }
  glBegin_()(mode);
}

EXPORT void glDrawArrays(GLenum mode, GLint first, GLsizei count) {
  around_draw([&] {
    capture_draw("glDrawArrays", mode, first, count, nullptr, 0, 1,
                 [&] { glDrawArrays_()(GL_POINTS, first, count); });
  });
  glDrawArrays_()(mode, first, count);
}

EXPORT void glDrawArraysInstanced(GLenum mode, GLint first, GLsizei count, GLsizei instances) {
  around_draw([&] {
    capture_draw("glDrawArraysInstanced", mode, first, count, nullptr, 0, instances,
                 [&] { glDrawArraysInstanced_()(GL_POINTS, first, count, instances); });
  });
  glDrawArraysInstanced_()(mode, first, count, instances);
}

EXPORT void glDrawElements(GLenum mode, GLsizei count, GLenum type, const void* indices) {
  around_draw([&] {
    const auto e = read_indices(count, type, indices);
    capture_draw("glDrawElements", mode, 0, count, &e, 0, 1,
                 [&] { glDrawElements_()(GL_POINTS, count, type, indices); });
  });
  glDrawElements_()(mode, count, type, indices);
}

EXPORT void glDrawRangeElements(GLenum mode, GLuint start, GLuint end, GLsizei count, GLenum type,
                                const void* indices) {
  around_draw([&] {
    const auto e = read_indices(count, type, indices);
    capture_draw("glDrawRangeElements", mode, 0, count, &e, 0, 1,
                 [&] { glDrawRangeElements_()(GL_POINTS, start, end, count, type, indices); });
  });
  glDrawRangeElements_()(mode, start, end, count, type, indices);
}

EXPORT void glDrawElementsInstanced(GLenum mode, GLsizei count, GLenum type, const void* indices, GLsizei instances) {
  around_draw([&] {
    const auto e = read_indices(count, type, indices);
    capture_draw("glDrawElementsInstanced", mode, 0, count, &e, 0, instances,
                 [&] { glDrawElementsInstanced_()(GL_POINTS, count, type, indices, instances); });
  });
  glDrawElementsInstanced_()(mode, count, type, indices, instances);
}

EXPORT void glDrawElementsBaseVertex(GLenum mode, GLsizei count, GLenum type, const void* indices, GLint base) {
  around_draw([&] {
    const auto e = read_indices(count, type, indices);
    capture_draw("glDrawElementsBaseVertex", mode, 0, count, &e, base, 1,
                 [&] { glDrawElementsBaseVertex_()(GL_POINTS, count, type, indices, base); });
  });
  glDrawElementsBaseVertex_()(mode, count, type, indices, base);
}

EXPORT void glMultiDrawArrays(GLenum mode, const GLint* first, const GLsizei* count, GLsizei n) {
  for (GLsizei i = 0; i < n; ++i) glDrawArrays(mode, first[i], count[i]);
}

EXPORT void glMultiDrawElements(GLenum mode, const GLsizei* count, GLenum type, const void* const* indices, GLsizei n) {
  for (GLsizei i = 0; i < n; ++i) glDrawElements(mode, count[i], type, indices[i]);
}

EXPORT void glXSwapBuffers(Display* dpy, GLXDrawable drawable) {
  static SwapFn real = reinterpret_cast<SwapFn>(real_gl("glXSwapBuffers"));
  static QueryDrawableFn query = reinterpret_cast<QueryDrawableFn>(real_gl("glXQueryDrawable"));
  unsigned w = 0, h = 0;
  if (config().out && query) {
    query(dpy, drawable, GLX_WIDTH, &w);
    query(dpy, drawable, GLX_HEIGHT, &h);
  }
  end_frame(w, h);
  real(dpy, drawable);
}

EXPORT EGLBoolean eglSwapBuffers(EGLDisplay dpy, EGLSurface surface) {
  static EglSwapFn real = reinterpret_cast<EglSwapFn>(real_egl("eglSwapBuffers"));
  static EglQuerySurfaceFn query = reinterpret_cast<EglQuerySurfaceFn>(real_egl("eglQuerySurface"));
  EGLint w = 0, h = 0;
  if (config().out && query) {
    query(dpy, surface, EGL_WIDTH, &w);
    query(dpy, surface, EGL_HEIGHT, &h);
  }
  end_frame(uint32_t(w), uint32_t(h));
  return real(dpy, surface);
}

// ---- how programs find GL entry points ---------------------------------------------------

namespace {

// Our wrapper for a GL or window-system function name, or null.
void* wrapper_for(const char* name);

}  // namespace

EXPORT __GLXextFuncPtr glXGetProcAddressARB(const GLubyte* name) {
  if (void* w = wrapper_for(reinterpret_cast<const char*>(name))) return reinterpret_cast<__GLXextFuncPtr>(w);
  static auto real = reinterpret_cast<GetProcFn>(real_dlsym()(libgl(), "glXGetProcAddressARB"));
  return real ? real(name) : nullptr;
}

EXPORT __GLXextFuncPtr glXGetProcAddress(const GLubyte* name) { return glXGetProcAddressARB(name); }

EXPORT __eglMustCastToProperFunctionPointerType eglGetProcAddress(const char* name) {
  if (void* w = wrapper_for(name)) return reinterpret_cast<__eglMustCastToProperFunctionPointerType>(w);
  static auto real = reinterpret_cast<EglGetProcFn>(real_egl("eglGetProcAddress"));
  return real ? real(name) : nullptr;
}

namespace {

std::mutex g_handles_mutex;
std::vector<void*> g_gl_handles;  // handles of libGL, libEGL, libOpenGL, libGLX the program opened

bool is_gl_library(const char* file) {
  if (!file) return false;
  const char* base = strrchr(file, '/');
  base = base ? base + 1 : file;
  return strncmp(base, "libGL.so", 8) == 0 || strncmp(base, "libEGL.so", 9) == 0 ||
         strncmp(base, "libOpenGL.so", 12) == 0 || strncmp(base, "libGLX.so", 9) == 0 ||
         strncmp(base, "libGLESv2.so", 12) == 0;
}

void* wrapper_for(const char* name) {
  if (!name) return nullptr;
  static const std::unordered_map<std::string, void*> table = {
      {"glDrawArrays", reinterpret_cast<void*>(&glDrawArrays)},
      {"glDrawArraysEXT", reinterpret_cast<void*>(&glDrawArrays)},
      {"glDrawArraysInstanced", reinterpret_cast<void*>(&glDrawArraysInstanced)},
      {"glDrawArraysInstancedARB", reinterpret_cast<void*>(&glDrawArraysInstanced)},
      {"glDrawElements", reinterpret_cast<void*>(&glDrawElements)},
      {"glDrawRangeElements", reinterpret_cast<void*>(&glDrawRangeElements)},
      {"glDrawRangeElementsEXT", reinterpret_cast<void*>(&glDrawRangeElements)},
      {"glDrawElementsInstanced", reinterpret_cast<void*>(&glDrawElementsInstanced)},
      {"glDrawElementsInstancedARB", reinterpret_cast<void*>(&glDrawElementsInstanced)},
      {"glDrawElementsBaseVertex", reinterpret_cast<void*>(&glDrawElementsBaseVertex)},
      {"glMultiDrawArrays", reinterpret_cast<void*>(&glMultiDrawArrays)},
      {"glMultiDrawElements", reinterpret_cast<void*>(&glMultiDrawElements)},
      {"glLinkProgram", reinterpret_cast<void*>(&glLinkProgram)},
      {"glBegin", reinterpret_cast<void*>(&glBegin)},
      {"glClear", reinterpret_cast<void*>(&glClear)},
      {"glLinkProgramARB", reinterpret_cast<void*>(&glLinkProgram)},
      {"glXSwapBuffers", reinterpret_cast<void*>(&glXSwapBuffers)},
      {"eglSwapBuffers", reinterpret_cast<void*>(&eglSwapBuffers)},
      {"glXGetProcAddress", reinterpret_cast<void*>(&glXGetProcAddress)},
      {"glXGetProcAddressARB", reinterpret_cast<void*>(&glXGetProcAddressARB)},
      {"eglGetProcAddress", reinterpret_cast<void*>(&eglGetProcAddress)},
  };
  auto it = table.find(name);
  return it == table.end() ? nullptr : it->second;
}

}  // namespace

EXPORT void* dlopen(const char* file, int flags) {
  void* h = real_dlopen()(file, flags);
  if (h && is_gl_library(file)) {
    std::lock_guard<std::mutex> lock(g_handles_mutex);
    g_gl_handles.push_back(h);
  }
  return h;
}

EXPORT void* dlsym(void* handle, const char* name) {
  bool gl_handle = false;
  {
    std::lock_guard<std::mutex> lock(g_handles_mutex);
    for (void* h : g_gl_handles) gl_handle |= h == handle;
  }
  if (gl_handle)
    if (void* w = wrapper_for(name)) return w;
  return real_dlsym()(handle, name);
}
