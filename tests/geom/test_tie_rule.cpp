#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "geom/clip.h"
#include "geom/polygon.h"
#include "geom/predicates.h"
#include "oracle.h"

namespace tilevis::geom::test {
namespace {

// D3D11 §3.5.2 (top-left rule) with screen y downward.
TEST(TopLeftRule, D3DCases) {
  // Triangle with a horizontal top edge y = 0 and a horizontal... right triangle
  // (0,0) (8,0) (0,8): top edge y = 0, left edge x = 0, hypotenuse on the right.
  const TriangleEdges t = TriangleEdges::from(Point{0, 0}, Point{8, 0}, Point{0, 8});
  EXPECT_TRUE(t.covers({4, 0}));   // on the top edge
  EXPECT_TRUE(t.covers({0, 4}));   // on the left edge
  EXPECT_FALSE(t.covers({4, 4}));  // on the hypotenuse (a right edge)
  EXPECT_TRUE(t.covers({0, 0}));   // top-left corner: on two owned edges
  EXPECT_FALSE(t.covers({8, 0}));  // on the top edge and the right edge
  EXPECT_FALSE(t.covers({0, 8}));  // on the left edge and the right edge
  EXPECT_TRUE(t.covers({3, 4}));   // strictly inside
  // Its mirror (0,8) (8,8) (8,0): bottom edge y = 8 and right edge x = 8 are not owned.
  const TriangleEdges u = TriangleEdges::from(Point{0, 8}, Point{8, 8}, Point{8, 0});
  EXPECT_FALSE(u.covers({4, 8}));
  EXPECT_FALSE(u.covers({8, 4}));
  EXPECT_TRUE(u.covers({4, 4}));  // hypotenuse is a left edge here
  // Winding does not matter.
  const TriangleEdges tr = TriangleEdges::from(Point{0, 0}, Point{0, 8}, Point{8, 0});
  for (int32_t y = -1; y <= 9; ++y)
    for (int32_t x = -1; x <= 9; ++x) EXPECT_EQ(t.covers({x, y}), tr.covers({x, y}));
}

// A fan of triangles around a centre sitting exactly on a sample: every sample in the
// fan's disc, the centre included, is covered exactly once, for either winding of each.
TEST(TopLeftRule, FanAroundASampleCoversEachSampleOnce) {
  std::mt19937_64 rng(111);
  for (int it = 0; it < 300; ++it) {
    const Point c{128 + static_cast<int32_t>(rng() % 5) * 256, 128};
    const int n = 3 + static_cast<int>(rng() % 10);
    std::vector<double> ang;
    for (int i = 0; i < n; ++i) ang.push_back(std::uniform_real_distribution<double>(0, 2 * std::numbers::pi)(rng));
    std::sort(ang.begin(), ang.end());
    std::vector<Point> ring;
    for (double a : ang) {
      const double rad = 20 + static_cast<double>(rng() % 40);
      ring.push_back({c.x + static_cast<int32_t>(std::lround(rad * std::cos(a))), c.y + static_cast<int32_t>(std::lround(rad * std::sin(a)))});
    }
    // Include axis-aligned spokes often: samples on horizontal/vertical edges.
    if (it % 2 == 0) ring[0] = {c.x + 30, c.y};
    std::vector<TriangleEdges> fan;
    bool complete = true;
    for (int i = 0; i < n; ++i) {
      const Point p = ring[i], q = ring[(i + 1) % n];
      const int64_t o = orient2d(c, p, q);
      if (o <= 0) complete = false;  // wedge of >= 180 degrees or degenerate: not a fan
      fan.push_back((rng() & 1) ? TriangleEdges::from(c, p, q) : TriangleEdges::from(q, c, p));
    }
    if (!complete) continue;
    for (int32_t y = c.y - 70; y <= c.y + 70; ++y)
      for (int32_t x = c.x - 70; x <= c.x + 70; ++x) {
        int cnt = 0;
        for (const auto& t : fan) cnt += t.covers({x, y});
        // Inside the fan polygon (the ring), tie-ruled like any polygon.
        const auto ringpoly = ConvexPolygon::from_convex_points(ring);
        if (ringpoly) {
          ASSERT_EQ(cnt, int{covers(*ringpoly, {x, y})}) << x << "," << y;
        } else {
          ASSERT_LE(cnt, 1);
        }
        if (x == c.x && y == c.y) {
          ASSERT_EQ(cnt, 1);
        }
      }
  }
}

// A jittered triangulated grid (shared edges in both diagonal directions, vertices on
// samples, axis-aligned edges): every sample of the mesh's interior is covered once.
TEST(TopLeftRule, SharedEdgesOfAMeshCoverEachSampleOnce) {
  std::mt19937_64 rng(112);
  for (int it = 0; it < 20; ++it) {
    const int n = 6, step = 24, jit = (it % 3 == 0) ? 0 : 5;
    std::vector<Point> v((n + 1) * (n + 1));
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const bool border = i == 0 || j == 0 || i == n || j == n;
        const int32_t dx = border ? 0 : static_cast<int32_t>(rng() % (2 * jit + 1)) - jit;
        const int32_t dy = border ? 0 : static_cast<int32_t>(rng() % (2 * jit + 1)) - jit;
        v[j * (n + 1) + i] = {i * step + dx, j * step + dy};
      }
    std::vector<TriangleEdges> tris;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Point a = v[j * (n + 1) + i], b = v[j * (n + 1) + i + 1];
        const Point c = v[(j + 1) * (n + 1) + i + 1], d = v[(j + 1) * (n + 1) + i];
        if (rng() & 1) {
          tris.push_back(TriangleEdges::from(a, b, c));
          tris.push_back(TriangleEdges::from(a, c, d));
        } else {
          tris.push_back(TriangleEdges::from(a, b, d));
          tris.push_back(TriangleEdges::from(b, c, d));
        }
      }
    const ConvexPolygon hull = ConvexPolygon::from_rect({0, 0, n * step, n * step});
    for (int32_t y = -2; y <= n * step + 2; ++y)
      for (int32_t x = -2; x <= n * step + 2; ++x) {
        int cnt = 0;
        for (const auto& t : tris) cnt += t.covers({x, y});
        ASSERT_EQ(cnt, int{covers(hull, {x, y})}) << x << "," << y;
      }
  }
}

// Pieces from clipping a triangle by silhouette lines and by tile rectangles: together with
// the tie rule on clip lines, the pieces of all tiles cover each sample of the triangle once.
TEST(TopLeftRule, TilePiecesOfATriangleCoverEachSampleOnce) {
  std::mt19937_64 rng(113);
  for (int it = 0; it < 200; ++it) {
    const Point a = random_point(rng, -10, 90), b = random_point(rng, -10, 90), c = random_point(rng, -10, 90);
    const Triangle t{{Vertex{a.x, a.y, 0}, Vertex{b.x, b.y, 0}, Vertex{c.x, c.y, 0}}};
    const TriangleEdges te = TriangleEdges::from(t);
    std::vector<ConvexPolygon> pieces;
    for (int32_t ty = -1; ty < 4; ++ty)
      for (int32_t tx = -1; tx < 4; ++tx) {
        const Rect r{tx * 25, ty * 25, tx * 25 + 25, ty * 25 + 25};
        ConvexPolygon p = triangle_in_rect(t, r);
        if (p.empty()) continue;
        const Line sil = Line::through(random_point(rng, -10, 90), random_point(rng, -10, 90));
        if (sil.a == 0 && sil.b == 0) {
          pieces.push_back(std::move(p));
          continue;
        }
        SplitResult s = split(p, sil);
        if (!s.inside.empty()) pieces.push_back(std::move(s.inside));
        if (!s.outside.empty()) pieces.push_back(std::move(s.outside));
      }
    for (int32_t y = -12; y <= 92; ++y)
      for (int32_t x = -12; x <= 92; ++x) {
        int cnt = 0;
        for (const auto& p : pieces) cnt += covers(p, {x, y});
        ASSERT_EQ(cnt, int{te.covers({x, y})}) << x << "," << y;
      }
  }
}

}  // namespace
}  // namespace tilevis::geom::test
