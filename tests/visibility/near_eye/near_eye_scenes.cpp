#include "near_eye_scenes.h"

#include <cmath>

namespace tilevis::near_eye {
namespace {

// SplitMix64: the same numbers on every platform.
struct Rng {
  uint64_t s;
  uint64_t next() {
    uint64_t z = (s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  float uniform() { return float(double(next() >> 40) / double(1ull << 24)) * 2.0f - 1.0f; }  // [-1, 1)
};

trace::Frame empty_frame(uint32_t width, uint32_t height) {
  trace::Frame f;
  f.width = width;
  f.height = height;
  f.samples = trace::standard_samples(1);
  return f;
}

trace::Draw background() {
  trace::Draw bg;
  bg.name = "far_plane_quad";
  bg.vertices = {{-1, -1, 1, 1}, {1, -1, 1, 1}, {1, 1, 1, 1}, {-1, 1, 1, 1}};  // z = w: the far plane
  bg.indices = {0, 1, 2, 0, 2, 3};
  return bg;
}

// A triangle with its front vertex at (x w0, y w0) in NDC and two vertices behind the eye,
// at NDC depth c everywhere (z = c w is exact for c a power of two or zero).
void add_triangle(trace::Draw& d, float c, float w0, float x0, float y0, float x1, float y1, float x2, float y2) {
  const auto base = uint32_t(d.vertices.size());
  d.vertices.push_back({x0 * w0, y0 * w0, c * w0, w0});
  d.vertices.push_back({x1, y1, -c, -1});
  d.vertices.push_back({x2, y2, -c, -1});
  d.indices.insert(d.indices.end(), {base, base + 1, base + 2});
}

}  // namespace

trace::Frame two_triangles(uint32_t width, uint32_t height, float c_a, float c_b) {
  trace::Frame f = empty_frame(width, height);
  trace::Draw d;
  d.name = "near_eye";
  d.flags = trace::kTriangleSoup;
  // Both counter-clockwise in NDC where they are in front of the eye (det[x y w] > 0).
  add_triangle(d, c_a, 0.001f, 0.2f, 0.1f, -0.4f, -0.8f, 0.9f, 0.3f);
  add_triangle(d, c_b, 0.001f, -0.3f, 0.2f, -0.7f, 0.6f, 0.5f, -0.9f);
  f.draws = {d, background()};
  return f;
}

trace::Frame random_near_eye(uint64_t seed, uint32_t count, uint32_t width, uint32_t height) {
  trace::Frame f = empty_frame(width, height);
  Rng rng{seed};
  const float depths[5] = {0.0f, 0.25f, -0.25f, 0.5f, -0.5f};
  trace::Draw d;
  d.name = "near_eye";
  d.flags = trace::kTriangleSoup;
  for (uint32_t t = 0; t < count; ++t) {
    const float c = depths[rng.next() % 5];
    const float w0 = std::ldexp(1.0f, -int(4 + rng.next() % 17));
    add_triangle(d, c, w0, rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform());
  }
  f.draws = {d, background()};
  return f;
}

trace::Frame near_zero_w(uint64_t seed, uint32_t width, uint32_t height) {
  trace::Frame f = empty_frame(width, height);
  Rng rng{seed};
  trace::Draw d;
  d.name = "near_zero_w";
  const float w = std::ldexp(rng.uniform(), -int(rng.next() % 126));
  d.vertices = {{rng.uniform(), rng.uniform(), rng.uniform() * 0.5f, 1.0f},
                {rng.uniform(), rng.uniform(), rng.uniform() * 0.5f, 1.0f},
                {rng.uniform(), rng.uniform(), 0.0f, w}};
  if (seed % 3 == 1) d.vertices[2] = {rng.uniform() * w, rng.uniform() * w, rng.uniform() * w, w};
  if (seed % 50 == 0) d.vertices[2] = {0, 0, 0, 0};
  d.indices = {0, 1, 2};
  f.draws = {d};
  return f;
}

}  // namespace tilevis::near_eye
