#include <gtest/gtest.h>

#include <random>

#include "geom/clip.h"
#include "geom/overlap.h"
#include "oracle.h"
#include "test_cases.h"

namespace tilevis::geom::test {
namespace {

// Positive-area intersection by rational clipping.
bool oracle_triangle_rect(Point a, Point b, Point c, const Rect& r) {
  std::vector<RPoint> poly{rpoint(a), rpoint(b), rpoint(c)};
  if (orient(poly[0], poly[1], poly[2]) < 0) std::swap(poly[1], poly[2]);
  if (orient(poly[0], poly[1], poly[2]) == 0) return false;
  poly = clip_rational(poly, 1, 0, -r.x0);
  poly = clip_rational(poly, -1, 0, r.x1);
  poly = clip_rational(poly, 0, 1, -r.y0);
  poly = clip_rational(poly, 0, -1, r.y1);
  return poly.size() >= 3 && shoelace(poly) > 0;
}

// Does the closed segment ab meet the open region {f_i > 0} (f_i affine)? Parameter
// interval t in [0, 1] intersected with each open constraint.
struct Affine {
  Rational a, b, c;
};
bool oracle_segment_open_region(Point pa, Point pb, const std::vector<Affine>& fs) {
  Rational lo = -1, hi = 2;  // open bounds
  const Rational L = 0, H = 1;  // the closed segment
  bool has_lo = false, has_hi = false;
  for (const auto& f : fs) {
    const Rational fa = f.a * pa.x + f.b * pa.y + f.c, fb = f.a * pb.x + f.b * pb.y + f.c;
    const Rational d = fb - fa;  // f(t) = fa + t d > 0
    if (d == 0) {
      if (fa <= 0) return false;
      continue;
    }
    const Rational t0 = -fa / d;
    if (d > 0) {  // t > t0
      if (!has_lo || t0 > lo) lo = t0;
      has_lo = true;
    } else {      // t < t0
      if (!has_hi || t0 < hi) hi = t0;
      has_hi = true;
    }
  }
  // Need t in [L, H] with t > lo and t < hi.
  const Rational left = has_lo ? lo : Rational(-1), right = has_hi ? hi : Rational(2);
  if (!(left < right)) return false;
  return left < H && right > L;
}

std::vector<Affine> rect_region(const Rect& r) {
  return {{1, 0, -r.x0}, {-1, 0, r.x1}, {0, 1, -r.y0}, {0, -1, r.y1}};
}

TEST(TriangleOverlapsRect, MatchesOracleWithManyContacts) {
  std::mt19937_64 rng(101);
  const Rect r{0, 0, 64, 64};
  int overlaps = 0;
  for (int it = 0; it < tilevis::test::cases(60000); ++it) {
    auto p = [&] { return Point{8 * static_cast<int32_t>(rng() % 25) - 64, 8 * static_cast<int32_t>(rng() % 25) - 64}; };
    const Point a = p(), b = p(), c = p();
    const bool expect = oracle_triangle_rect(a, b, c, r);
    ASSERT_EQ(triangle_overlaps_rect(a, b, c, r), expect) << a.x << "," << a.y << " " << b.x << "," << b.y << " " << c.x << "," << c.y;
    overlaps += expect;
  }
  EXPECT_GT(overlaps, tilevis::test::cases(10000));
}

TEST(TriangleOverlapsRect, MatchesOracleFullRange) {
  std::mt19937_64 rng(102);
  for (int it = 0; it < tilevis::test::cases(30000); ++it) {
    const int32_t lim = kCoordLimit;
    const Point a = random_point(rng, -lim, lim), b = random_point(rng, -lim, lim), c = random_point(rng, -lim, lim);
    const Point q = random_point(rng, -lim, lim - 1 - (1 << 20));
    const Rect r{q.x, q.y, q.x + 1 + static_cast<int32_t>(rng() % (1 << 20)), q.y + 1 + static_cast<int32_t>(rng() % (1 << 20))};
    ASSERT_EQ(triangle_overlaps_rect(a, b, c, r), oracle_triangle_rect(a, b, c, r));
  }
}

// Binning never misses: a covered sample owned by the tile implies overlap.
TEST(TriangleOverlapsRect, NeverMissesACoveredSample) {
  std::mt19937_64 rng(103);
  const Rect r{0, 0, 32, 32};
  for (int it = 0; it < tilevis::test::cases(20000); ++it) {
    const Point a = random_point(rng, -20, 52), b = random_point(rng, -20, 52), c = random_point(rng, -20, 52);
    const TriangleEdges t = TriangleEdges::from(a, b, c);
    bool covered = false;
    for (int32_t y = r.y0; y < r.y1 && !covered; ++y)
      for (int32_t x = r.x0; x < r.x1 && !covered; ++x) covered = t.covers({x, y});
    if (covered) {
      ASSERT_TRUE(triangle_overlaps_rect(a, b, c, r));
    }
  }
}

TEST(SegmentOverlapsRect, MatchesOracle) {
  std::mt19937_64 rng(104);
  const Rect r{0, 0, 64, 64};
  int overlaps = 0;
  for (int it = 0; it < tilevis::test::cases(60000); ++it) {
    auto p = [&] { return Point{8 * static_cast<int32_t>(rng() % 25) - 64, 8 * static_cast<int32_t>(rng() % 25) - 64}; };
    const Point a = p(), b = (it % 5 == 0) ? a : p();
    const bool expect = !(a == b) && oracle_segment_open_region(a, b, rect_region(r));
    ASSERT_EQ(segment_overlaps_rect(a, b, r), expect) << a.x << "," << a.y << " " << b.x << "," << b.y;
    ASSERT_EQ(segment_overlaps(ConvexPolygon::from_rect(r), a, b), expect);
    overlaps += expect;
  }
  EXPECT_GT(overlaps, tilevis::test::cases(5000));
  // Along a border, or touching a corner: no overlap.
  EXPECT_FALSE(segment_overlaps_rect({0, -10}, {0, 100}, r));
  EXPECT_FALSE(segment_overlaps_rect({-8, 72}, {72, -8}, {0, 0, 32, 32}));  // x + y = 64 touches (32,32)
  EXPECT_TRUE(segment_overlaps_rect({-8, 71}, {71, -8}, {0, 0, 32, 32}));
}

TEST(SegmentOverlapsPolygon, MatchesOracle) {
  std::mt19937_64 rng(105);
  for (int it = 0; it < tilevis::test::cases(30000); ++it) {
    const ConvexPolygon poly = random_convex_polygon(rng, -40, 40, 3 + static_cast<int>(rng() % 5));
    const Point a = random_point(rng, -50, 50), b = random_point(rng, -50, 50);
    std::vector<Affine> fs;
    for (const auto& e : poly.edges()) fs.push_back({Rational(e.line.a), Rational(e.line.b), Rational(e.line.c)});
    const bool expect = !(a == b) && oracle_segment_open_region(a, b, fs);
    ASSERT_EQ(segment_overlaps(poly, a, b), expect);
  }
}

}  // namespace
}  // namespace tilevis::geom::test
