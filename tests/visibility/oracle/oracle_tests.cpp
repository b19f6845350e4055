// Checks of the CGAL visible-area oracle and of the random-scene generator, so that the
// golden pipeline's own tests can trust both: hand-computed cases, an exact area identity
// against an independent union computation, a sampling estimate with a derived error
// bound, and the generator's exact-snap claim.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <boost/multiprecision/gmp.hpp>

#include "oracle.h"
#include "random_scenes.h"
#include "tilevis/trace.h"

namespace tilevis::oracle {
namespace {

using Q = boost::multiprecision::mpq_rational;
__extension__ typedef __int128 Int128;  // GCC/Clang builtin; -Wpedantic wants the marker

Triangle tri(int64_t x0, int64_t y0, int64_t x1, int64_t y1, int64_t x2, int64_t y2, uint32_t z_min, uint32_t z_max,
             int32_t id = 0) {
  return {{x0, x1, x2}, {y0, y1, y2}, z_min, z_max, id};
}

Q rational(const Area& a) { return Q(a.num + "/" + a.den); }

void expect_area(const Area& a, const std::string& num, const std::string& den) {
  EXPECT_EQ(a.num, num);
  EXPECT_EQ(a.den, den);
  EXPECT_DOUBLE_EQ(a.value, std::stod(num) / std::stod(den));
}

constexpr int64_t kView = int64_t{kSceneSize} * kSubpixel;  // viewport side in sub-pixel units

// ---------------------------------------------------------------------------------------
// Hand-computed cases.

TEST(OracleHand, SingleTriangleEitherOrientation) {
  auto cw = visible_areas({tri(0, 0, 10, 0, 0, 10, 5, 5)}, 0, 0, 100, 100);
  auto ccw = visible_areas({tri(0, 0, 0, 10, 10, 0, 5, 5)}, 0, 0, 100, 100);
  ASSERT_EQ(cw.size(), 1u);
  ASSERT_EQ(ccw.size(), 1u);
  expect_area(cw[0], "50", "1");
  expect_area(ccw[0], "50", "1");
}

TEST(OracleHand, HalfUnitAreaIsAnExactRational) {
  auto a = visible_areas({tri(0, 0, 1, 0, 0, 1, 1, 1)}, 0, 0, 4, 4);
  expect_area(a[0], "1", "2");
}

TEST(OracleHand, NearerTriangleHidesTheOverlap) {
  // A: x,y >= 0, x + y <= 20 (area 200). B: x >= 10, y >= 0, x + y <= 30 (area 200).
  // A ∩ B: x >= 10, y >= 0, x + y <= 20: the triangle (10,0),(20,0),(10,10), area 50.
  const Triangle a = tri(0, 0, 20, 0, 0, 20, 5, 5, 0);
  const Triangle b_behind = tri(10, 0, 30, 0, 10, 20, 10, 12, 1);
  auto r = visible_areas({a, b_behind}, -1000, -1000, 1000, 1000);
  expect_area(r[0], "200", "1");
  expect_area(r[1], "150", "1");
  // Depths swapped: now A loses the overlap.
  const Triangle a_behind = tri(0, 0, 20, 0, 0, 20, 20, 30, 0);
  r = visible_areas({a_behind, b_behind}, -1000, -1000, 1000, 1000);
  expect_area(r[0], "150", "1");
  expect_area(r[1], "200", "1");
}

TEST(OracleHand, OverlapWithNonDyadicCorner) {
  // F: x >= 0, y <= 6, y >= 2x (area 9), in front. B: x,y >= 0, x + y <= 4 (area 8).
  // B ∩ F = (0,0), (0,4), (4/3, 8/3): area 8/3, so B keeps 8 - 8/3 = 16/3.
  auto r = visible_areas({tri(0, 0, 3, 6, 0, 6, 1, 1), tri(0, 0, 4, 0, 0, 4, 2, 2)}, -10, -10, 10, 10);
  expect_area(r[0], "9", "1");
  expect_area(r[1], "16", "3");
}

TEST(OracleHand, FullyHiddenTriangleHasZeroArea) {
  auto r = visible_areas({tri(10, 10, 20, 10, 10, 20, 9, 9), tri(0, 0, 100, 0, 0, 100, 1, 3)}, 0, 0, 100, 100);
  expect_area(r[0], "0", "1");
  expect_area(r[1], "5000", "1");
}

TEST(OracleHand, OnlyThePartInsideTheViewportCounts) {
  // Viewport [0,100]^2. T1 pokes out left: x >= -10, y >= 0, x + y <= 10; inside, the
  // triangle (0,0),(10,0),(0,10): 50. T2 pokes out below: legs 20 at (20,90), area 200,
  // less the corner y > 100, the triangle (20,100),(30,100),(20,110): 150. T3 is wholly
  // outside. T4, behind all, covers the viewport: 10000 - 50 - 150.
  auto r = visible_areas({tri(-10, 0, 10, 0, -10, 20, 1, 1), tri(20, 90, 40, 90, 20, 110, 2, 2),
                          tri(200, 200, 300, 200, 200, 300, 3, 3), tri(-1000, -1000, 3000, -1000, -1000, 3000, 100, 100)},
                         0, 0, 100, 100);
  expect_area(r[0], "50", "1");
  expect_area(r[1], "150", "1");
  expect_area(r[2], "0", "1");
  expect_area(r[3], "9800", "1");
}

TEST(OracleHand, SharedEdgeFanKeepsItsAreaAndHidesWhatIsBehind) {
  // Four triangles around (50,50) tiling the square [40,60]^2, one depth, mixed
  // orientations: each 100, and the triangle behind loses exactly the square, 400.
  std::vector<Triangle> s = {tri(50, 50, 40, 40, 60, 40, 10, 10, 0), tri(50, 50, 60, 60, 60, 40, 10, 10, 1),
                             tri(50, 50, 60, 60, 40, 60, 10, 10, 2), tri(50, 50, 40, 40, 40, 60, 10, 10, 3),
                             tri(0, 0, 200, 0, 0, 200, 20, 20, 4)};
  auto r = visible_areas(s, 0, 0, 1000, 1000);
  for (int i = 0; i < 4; ++i) expect_area(r[size_t(i)], "100", "1");
  expect_area(r[4], "19600", "1");
}

TEST(OracleHand, ZeroAreaTrianglesNeverOcclude) {
  auto r = visible_areas({tri(0, 0, 50, 50, 100, 100, 1, 1), tri(30, 30, 30, 30, 70, 0, 1, 1), tri(0, 0, 100, 0, 0, 100, 5, 5)},
                         0, 0, 100, 100);
  expect_area(r[0], "0", "1");
  expect_area(r[1], "0", "1");
  expect_area(r[2], "5000", "1");
}

TEST(OracleHand, RejectsWhatHasNoDepthOrder) {
  // Overlapping interiors with intersecting depth ranges.
  EXPECT_THROW(visible_areas({tri(0, 0, 20, 0, 0, 20, 5, 10), tri(10, 0, 30, 0, 10, 20, 8, 12)}, 0, 0, 100, 100),
               std::invalid_argument);
  // Identical triangles at one depth.
  EXPECT_THROW(visible_areas({tri(0, 0, 20, 0, 0, 20, 5, 5), tri(0, 20, 20, 0, 0, 0, 5, 5)}, 0, 0, 100, 100),
               std::invalid_argument);
  EXPECT_THROW(visible_areas({tri(0, 0, 20, 0, 0, 20, 6, 5)}, 0, 0, 100, 100), std::invalid_argument);
  EXPECT_THROW(visible_areas({tri(0, 0, 20, 0, 0, 20, 5, 5)}, 0, 0, 0, 100), std::invalid_argument);
  EXPECT_THROW(visible_areas({tri(0, 0, int64_t{1} << 54, 0, 0, 20, 5, 5)}, 0, 0, 10, 100), std::invalid_argument);
  // Touching along an edge or at a corner at one depth is fine; so is a zero-area
  // triangle inside another at the same depth.
  EXPECT_NO_THROW(visible_areas({tri(0, 0, 20, 0, 0, 20, 5, 5), tri(20, 0, 20, 20, 0, 20, 5, 5),
                                 tri(20, 20, 40, 20, 20, 40, 5, 5), tri(1, 1, 2, 2, 3, 3, 5, 5)},
                                0, 0, 100, 100));
}

// ---------------------------------------------------------------------------------------
// Exact identity: Σ visible areas = area of the union of all projections inside the
// viewport, the union computed here independently of CGAL by vertical slabs. Between
// consecutive event abscissae (vertices, edge crossings, crossings of the viewport's
// horizontal sides) no boundary crosses another, so the covered length is linear in x
// and the midpoint rule is exact.

struct Seg {
  int64_t ax, ay, bx, by;
};

Int128 orient128(int64_t ax, int64_t ay, int64_t bx, int64_t by, int64_t cx, int64_t cy) {
  return Int128(bx - ax) * (cy - ay) - Int128(by - ay) * (cx - ax);
}

Q union_area(const std::vector<Triangle>& tris, int64_t x0, int64_t y0, int64_t x1, int64_t y1) {
  std::vector<const Triangle*> live;
  std::vector<Seg> segs;
  for (const Triangle& t : tris) {
    if (orient128(t.x[0], t.y[0], t.x[1], t.y[1], t.x[2], t.y[2]) == 0) continue;
    live.push_back(&t);
    for (int k = 0; k < 3; ++k) segs.push_back({t.x[k], t.y[k], t.x[(k + 1) % 3], t.y[(k + 1) % 3]});
  }
  std::vector<Q> xs = {Q(x0), Q(x1)};
  for (const Seg& s : segs) {
    xs.emplace_back(s.ax);
    for (int64_t yc : {y0, y1})
      if ((s.ay - yc) * (s.by - yc) < 0) xs.push_back(Q(s.ax) + Q(yc - s.ay) * Q(s.bx - s.ax) / Q(s.by - s.ay));
  }
  for (size_t i = 0; i < segs.size(); ++i)
    for (size_t j = i + 1; j < segs.size(); ++j) {
      const Seg &p = segs[i], &q = segs[j];
      const Int128 d = Int128(p.bx - p.ax) * (q.by - q.ay) - Int128(p.by - p.ay) * (q.bx - q.ax);
      if (d == 0) continue;  // parallel: any shared point is an endpoint, already an event
      const Int128 o1 = orient128(p.ax, p.ay, p.bx, p.by, q.ax, q.ay), o2 = orient128(p.ax, p.ay, p.bx, p.by, q.bx, q.by);
      const Int128 o3 = orient128(q.ax, q.ay, q.bx, q.by, p.ax, p.ay), o4 = orient128(q.ax, q.ay, q.bx, q.by, p.bx, p.by);
      if ((o1 > 0 && o2 > 0) || (o1 < 0 && o2 < 0) || (o3 > 0 && o4 > 0) || (o3 < 0 && o4 < 0)) continue;
      // p.a + t (p.b - p.a) with t = cross(q.a - p.a, q.b - q.a) / cross(p.b - p.a, q.b - q.a).
      const Q t = Q(static_cast<int64_t>(o3)) / Q(static_cast<int64_t>(d));
      xs.push_back(Q(p.ax) + t * Q(p.bx - p.ax));
    }
  std::sort(xs.begin(), xs.end());
  xs.erase(std::unique(xs.begin(), xs.end()), xs.end());

  Q total = 0;
  std::vector<std::pair<Q, Q>> spans;
  for (size_t i = 0; i + 1 < xs.size(); ++i) {
    if (xs[i] < x0 || xs[i + 1] > x1) continue;
    const Q xm = (xs[i] + xs[i + 1]) / 2;
    spans.clear();
    for (const Triangle* t : live) {
      std::vector<Q> ys;
      for (int k = 0; k < 3; ++k) {
        const int64_t ax = t->x[k], ay = t->y[k], bx = t->x[(k + 1) % 3], by = t->y[(k + 1) % 3];
        if (ax == bx || xm <= std::min(ax, bx) || xm >= std::max(ax, bx)) continue;
        ys.push_back(Q(ay) + (xm - ax) * Q(by - ay) / Q(bx - ax));
      }
      if (ys.size() < 2) continue;
      auto [lo, hi] = std::minmax_element(ys.begin(), ys.end());
      Q a = std::max(*lo, Q(y0)), b = std::min(*hi, Q(y1));
      if (a < b) spans.emplace_back(a, b);
    }
    std::sort(spans.begin(), spans.end());
    Q len = 0, end = Q(y0);
    for (const auto& [a, b] : spans) {
      if (b <= end) continue;
      len += b - std::max(a, end);
      end = b;
    }
    total += (xs[i + 1] - xs[i]) * len;
  }
  return total;
}

std::vector<SceneOptions> option_mixes() {
  std::vector<SceneOptions> mixes(4);
  mixes[0].triangles = 16;
  mixes[1].triangles = 16;
  mixes[1].meshes = true;
  mixes[1].huge_fraction = 0.15;
  mixes[2].triangles = 14;
  mixes[2].huge_fraction = 0.3;
  mixes[2].sliver_fraction = 0.4;
  mixes[3].triangles = 18;
  mixes[3].draws = 3;
  mixes[3].back_fraction = 0.2;
  mixes[3].degenerate_fraction = 0.15;
  return mixes;
}

TEST(OracleUnion, UnionSlabsAgreeWithHandCase) {
  // The checker itself on the fan case: square 400 plus the back triangle's 19600.
  std::vector<Triangle> s = {tri(50, 50, 40, 40, 60, 40, 10, 10), tri(50, 50, 60, 60, 60, 40, 10, 10),
                             tri(0, 0, 200, 0, 0, 200, 20, 20), tri(150, 150, 300, 150, 150, 300, 1, 1)};
  // The last triangle (x, y >= 150: x + y >= 300) misses the back one (x + y <= 200) and
  // adds its 150²/2 = 11250; the fan lies inside the back triangle and adds nothing.
  EXPECT_EQ(union_area(s, 0, 0, 1000, 1000), Q(20000 + 11250));
  // Clipped to [0,100]^2: the back triangle's part, x + y <= 200, is the whole square.
  EXPECT_EQ(union_area(s, 0, 0, 100, 100), Q(10000));
}

TEST(OracleUnion, SumOfVisibleAreasEqualsUnionAreaExactly) {
  int scenes = 0;
  for (SceneOptions o : option_mixes())
    for (uint64_t seed = 1; seed <= 4; ++seed) {
      o.seed = seed * 7919 + o.triangles;
      const RandomScene scene = random_scene(o);
      const auto areas = visible_areas(scene.triangles, 0, 0, kView, kView);
      ASSERT_EQ(areas.size(), scene.triangles.size());
      Q sum = 0;
      for (const Area& a : areas) {
        const Q q = rational(a);
        EXPECT_GE(q, 0);
        EXPECT_NEAR(a.value, q.convert_to<double>(), 1e-12 * std::max(1.0, a.value));
        sum += q;
      }
      EXPECT_EQ(sum, union_area(scene.triangles, 0, 0, kView, kView)) << "seed " << o.seed;
      ++scenes;
    }
  EXPECT_EQ(scenes, 16);
}

// ---------------------------------------------------------------------------------------
// Sampling estimate. Cells of side h tile the viewport; the visible triangle at each cell
// centre is the first of the depth-sorted triangles containing it (closed). A cell's
// vote is wrong only if the boundary of the triangle's visible region enters it, and that
// boundary lies on the triangle's own edges and on edges of nearer triangles (viewport
// sides fall on cell borders). A segment with extents dx, dy enters at most
// dx/h + dy/h + 3 cells, so |estimate − area| <= h² Σ (dx/h + dy/h + 3) over those edges
// clipped to the triangle's bounding box.

struct ClipBox {
  double x0, y0, x1, y1;
};

// Liang–Barsky; returns false if the segment misses the box. Double is fine: this feeds a
// tolerance, padded by a cell on each side.
bool clip_segment(double& ax, double& ay, double& bx, double& by, const ClipBox& b) {
  double t0 = 0, t1 = 1;
  const double dx = bx - ax, dy = by - ay;
  const double p[4] = {-dx, dx, -dy, dy}, q[4] = {ax - b.x0, b.x1 - ax, ay - b.y0, b.y1 - ay};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0) {
      if (q[i] < 0) return false;
      continue;
    }
    const double r = q[i] / p[i];
    if (p[i] < 0) t0 = std::max(t0, r);
    else t1 = std::min(t1, r);
  }
  if (t0 > t1) return false;
  const double nax = ax + t0 * dx, nay = ay + t0 * dy, nbx = ax + t1 * dx, nby = ay + t1 * dy;
  ax = nax, ay = nay, bx = nbx, by = nby;
  return true;
}

bool contains(const Triangle& t, int64_t px, int64_t py) {
  const Int128 o = orient128(t.x[0], t.y[0], t.x[1], t.y[1], t.x[2], t.y[2]);
  if (o == 0) return false;
  for (int k = 0; k < 3; ++k) {
    const Int128 e = orient128(t.x[k], t.y[k], t.x[(k + 1) % 3], t.y[(k + 1) % 3], px, py);
    if ((o > 0 && e < 0) || (o < 0 && e > 0)) return false;
  }
  return true;
}

TEST(OracleSampling, MatchesPointSamplingWithinTheDerivedBound) {
  constexpr int64_t h = 32;  // 1/8 pixel
  static_assert(kView % h == 0, "cells must tile the viewport");
  constexpr int64_t cells = kView / h;
  double worst_ratio = 0;
  int occluded = 0;
  for (SceneOptions o : option_mixes())
    for (uint64_t seed = 1; seed <= 2; ++seed) {
      o.seed = 1000 + seed;
      const RandomScene scene = random_scene(o);
      const auto& tris = scene.triangles;
      const auto areas = visible_areas(tris, 0, 0, kView, kView);
      std::vector<size_t> order(tris.size());
      for (size_t i = 0; i < order.size(); ++i) order[i] = i;
      std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return tris[a].z_min < tris[b].z_min; });

      std::vector<uint8_t> owned(size_t(cells * cells), 0);
      std::vector<int64_t> votes(tris.size(), 0), own_votes(tris.size(), 0);
      for (size_t i : order) {
        const Triangle& t = tris[i];
        const int64_t bx0 = std::max<int64_t>(0, *std::min_element(t.x, t.x + 3) / h - 1);
        const int64_t by0 = std::max<int64_t>(0, *std::min_element(t.y, t.y + 3) / h - 1);
        const int64_t bx1 = std::min<int64_t>(cells - 1, *std::max_element(t.x, t.x + 3) / h + 1);
        const int64_t by1 = std::min<int64_t>(cells - 1, *std::max_element(t.y, t.y + 3) / h + 1);
        for (int64_t cy = by0; cy <= by1; ++cy)
          for (int64_t cx = bx0; cx <= bx1; ++cx) {
            if (!contains(t, cx * h + h / 2, cy * h + h / 2)) continue;
            ++own_votes[i];
            uint8_t& cell = owned[size_t(cy * cells + cx)];
            if (!cell) cell = 1, ++votes[i];
          }
      }
      for (size_t r = 0; r < order.size(); ++r) {
        const size_t i = order[r];
        const Triangle& t = tris[i];
        const ClipBox box = {std::max(0.0, double(*std::min_element(t.x, t.x + 3)) - h),
                             std::max(0.0, double(*std::min_element(t.y, t.y + 3)) - h),
                             std::min(double(kView), double(*std::max_element(t.x, t.x + 3)) + h),
                             std::min(double(kView), double(*std::max_element(t.y, t.y + 3)) + h)};
        double crossed = 0;
        for (size_t s = 0; s <= r; ++s) {
          const Triangle& u = tris[order[s]];
          for (int k = 0; k < 3; ++k) {
            double ax = double(u.x[k]), ay = double(u.y[k]), bx = double(u.x[(k + 1) % 3]), by = double(u.y[(k + 1) % 3]);
            if (box.x0 < box.x1 && box.y0 < box.y1 && clip_segment(ax, ay, bx, by, box))
              crossed += std::fabs(bx - ax) / h + std::fabs(by - ay) / h + 3;
          }
        }
        const double tolerance = crossed * double(h * h);
        const double estimate = double(votes[i]) * double(h * h);
        const double err = std::fabs(estimate - areas[i].value);
        EXPECT_LE(err, tolerance) << "seed " << o.seed << " triangle " << t.id << " area " << areas[i].value;
        if (tolerance > 0) worst_ratio = std::max(worst_ratio, err / tolerance);
        // Occlusion happened here, beyond what sampling error could explain.
        if (double(own_votes[i] - votes[i]) * double(h * h) > tolerance) ++occluded;
      }
    }
  EXPECT_GT(occluded, 10) << "the random scenes should exercise occlusion";
  RecordProperty("worst_error_over_tolerance", std::to_string(worst_ratio));
  std::printf("worst |estimate - oracle| / tolerance = %.3f, clearly occluded triangles = %d\n", worst_ratio, occluded);
}

// ---------------------------------------------------------------------------------------
// The generator.

// The pipeline's viewport transform as DESIGN.md and model/visibility/setup.cpp state it,
// written out again here rather than taken from the generator.
WindowVertex pipeline_snap(const trace::Frame& f, const trace::Vec4& v) {
  const double inv_w = 1.0 / double(v.w);
  const double half_w = f.width * 0.5, half_h = f.height * 0.5, sub = double(1u << f.subpixel_bits);
  const double xw = (double(v.x) * inv_w + 1.0) * half_w;
  const double yw = (1.0 - double(v.y) * inv_w) * half_h;
  double zw = double(f.depth_near) + (double(f.depth_far) - double(f.depth_near)) * (double(v.z) * inv_w + 1.0) * 0.5;
  zw = std::clamp(zw, 0.0, 1.0);
  const double depth_scale = double((uint64_t{1} << kSceneDepthBits) - 1);
  return {static_cast<int64_t>(std::nearbyint(xw * sub)), static_cast<int64_t>(std::nearbyint(yw * sub)),
          static_cast<uint32_t>(std::nearbyint(zw * depth_scale))};
}

std::vector<SceneOptions> generator_mixes() {
  auto mixes = option_mixes();
  SceneOptions all = mixes[3];
  all.meshes = true;
  all.triangles = 40;
  all.huge_fraction = 0.2;
  mixes.push_back(all);
  return mixes;
}

TEST(RandomScenes, PipelineSnapsEveryVertexExactly) {
  size_t vertices = 0;
  for (SceneOptions o : generator_mixes())
    for (uint64_t seed = 1; seed <= 20; ++seed) {
      o.seed = seed;
      const RandomScene s = random_scene(o);
      EXPECT_EQ(s.frame.width, 256u);
      EXPECT_EQ(s.frame.height, 256u);
      EXPECT_EQ(s.frame.subpixel_bits, 8u);
      EXPECT_EQ(s.frame.samples, trace::standard_samples(1));
      ASSERT_EQ(s.window.size(), s.frame.draws.size());
      for (size_t d = 0; d < s.frame.draws.size(); ++d) {
        const trace::Draw& draw = s.frame.draws[d];
        ASSERT_EQ(s.window[d].size(), draw.vertices.size());
        for (size_t v = 0; v < draw.vertices.size(); ++v) {
          EXPECT_EQ(draw.vertices[v].w, 1.0f);
          EXPECT_EQ(pipeline_snap(s.frame, draw.vertices[v]), s.window[d][v]) << "seed " << seed << " draw " << d << " vertex " << v;
          const WindowVertex& w = s.window[d][v];
          EXPECT_TRUE(w.x >= kCoordMin && w.x <= kCoordMax && w.y >= kCoordMin && w.y <= kCoordMax);
          ++vertices;
        }
      }
      trace::Trace t;
      t.frames.push_back(s.frame);
      EXPECT_NO_THROW(trace::validate(t));
    }
  EXPECT_GT(vertices, 1000u);
}

TEST(RandomScenes, DepthSnapRoundTripsOverTheWholeRange) {
  // Every depth the generator may pick, sampled densely, plus the ends of the range.
  const trace::Frame f = random_scene(SceneOptions{}).frame;
  for (uint32_t z = 1u << 16; z < (1u << 24) - (1u << 16); z += 997) {
    const float c = clip_z_for(z);
    ASSERT_EQ(pipeline_snap(f, {0.0f, 0.0f, c, 1.0f}).z, z);
  }
  for (uint32_t z : {0u, 1u, 8388607u, 8388608u, (1u << 24) - 2}) EXPECT_EQ(pipeline_snap(f, {0.0f, 0.0f, clip_z_for(z), 1.0f}).z, z);
  EXPECT_THROW(clip_x_for(kCoordMax + 1), std::logic_error);
  EXPECT_THROW(clip_y_for(kCoordMin - 1), std::logic_error);
}

int64_t window_orient(const WindowVertex& a, const WindowVertex& b, const WindowVertex& c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

TEST(RandomScenes, OracleTrianglesAreTheFrontFacingOnesOfTheFrame) {
  for (SceneOptions o : generator_mixes())
    for (uint64_t seed = 1; seed <= 10; ++seed) {
      o.seed = seed;
      const RandomScene s = random_scene(o);
      size_t next = 0, total = 0;
      int32_t id = 0;
      for (size_t d = 0; d < s.frame.draws.size(); ++d) {
        const trace::Draw& draw = s.frame.draws[d];
        for (size_t t = 0; t < draw.triangle_count(); ++t, ++id, ++total) {
          const uint32_t* ix = &draw.indices[3 * t];
          const WindowVertex a = s.window[d][ix[0]], b = s.window[d][ix[1]], c = s.window[d][ix[2]];
          // Facing from the clip-space floats too: counter-clockwise in NDC is front.
          const trace::Vec4 &p = draw.vertices[ix[0]], &q = draw.vertices[ix[1]], &r = draw.vertices[ix[2]];
          const double ndc = (double(q.x) - p.x) * (double(r.y) - p.y) - (double(q.y) - p.y) * (double(r.x) - p.x);
          const int64_t wo = window_orient(a, b, c);
          EXPECT_EQ(ndc > 0, wo < 0);
          if (wo >= 0) continue;
          ASSERT_LT(next, s.triangles.size());
          const Triangle& ot = s.triangles[next++];
          EXPECT_EQ(ot.id, id);
          EXPECT_EQ(ot.x[0], a.x);
          EXPECT_EQ(ot.y[1], b.y);
          EXPECT_EQ(ot.x[2], c.x);
          EXPECT_EQ(ot.z_min, std::min({a.z, b.z, c.z}));
          EXPECT_EQ(ot.z_max, std::max({a.z, b.z, c.z}));
        }
      }
      EXPECT_EQ(next, s.triangles.size());
      EXPECT_EQ(total, o.triangles);
      // Depth-ordered, as the oracle requires (it throws otherwise).
      EXPECT_NO_THROW(visible_areas(s.triangles, 0, 0, kView, kView));
    }
}

TEST(RandomScenes, SameSeedSameSceneOtherSeedOtherScene) {
  SceneOptions o;
  o.meshes = true;
  o.seed = 42;
  const RandomScene a = random_scene(o), b = random_scene(o);
  EXPECT_EQ(a.frame, b.frame);
  o.seed = 43;
  EXPECT_NE(a.frame, random_scene(o).frame);
}

TEST(RandomScenes, OptionsShapeTheScene) {
  auto doubled_area = [](const Triangle& t) {
    return std::abs((t.x[1] - t.x[0]) * (t.y[2] - t.y[0]) - (t.y[1] - t.y[0]) * (t.x[2] - t.x[0]));
  };
  SceneOptions o;
  o.triangles = 30;
  // Meshes share vertices (indexed): fewer vertices than 3 per triangle.
  o.meshes = true;
  RandomScene s = random_scene(o);
  EXPECT_LT(s.frame.vertex_count(), 3 * s.frame.triangle_count());
  // All huge, no meshes: each triangle covers over 40% of the viewport.
  o = SceneOptions{};
  o.huge_fraction = 1.0;
  o.triangles = 3;
  o.seed = 5;
  s = random_scene(o);
  ASSERT_EQ(s.triangles.size(), 3u);
  for (const Triangle& t : s.triangles) EXPECT_GT(double(doubled_area(t)) / 2, 0.4 * double(kView) * double(kView));
  // Slivers: long and at most 32 units thick (doubled area <= 32 · 2 · longest edge).
  o = SceneOptions{};
  o.huge_fraction = 0;
  o.sliver_fraction = 1.0;
  o.triangles = 20;
  s = random_scene(o);
  ASSERT_EQ(s.triangles.size(), 20u);
  for (const Triangle& t : s.triangles) {
    double longest = 0;
    for (int k = 0; k < 3; ++k)
      longest = std::max(longest, std::hypot(double(t.x[(k + 1) % 3] - t.x[k]), double(t.y[(k + 1) % 3] - t.y[k])));
    EXPECT_GE(longest, 31.0 * kSubpixel);
    EXPECT_LE(double(doubled_area(t)) / longest, 33.0);
  }
  // Back-facing and degenerate triangles are emitted but not handed to the oracle.
  o = SceneOptions{};
  o.back_fraction = 1.0;
  s = random_scene(o);
  EXPECT_EQ(s.frame.triangle_count(), o.triangles);
  EXPECT_TRUE(s.triangles.empty());
  o = SceneOptions{};
  o.degenerate_fraction = 1.0;
  s = random_scene(o);
  EXPECT_EQ(s.frame.triangle_count(), o.triangles);
  EXPECT_TRUE(s.triangles.empty());
  // Across seeds some triangles poke out of the viewport, and some tilt.
  int outside = 0, tilted = 0;
  for (uint64_t seed = 1; seed <= 10; ++seed) {
    o = SceneOptions{};
    o.seed = seed;
    for (const Triangle& t : random_scene(o).triangles) {
      outside += *std::min_element(t.x, t.x + 3) < 0 || *std::max_element(t.y, t.y + 3) > kView;
      tilted += t.z_min != t.z_max;
    }
  }
  EXPECT_GT(outside, 0);
  EXPECT_GT(tilted, 0);
  // Draws: triangles spread over all of them.
  o = SceneOptions{};
  o.draws = 3;
  s = random_scene(o);
  ASSERT_EQ(s.frame.draws.size(), 3u);
  for (const auto& d : s.frame.draws) EXPECT_GT(d.triangle_count(), 0u);
  o = SceneOptions{};
  o.triangles = 0;
  EXPECT_THROW(random_scene(o), std::invalid_argument);
}

}  // namespace
}  // namespace tilevis::oracle
