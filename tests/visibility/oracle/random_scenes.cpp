#include "random_scenes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace tilevis::oracle {
namespace {

constexpr uint32_t kDepthMax = (uint32_t{1} << kSceneDepthBits) - 1;
// Depths stay clear of the near and far planes (z = ∓w), which the pipeline clips against.
constexpr uint32_t kDepthLo = uint32_t{1} << 16;
constexpr uint32_t kDepthHi = kDepthMax - (uint32_t{1} << 16);
constexpr int kMaxTries = 10000;

// The pipeline's viewport transform and snap (model/visibility/setup.cpp, Snapper), term
// by term in the same double operations, for a 256×256 frame, depth range [0, 1], w = 1.
struct PipelineSnap {
  static int64_t x(float cx) {
    const double inv_w = 1.0 / static_cast<double>(1.0f);
    const double xw = (static_cast<double>(cx) * inv_w + 1.0) * (kSceneSize * 0.5);
    return static_cast<int64_t>(std::nearbyint(xw * double(kSubpixel)));
  }
  static int64_t y(float cy) {
    const double inv_w = 1.0 / static_cast<double>(1.0f);
    const double yw = (1.0 - static_cast<double>(cy) * inv_w) * (kSceneSize * 0.5);
    return static_cast<int64_t>(std::nearbyint(yw * double(kSubpixel)));
  }
  static uint32_t z(float cz) {
    const double inv_w = 1.0 / static_cast<double>(1.0f);
    const double depth_near = static_cast<double>(0.0f);
    const double depth_range = static_cast<double>(1.0f) - static_cast<double>(0.0f);
    double zw = depth_near + depth_range * (static_cast<double>(cz) * inv_w + 1.0) * 0.5;
    zw = std::clamp(zw, 0.0, 1.0);
    const auto s = static_cast<uint32_t>(std::nearbyint(zw * double(kDepthMax)));
    return std::min(s, kDepthMax);
  }
};

// splitmix64: a fixed, documented sequence, unlike std:: distributions whose output
// differs between standard libraries.
class Rng {
 public:
  explicit Rng(uint64_t seed) : m_state(seed) {}
  uint64_t next() {
    uint64_t z = (m_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  // Uniform in [lo, hi]; the modulo bias (< 2^-40 here) does not matter for test scenes.
  int64_t range(int64_t lo, int64_t hi) { return lo + static_cast<int64_t>(next() % static_cast<uint64_t>(hi - lo + 1)); }
  double unit() { return static_cast<double>(next() >> 11) * 0x1p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  bool chance(double p) { return unit() < p; }

 private:
  uint64_t m_state;
};

struct P {
  int64_t x, y;
};

int64_t orient(P a, P b, P c) { return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x); }

bool in_range(P p) { return p.x >= kCoordMin && p.x <= kCoordMax && p.y >= kCoordMin && p.y <= kCoordMax; }

P rounded(double x, double y) { return {std::llround(x), std::llround(y)}; }

using Tri = std::array<uint32_t, 3>;

// Exact separating-axis test for two non-degenerate triangles: their interiors are disjoint
// iff some edge line of one has all of the other's vertices on its closed outer side.
// Coordinates are below 2^17 in magnitude, so every product fits int64.
bool interiors_overlap(const std::array<P, 3>& a, const std::array<P, 3>& b) {
  auto separated_by_edges_of = [](const std::array<P, 3>& s, const std::array<P, 3>& t) {
    const int64_t sign = orient(s[0], s[1], s[2]) > 0 ? 1 : -1;
    for (int e = 0; e < 3; ++e) {
      bool all_out = true;
      for (const P& v : t) all_out = all_out && sign * orient(s[e], s[(e + 1) % 3], v) <= 0;
      if (all_out) return true;
    }
    return false;
  };
  return !separated_by_edges_of(a, b) && !separated_by_edges_of(b, a);
}

// One generated object: a single triangle or a mesh sharing vertices, at one depth slot.
struct Object {
  std::vector<P> points;
  std::vector<uint32_t> z;
  std::vector<Tri> tris;
  bool tilted = false;
  size_t draw = 0;

  std::array<P, 3> corners(const Tri& t) const { return {points[t[0]], points[t[1]], points[t[2]]}; }
  bool all_in_range() const { return std::all_of(points.begin(), points.end(), in_range); }
  // Every triangle non-degenerate with one orientation sign, and no two overlapping: a
  // valid mesh at one depth, whose interior edges are shared and change no area.
  bool valid_mesh() const {
    int64_t first = 0;
    for (const Tri& t : tris) {
      const int64_t o = orient(points[t[0]], points[t[1]], points[t[2]]);
      if (o == 0 || (first != 0 && (o > 0) != (first > 0))) return false;
      if (first == 0) first = o;
    }
    for (size_t i = 0; i < tris.size(); ++i)
      for (size_t j = i + 1; j < tris.size(); ++j)
        if (interiors_overlap(corners(tris[i]), corners(tris[j]))) return false;
    return all_in_range();
  }
  // Front-facing = orient2d < 0 in y-down window coordinates (counter-clockwise in NDC).
  void face(bool back) {
    for (Tri& t : tris) {
      const int64_t o = orient(points[t[0]], points[t[1]], points[t[2]]);
      if (o != 0 && (o > 0) != back) std::swap(t[1], t[2]);
    }
  }
};

double px(double pixels) { return pixels * double(kSubpixel); }

P random_point(Rng& rng) { return {rng.range(kCoordMin, kCoordMax), rng.range(kCoordMin, kCoordMax)}; }

Object single(std::array<P, 3> v) {
  Object o;
  o.points.assign(v.begin(), v.end());
  o.tris.push_back({0, 1, 2});
  return o;
}

bool make_normal(Rng& rng, Object& out) {
  const P c = random_point(rng);
  const double s = px(2.0 * std::pow(48.0, rng.unit()));  // 2..96 pixels, log-uniform
  std::array<P, 3> v;
  for (P& p : v) p = rounded(double(c.x) + rng.uniform(-s, s), double(c.y) + rng.uniform(-s, s));
  out = single(v);
  return out.all_in_range() && orient(v[0], v[1], v[2]) != 0;
}

// About half the viewport: three jittered corners of the coordinate range. No triangle
// inside that range can cover much more.
bool make_huge(Rng& rng, Object& out) {
  const std::array<P, 4> box = {{{kCoordMin, kCoordMin}, {kCoordMax, kCoordMin}, {kCoordMax, kCoordMax}, {kCoordMin, kCoordMax}}};
  const int64_t skip = rng.range(0, 3);
  std::array<P, 3> v;
  for (int k = 0, n = 0; k < 4; ++k) {
    if (k == skip) continue;
    const int64_t jx = rng.range(0, 3 * kSubpixel), jy = rng.range(0, 3 * kSubpixel);
    v[size_t(n++)] = {box[size_t(k)].x == kCoordMin ? box[size_t(k)].x + jx : box[size_t(k)].x - jx,
                      box[size_t(k)].y == kCoordMin ? box[size_t(k)].y + jy : box[size_t(k)].y - jy};
  }
  out = single(v);
  return out.all_in_range() && orient(v[0], v[1], v[2]) != 0;
}

// 32..256 pixels long, its third vertex 1..32 sub-pixel units off the long edge.
bool make_sliver(Rng& rng, Object& out) {
  const P a = random_point(rng);
  const double len = px(rng.uniform(32.0, 256.0)), phi = rng.uniform(0.0, 2.0 * std::numbers::pi);
  const double dx = std::cos(phi), dy = std::sin(phi);
  const P b = rounded(double(a.x) + len * dx, double(a.y) + len * dy);
  const double t = rng.uniform(0.05, 0.95), w = double(rng.range(1, 32)) * (rng.chance(0.5) ? 1.0 : -1.0);
  const P c = rounded(double(a.x) + t * double(b.x - a.x) - w * dy, double(a.y) + t * double(b.y - a.y) + w * dx);
  out = single({a, b, c});
  return out.all_in_range() && orient(a, b, c) != 0;
}

// Zero area: three collinear vertices, or a repeated one.
bool make_degenerate(Rng& rng, Object& out) {
  const P a = random_point(rng);
  const P g = {rng.range(-32 * kSubpixel, 32 * kSubpixel), rng.range(-32 * kSubpixel, 32 * kSubpixel)};
  const P b = {a.x + g.x, a.y + g.y};
  const int64_t m = std::array<int64_t, 4>{-1, 2, 3, 1}[size_t(rng.range(0, 3))];
  const P c = {a.x + m * g.x, a.y + m * g.y};
  out = single({a, b, c});
  return out.all_in_range();
}

// A fan of k triangles around a centre, a full disc (k >= 3) or an open sector; each
// angular step stays within [0.35, π - 0.35] rad so that rounding cannot fold it.
bool make_fan(Rng& rng, uint32_t k, bool huge, Object& out) {
  out = Object{};
  const P c = huge ? P{128 * kSubpixel + rng.range(-2 * kSubpixel, 2 * kSubpixel), 128 * kSubpixel + rng.range(-2 * kSubpixel, 2 * kSubpixel)}
                   : random_point(rng);
  const bool full = k >= 3 && (huge || rng.chance(0.3));
  std::vector<double> steps(k);
  double sum = 0;
  for (double& s : steps) sum += (s = rng.uniform(1.0, 2.0));
  const double total = full ? 2.0 * std::numbers::pi : std::min(double(k) * rng.uniform(0.5, 1.6), 2.0 * std::numbers::pi - 0.5);
  for (double& s : steps) s *= total / sum;
  if (std::any_of(steps.begin(), steps.end(), [](double s) { return s < 0.35 || s > std::numbers::pi - 0.35; }))
    return false;
  const size_t rim = full ? k : k + 1;
  out.points.push_back(c);
  double angle = rng.uniform(0.0, 2.0 * std::numbers::pi);
  for (size_t i = 0; i < rim; ++i) {
    const double r = huge ? px(rng.uniform(120.0, 129.0)) : px(6.0 * std::pow(12.0, rng.unit()));
    out.points.push_back(rounded(double(c.x) + r * std::cos(angle), double(c.y) + r * std::sin(angle)));
    angle += steps[i % k];
  }
  for (uint32_t i = 0; i < k; ++i) out.tris.push_back({0, 1 + i, 1 + (i + 1) % uint32_t(rim)});
  return out.valid_mesh();
}

// A strip of q quads, two triangles each sharing the quad's diagonal and the rungs
// between quads. Huge: one quad over the whole coordinate range (hides what is behind).
bool make_strip(Rng& rng, uint32_t q, bool huge, Object& out) {
  out = Object{};
  if (huge) {
    auto j = [&] { return rng.range(0, 3 * kSubpixel); };
    out.points = {{kCoordMin + j(), kCoordMin + j()}, {kCoordMin + j(), kCoordMax - j()},
                  {kCoordMax - j(), kCoordMin + j()}, {kCoordMax - j(), kCoordMax - j()}};
  } else {
    const P o = random_point(rng);
    const double phi = rng.uniform(0.0, 2.0 * std::numbers::pi);
    const double dx = std::cos(phi), dy = std::sin(phi);
    const double len = px(rng.uniform(6.0, 64.0)), half = px(rng.uniform(4.0, 40.0));
    for (uint32_t i = 0; i <= q; ++i) {
      for (double side : {1.0, -1.0}) {
        const double along = double(i) * len + (i == 0 ? 0.0 : rng.uniform(-0.25, 0.25) * len);
        out.points.push_back(rounded(double(o.x) + along * dx - side * half * dy, double(o.y) + along * dy + side * half * dx));
      }
    }
  }
  // points: a_i = 2i, b_i = 2i + 1.
  for (uint32_t i = 0; i < q; ++i) {
    out.tris.push_back({2 * i, 2 * i + 1, 2 * i + 2});
    out.tris.push_back({2 * i + 2, 2 * i + 1, 2 * i + 3});
  }
  return out.valid_mesh();
}

template <class Make>
Object retry(Make make) {
  Object o;
  for (int t = 0; t < kMaxTries; ++t)
    if (make(o)) return o;
  throw std::logic_error("random_scene: could not place an object");
}

}  // namespace

float clip_x_for(int64_t window_x) {
  if (window_x < kCoordMin || window_x > kCoordMax)
    throw std::logic_error("clip_x_for: " + std::to_string(window_x) + " outside the coordinate range");
  // (X - 32768) / 32768: |numerator| < 2^24, a power-of-two divisor: exact in float.
  const auto x = static_cast<float>(static_cast<double>(window_x - 32768) / 32768.0);
  if (PipelineSnap::x(x) != window_x) throw std::logic_error("clip_x_for: no exact round trip");
  return x;
}

float clip_y_for(int64_t window_y) {
  if (window_y < kCoordMin || window_y > kCoordMax)
    throw std::logic_error("clip_y_for: " + std::to_string(window_y) + " outside the coordinate range");
  const auto y = static_cast<float>(static_cast<double>(32768 - window_y) / 32768.0);
  if (PipelineSnap::y(y) != window_y) throw std::logic_error("clip_y_for: no exact round trip");
  return y;
}

float clip_z_for(uint32_t window_z) {
  // One depth step is 2/(2^24 - 1) in z, at least twice the float spacing below |z| = 1,
  // so a float a few ulps from 2Z/(2^24 - 1) - 1 rounds to Z; search outward from it.
  const auto guess = static_cast<float>(2.0 * double(window_z) / double(kDepthMax) - 1.0);
  float up = guess, down = guess;
  for (int k = 0; k < 8; ++k) {
    if (PipelineSnap::z(up) == window_z) return up;
    if (PipelineSnap::z(down) == window_z) return down;
    up = std::nextafter(up, 2.0f);
    down = std::nextafter(down, -2.0f);
  }
  throw std::logic_error("clip_z_for: no float snaps to depth " + std::to_string(window_z));
}

RandomScene random_scene(const SceneOptions& options) {
  if (options.triangles == 0 || options.draws == 0)
    throw std::invalid_argument("random_scene: triangles and draws must be positive");
  Rng rng(options.seed);

  std::vector<Object> objects;
  for (uint32_t left = options.triangles; left > 0;) {
    const bool huge = rng.chance(options.huge_fraction);
    const bool back = rng.chance(options.back_fraction);
    Object o;
    if (options.meshes && left >= 2) {
      const auto k = static_cast<uint32_t>(std::min<int64_t>(left, rng.range(2, 6)));
      if (huge && (k == 2 || rng.chance(0.5)))
        o = retry([&](Object& x) { return make_strip(rng, 1, true, x); });
      else if (k % 2 == 0 && rng.chance(0.5))
        o = retry([&](Object& x) { return make_strip(rng, k / 2, false, x); });
      else
        o = retry([&](Object& x) { return make_fan(rng, k, huge, x); });
    } else if (rng.chance(options.degenerate_fraction)) {
      o = retry([&](Object& x) { return make_degenerate(rng, x); });
    } else if (huge) {
      o = retry([&](Object& x) { return make_huge(rng, x); });
    } else if (rng.chance(options.sliver_fraction)) {
      o = retry([&](Object& x) { return make_sliver(rng, x); });
    } else {
      o = retry([&](Object& x) { return make_normal(rng, x); });
    }
    // Meshes stay at one depth; a single triangle may lie on a tilted plane.
    o.tilted = o.tris.size() == 1 && rng.chance(options.tilted_fraction);
    o.face(back);
    left -= static_cast<uint32_t>(o.tris.size());
    objects.push_back(std::move(o));
  }

  // Submission order and depth order are independent shuffles. Each object owns a depth
  // slot disjoint from every other's: no two objects can interpenetrate or tie, while a
  // mesh's triangles share one depth and never overlap each other.
  for (size_t i = objects.size(); i > 1; --i) std::swap(objects[i - 1], objects[size_t(rng.range(0, int64_t(i) - 1))]);
  std::vector<uint32_t> slot(objects.size());
  for (size_t i = 0; i < slot.size(); ++i) slot[i] = uint32_t(i);
  for (size_t i = slot.size(); i > 1; --i) std::swap(slot[i - 1], slot[size_t(rng.range(0, int64_t(i) - 1))]);
  const uint32_t width = (kDepthHi - kDepthLo) / uint32_t(objects.size());
  for (size_t i = 0; i < objects.size(); ++i) {
    Object& o = objects[i];
    o.draw = i % options.draws;
    const int64_t lo = int64_t(kDepthLo) + int64_t(slot[i]) * width, hi = lo + width - 1;
    const auto constant = static_cast<uint32_t>(rng.range(lo, hi));
    for (size_t v = 0; v < o.points.size(); ++v) o.z.push_back(o.tilted ? static_cast<uint32_t>(rng.range(lo, hi)) : constant);
  }

  RandomScene scene;
  trace::Frame& f = scene.frame;
  f.width = f.height = kSceneSize;
  f.depth_near = 0.0f;
  f.depth_far = 1.0f;
  f.subpixel_bits = 8;
  f.samples = trace::standard_samples(1, 8);
  f.draws.resize(options.draws);
  scene.window.resize(options.draws);
  int32_t id = 0;
  for (uint32_t d = 0; d < options.draws; ++d) {
    trace::Draw& draw = f.draws[d];
    draw.name = "random_" + std::to_string(d);
    for (const Object& o : objects) {
      if (o.draw != d) continue;
      const auto base = static_cast<uint32_t>(draw.vertices.size());
      for (size_t v = 0; v < o.points.size(); ++v) {
        draw.vertices.push_back({clip_x_for(o.points[v].x), clip_y_for(o.points[v].y), clip_z_for(o.z[v]), 1.0f});
        scene.window[d].push_back({o.points[v].x, o.points[v].y, o.z[v]});
      }
      for (const Tri& t : o.tris) {
        for (uint32_t k : t) draw.indices.push_back(base + k);
        const P a = o.points[t[0]], b = o.points[t[1]], c = o.points[t[2]];
        if (orient(a, b, c) < 0) {
          const auto [zmin, zmax] = std::minmax({o.z[t[0]], o.z[t[1]], o.z[t[2]]});
          scene.triangles.push_back({{a.x, b.x, c.x}, {a.y, b.y, c.y}, zmin, zmax, id});
        }
        ++id;
      }
    }
  }
  return scene;
}

}  // namespace tilevis::oracle
