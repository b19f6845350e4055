#include "scenes.h"

#include "near_eye_scenes.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace tilevis::cudatest {
namespace {

void normalize(float v[3]) {
  const float l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  for (int i = 0; i < 3; ++i) v[i] /= l;
}

void cross(const float a[3], const float b[3], float out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

Mat4 multiply(const Mat4& a, const Mat4& b) {
  Mat4 r{};
  for (int c = 0; c < 4; ++c)
    for (int row = 0; row < 4; ++row) {
      float s = 0;
      for (int k = 0; k < 4; ++k) s += a.m[k * 4 + row] * b.m[c * 4 + k];
      r.m[c * 4 + row] = s;
    }
  return r;
}

}  // namespace

Mat4 look_at_perspective(const float eye[3], const float target[3], float fov_y_deg, float aspect, float near, float far) {
  float f[3] = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
  normalize(f);
  const float up[3] = {0, 1, 0};
  float s[3], u[3];
  cross(f, up, s);
  normalize(s);
  cross(s, f, u);
  Mat4 view{};
  view.m[0] = s[0], view.m[4] = s[1], view.m[8] = s[2];
  view.m[1] = u[0], view.m[5] = u[1], view.m[9] = u[2];
  view.m[2] = -f[0], view.m[6] = -f[1], view.m[10] = -f[2];
  view.m[12] = -(s[0] * eye[0] + s[1] * eye[1] + s[2] * eye[2]);
  view.m[13] = -(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2]);
  view.m[14] = f[0] * eye[0] + f[1] * eye[1] + f[2] * eye[2];
  view.m[15] = 1;
  const float t = 1.0f / std::tan(fov_y_deg * std::numbers::pi_v<float> / 360.0f);
  Mat4 proj{};
  proj.m[0] = t / aspect;
  proj.m[5] = t;
  proj.m[10] = (far + near) / (near - far);
  proj.m[11] = -1;
  proj.m[14] = 2 * far * near / (near - far);
  return multiply(proj, view);
}

void MeshBuilder::box(const float c[3], const float h[3], float rot_y_deg) {
  const auto base = uint32_t(pos.size() / 3);
  const float a = rot_y_deg * std::numbers::pi_v<float> / 180.0f, ca = std::cos(a), sa = std::sin(a);
  for (int i = 0; i < 8; ++i) {
    const float x = (i & 1 ? 1.0f : -1.0f) * h[0], y = (i & 2 ? 1.0f : -1.0f) * h[1], z = (i & 4 ? 1.0f : -1.0f) * h[2];
    pos.insert(pos.end(), {c[0] + ca * x + sa * z, c[1] + y, c[2] - sa * x + ca * z});
  }
  // Faces counter-clockwise seen from outside: (-x) 0 4 6 2, (+x) 1 3 7 5, (-y) 0 1 5 4, (+y) 2 6 7 3,
  // (-z) 0 2 3 1, (+z) 4 5 7 6.
  const uint32_t q[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& f : q) index.insert(index.end(), {base + f[0], base + f[1], base + f[2], base + f[0], base + f[2], base + f[3]});
}

void MeshBuilder::sphere(const float c[3], float r, int segments, int rings) {
  const auto base = uint32_t(pos.size() / 3);
  const float pi = std::numbers::pi_v<float>;
  for (int i = 0; i <= rings; ++i) {
    const float th = pi * float(i) / float(rings);
    for (int j = 0; j < segments; ++j) {
      const float ph = 2 * pi * float(j) / float(segments);
      pos.insert(pos.end(), {c[0] + r * std::sin(th) * std::cos(ph), c[1] + r * std::cos(th), c[2] + r * std::sin(th) * std::sin(ph)});
    }
  }
  auto v = [&](int i, int j) { return base + uint32_t(i * segments + (j % segments)); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      // Outward counter-clockwise (theta grows downward, phi around +y).
      if (i > 0) index.insert(index.end(), {v(i, j), v(i, j + 1), v(i + 1, j)});
      if (i + 1 < rings) index.insert(index.end(), {v(i, j + 1), v(i + 1, j + 1), v(i + 1, j)});
    }
}

void MeshBuilder::quad(const float c[3], float w, float h) {
  const auto base = uint32_t(pos.size() / 3);
  pos.insert(pos.end(), {c[0] - w / 2, c[1] - h / 2, c[2], c[0] + w / 2, c[1] - h / 2, c[2], c[0] + w / 2, c[1] + h / 2,
                         c[2], c[0] - w / 2, c[1] + h / 2, c[2]});
  index.insert(index.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
}

void MeshBuilder::plane(float y, float half, int n) {
  const auto base = uint32_t(pos.size() / 3);
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      pos.insert(pos.end(), {-half + 2 * half * float(j) / float(n), y, -half + 2 * half * float(i) / float(n)});
  auto v = [&](int i, int j) { return base + uint32_t(i * (n + 1) + j); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)  // facing +y: counter-clockwise seen from above
      index.insert(index.end(), {v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j), v(i + 1, j + 1), v(i, j + 1)});
}

trace::Draw make_draw(const std::string& name, const MeshBuilder& m, const Mat4& mvp, uint32_t flags) {
  trace::Draw d;
  d.name = name;
  d.flags = flags;
  for (size_t i = 0; i + 2 < m.pos.size(); i += 3) {
    const float x = m.pos[i], y = m.pos[i + 1], z = m.pos[i + 2];
    trace::Vec4 c;
    c.x = mvp.m[0] * x + mvp.m[4] * y + mvp.m[8] * z + mvp.m[12];
    c.y = mvp.m[1] * x + mvp.m[5] * y + mvp.m[9] * z + mvp.m[13];
    c.z = mvp.m[2] * x + mvp.m[6] * y + mvp.m[10] * z + mvp.m[14];
    c.w = mvp.m[3] * x + mvp.m[7] * y + mvp.m[11] * z + mvp.m[15];
    d.vertices.push_back(c);
  }
  if (flags & trace::kTriangleSoup) {  // unshared vertices: silhouettes keyed by position
    std::vector<trace::Vec4> v;
    for (uint32_t i : m.index) v.push_back(d.vertices[i]);
    d.vertices = v;
    for (uint32_t i = 0; i < m.index.size(); ++i) d.indices.push_back(i);
  } else {
    d.indices = m.index;
  }
  return d;
}

trace::Frame scene(const std::string& name, uint32_t samples) {
  trace::Frame f;
  f.width = 320;
  f.height = 240;
  f.samples = trace::standard_samples(samples);
  const float aspect = float(f.width) / float(f.height);
  if (name == "cubes") {
    const float eye[3] = {1.6f, 1.2f, 3.0f}, at[3] = {0, 0, 0};
    const Mat4 mvp = look_at_perspective(eye, at, 50, aspect, 0.1f, 20);
    MeshBuilder floor, box, ball, cards;
    floor.plane(-0.6f, 3, 3);
    const float c0[3] = {0, 0, 0}, h0[3] = {0.5f, 0.5f, 0.5f};
    box.box(c0, h0, 30);
    const float c1[3] = {-0.9f, -0.1f, 0.8f};
    ball.sphere(c1, 0.45f, 24, 12);
    for (int k = 0; k < 4; ++k) {
      const float c[3] = {1.6f - 0.1f * float(k), 0.05f * float(k), 1.5f - 0.25f * float(k)};
      cards.quad(c, 0.5f, 0.7f);
    }
    f.draws = {make_draw("floor", floor, mvp), make_draw("box", box, mvp), make_draw("ball", ball, mvp),
               make_draw("cards", cards, mvp)};
  } else if (name == "ground") {
    const float eye[3] = {0, 1, 2}, at[3] = {0, 0, 0};
    const Mat4 mvp = look_at_perspective(eye, at, 45, aspect, 0.1f, 100);
    MeshBuilder ground, box;
    ground.plane(0, 50, 2);
    const float c[3] = {0.2f, 0.3f, 0}, h[3] = {0.3f, 0.3f, 0.3f};
    box.box(c, h, 20);
    f.draws = {make_draw("ground", ground, mvp), make_draw("box", box, mvp)};
  } else if (name == "stack") {
    const float eye[3] = {0, 0, 2}, at[3] = {0, 0, 0};
    const Mat4 mvp = look_at_perspective(eye, at, 45, aspect, 0.1f, 20);
    MeshBuilder cards;
    for (int k = 0; k < 60; ++k) {
      const float c[3] = {0.003f * float(k), -0.002f * float(k), -2.0f + 0.03f * float(k)};
      cards.quad(c, 0.5f, 0.5f);
    }
    f.draws = {make_draw("stack", cards, mvp)};
  } else if (name == "mixed") {
    const float eye[3] = {0.5f, 0.8f, 2.5f}, at[3] = {0, 0, 0};
    const Mat4 mvp = look_at_perspective(eye, at, 45, aspect, 0.1f, 20);
    MeshBuilder a, b, c, d;
    const float ca[3] = {-0.5f, 0, 0}, ha[3] = {0.4f, 0.4f, 0.4f};
    a.box(ca, ha, 15);
    const float cb[3] = {0.3f, 0.1f, 0.5f};
    b.quad(cb, 0.8f, 0.6f);
    const float cc[3] = {0.5f, 0, -0.3f};
    c.sphere(cc, 0.4f, 16, 8);
    const float cd[3] = {-0.2f, -0.2f, 0.9f}, hd[3] = {0.15f, 0.2f, 0.1f};
    d.box(cd, hd, 40);
    f.draws = {make_draw("opaque", a, mvp), make_draw("glass", b, mvp, trace::kBlended),
               make_draw("soup", c, mvp, trace::kTriangleSoup), make_draw("depth", d, mvp, trace::kShaderWritesDepth)};
  } else if (name == "coplanar") {
    const float eye[3] = {0, 0, 3}, at[3] = {0, 0, 0};
    const Mat4 mvp = look_at_perspective(eye, at, 45, aspect, 0.1f, 20);
    MeshBuilder a, b;
    const float c0[3] = {0, 0, 0}, c1[3] = {0.3f, 0.2f, 0};
    a.quad(c0, 1.2f, 1.0f);
    b.quad(c1, 1.0f, 0.8f);
    f.draws = {make_draw("first", a, mvp), make_draw("second", b, mvp)};
  } else if (name == "folded") {
    const float eye[3] = {0.4f, 0.9f, 2.5f}, at[3] = {0, 0, 0};
    const Mat4 mvp = look_at_perspective(eye, at, 45, aspect, 0.1f, 20);
    MeshBuilder floor, card;
    floor.plane(-0.5f, 2, 3);
    const float c[3] = {0.1f, 0.1f, 0.4f};
    card.quad(c, 0.8f, 0.6f);
    // Every face twice with the same indices: each edge is shared by two faces on one side.
    const std::vector<uint32_t> once = card.index;
    card.index.insert(card.index.end(), once.begin(), once.end());
    f.draws = {make_draw("floor", floor, mvp), make_draw("card_twice", card, mvp)};
  } else if (name == "near_eye" || name == "near_eye_pair") {
    f = name == "near_eye" ? near_eye::random_near_eye(1, 60, f.width, f.height)
                           : near_eye::two_triangles(f.width, f.height, 0.0f, 0.0f);
    f.samples = trace::standard_samples(samples);
  } else {
    throw std::invalid_argument("unknown test scene " + name);
  }
  trace::Trace t;
  t.frames = {f};
  trace::validate(t);
  return f;
}

std::vector<trace::Frame> small_big_sequence() {
  const trace::Frame big = scene("cubes");
  trace::Frame small = big;
  for (auto& d : small.draws)
    for (auto& v : d.vertices) {
      v.x *= 0.5f;
      v.y *= 0.5f;
    }
  return {small, big, small, big};
}

std::vector<std::string> scene_names() {
  return {"cubes", "ground", "stack", "mixed", "coplanar", "folded", "near_eye", "near_eye_pair"};
}

}  // namespace tilevis::cudatest
