#include <gtest/gtest.h>

#include <random>

#include "geom/predicates.h"
#include "oracle.h"
#include "test_cases.h"

namespace tilevis::geom::test {
namespace {

BigInt big_orient(Point a, Point b, Point c) {
  return (BigInt(b.x) - a.x) * (BigInt(c.y) - a.y) - (BigInt(b.y) - a.y) * (BigInt(c.x) - a.x);
}

// A point on line ab (a lattice point when step divides b - a), pushed off it by `nudge`.
Point collinear_point(std::mt19937_64& rng, Point a, Point b, int nudge) {
  const int64_t dx = int64_t{b.x} - a.x, dy = int64_t{b.y} - a.y;
  const int64_t g = std::max<int64_t>(1, std::gcd(std::llabs(dx), std::llabs(dy)));
  const int64_t sx = dx / g, sy = dy / g;
  const int64_t k = static_cast<int64_t>(rng() % static_cast<uint64_t>(g + 1));
  int64_t x = a.x + k * sx + (rng() & 1 ? nudge : 0), y = a.y + k * sy + (rng() & 1 ? 0 : nudge);
  x = std::clamp<int64_t>(x, -kLim, kLim);
  y = std::clamp<int64_t>(y, -kLim, kLim);
  return {static_cast<int32_t>(x), static_cast<int32_t>(y)};
}

TEST(Orient2d, RandomFullRangeMatchesOracle) {
  std::mt19937_64 rng(21);
  for (int i = 0; i < 200000; ++i) {
    const Point a = random_point(rng, -kLim, kLim), b = random_point(rng, -kLim, kLim), c = random_point(rng, -kLim, kLim);
    ASSERT_EQ(BigInt(orient2d(a, b, c)), big_orient(a, b, c));
  }
  // Extreme corners: 2^48, the largest doubled area inside the band (2^49 bounds each term sum).
  const Point p{-kLim, -kLim}, q{kLim, -kLim}, r{kLim, kLim};
  EXPECT_EQ(BigInt(orient2d(p, q, r)), big_orient(p, q, r));
  EXPECT_EQ(orient2d(p, q, r), int64_t{1} << 48);
}

TEST(Orient2d, NearCollinear) {
  std::mt19937_64 rng(22);
  int zeros = 0;
  for (int i = 0; i < 100000; ++i) {
    const Point a = random_point(rng, -kLim, kLim);
    // b - a with a large common factor so that many lattice points lie on ab.
    const int32_t s = 1 + static_cast<int32_t>(rng() % 64);
    Point b = random_point(rng, -kLim / s, kLim / s);
    b = {std::clamp(a.x + b.x * s / 2, -kLim, kLim), std::clamp(a.y + b.y * s / 2, -kLim, kLim)};
    const Point c = collinear_point(rng, a, b, static_cast<int>(rng() % 3) - 1);
    const int64_t o = orient2d(a, b, c);
    ASSERT_EQ(BigInt(o), big_orient(a, b, c));
    zeros += o == 0;
  }
  EXPECT_GT(zeros, 20000);
}

TEST(Line, EvalIsOrientAndTieRuleIsExclusive) {
  std::mt19937_64 rng(23);
  for (int i = 0; i < 100000; ++i) {
    const Point p = random_point(rng, -kLim, kLim), q = random_point(rng, -kLim, kLim);
    if (p == q) continue;
    const Point s = (i & 1) ? collinear_point(rng, p, q, 0) : random_point(rng, -kLim, kLim);
    const Line l = Line::through(p, q);
    ASSERT_EQ(l.eval(s), orient2d(p, q, s));
    ASSERT_NE(l.owns_boundary(), l.flipped().owns_boundary());
    ASSERT_EQ(l.flipped(), Line::through(q, p));
    ASSERT_EQ(int{in_half_plane(l, s)} + int{in_half_plane(l.flipped(), s)}, 1);
  }
  // D3D top-left: inward normal pointing right (left edge) or down (top edge) owns the edge.
  EXPECT_TRUE(Line::through({0, 10}, {0, 0}).owns_boundary());   // x = 0, interior x > 0
  EXPECT_FALSE(Line::through({0, 0}, {0, 10}).owns_boundary());  // x = 0, interior x < 0
  EXPECT_TRUE(Line::through({0, 0}, {10, 0}).owns_boundary());   // y = 0, interior y > 0 (below)
  EXPECT_FALSE(Line::through({10, 0}, {0, 0}).owns_boundary());  // y = 0, interior above
}

Line random_line(std::mt19937_64& rng) {
  for (;;) {
    const Point p = random_point(rng, -kLim, kLim), q = random_point(rng, -kLim, kLim);
    if (!(p == q)) return Line::through(p, q);
  }
}

TEST(ImplicitPoint, IntersectMatchesCramer) {
  std::mt19937_64 rng(24);
  for (int i = 0; i < tilevis::test::cases(50000); ++i) {
    const Point a = random_point(rng, -kLim, kLim), b = random_point(rng, -kLim, kLim);
    const Point c = random_point(rng, -kLim, kLim), d = random_point(rng, -kLim, kLim);
    if (a == b || c == d) continue;
    const ImplicitPoint p = intersect(Line::through(a, b), Line::through(c, d));
    RPoint o;
    const bool ok = intersect_segments_lines(a, b, c, d, o);
    ASSERT_EQ(p.valid(), ok);
    if (!ok) continue;
    ASSERT_GT(p.w, 0);
    ASSERT_EQ(rpoint(p), o);
  }
  // Parallel lines.
  EXPECT_FALSE(intersect(Line::through({0, 0}, {4, 2}), Line::through({1, 7}, {9, 11})).valid());
}

// Configurations of three concurrent lines through a non-lattice point, built exactly:
// if (E + k F) / (1 + k) = m for lattice E, F then line EF passes through m.
struct Concurrent {
  Line l1, l2, l3;
};
Concurrent concurrent_lines(std::mt19937_64& rng, int32_t range, int k) {
  for (;;) {
    const Point p0 = random_point(rng, -range, range), p2 = random_point(rng, -range, range);
    const Point v = random_point(rng, -range, range), w = random_point(rng, -range, range);
    // m = (p0 + k p2) / (1 + k); E = p0 + k v, F = p2 - v keeps (E + k F)/(1+k) = m.
    const Point e{p0.x + k * v.x, p0.y + k * v.y}, f{p2.x - v.x, p2.y - v.y};
    const Point g{p0.x + k * w.x, p0.y + k * w.y}, h{p2.x - w.x, p2.y - w.y};
    if (p0 == p2 || e == f || g == h) continue;
    const Line l1 = Line::through(p0, p2), l2 = Line::through(e, f), l3 = Line::through(g, h);
    if (!intersect(l1, l2).valid()) continue;
    return {l1, l2, l3};
  }
}

TEST(ImplicitPoint, SideMatchesOracleRandom) {
  std::mt19937_64 rng(25);
  for (int i = 0; i < tilevis::test::cases(100000); ++i) {
    const Line l1 = random_line(rng), l2 = random_line(rng), l3 = random_line(rng);
    const ImplicitPoint p = intersect(l1, l2);
    if (!p.valid()) continue;
    const RPoint o = rpoint(p);
    const int expect = sgn(Rational(l3.a) * o.x + Rational(l3.b) * o.y + Rational(l3.c));
    ASSERT_EQ(side(l3, p), expect);
  }
}

TEST(ImplicitPoint, SideOfConcurrentAndNearlyConcurrentLines) {
  std::mt19937_64 rng(26);
  int zeros = 0;
  for (int i = 0; i < tilevis::test::cases(60000); ++i) {
    const int k = 1 + static_cast<int>(rng() % 5);
    const int32_t range = kLim / (2 * (k + 1));
    Concurrent c = concurrent_lines(rng, range, k);
    if (i % 3 == 1) c.l3.c += 1;   // off by one unit
    if (i % 3 == 2) c.l3.a += (rng() & 1) ? 1 : -1;
    const ImplicitPoint p = intersect(c.l1, c.l2);
    const RPoint o = rpoint(p);
    const int expect = sgn(Rational(c.l3.a) * o.x + Rational(c.l3.b) * o.y + Rational(c.l3.c));
    ASSERT_EQ(side(c.l3, p), expect);
    if (i % 3 == 0) {
      ASSERT_EQ(expect, 0);
    }
    zeros += expect == 0;
    // Same point from the other pair of lines: another representation, same decisions.
    const ImplicitPoint p2 = intersect(c.l2, c.l3);
    if (i % 3 == 0) {
      ASSERT_EQ(rpoint(p2), o);
    }
  }
  EXPECT_GE(zeros, tilevis::test::cases(20000));
}

TEST(ImplicitPoint, SideAtBoundExtremes) {
  // Lines through guard-band corners: |c| = 2^47, |w| up to 2^49, side value near 2^97.
  const Point c0{-kLim, -kLim}, c1{kLim, -kLim}, c2{kLim, kLim}, c3{-kLim, kLim};
  const Line l1 = Line::through(c0, c2), l2 = Line::through(c1, {-kLim, kLim - 1});
  const Line l3 = Line::through(c3, {kLim, -kLim + 1});
  const ImplicitPoint p = intersect(l1, l2);
  const RPoint o = rpoint(p);
  EXPECT_EQ(side(l3, p), sgn(Rational(l3.a) * o.x + Rational(l3.b) * o.y + Rational(l3.c)));
}

// Lattice-affine images of an implicit point p0 whose centroid is the lattice point m.
struct CentroidCase {
  ImplicitPoint p0, p1, p2;
  Point m;
};
CentroidCase centroid_case(std::mt19937_64& rng) {
  for (;;) {
    const int32_t r = 1 << 18;
    const Point a = random_point(rng, -r, r), b = random_point(rng, -r, r);
    const Point c = random_point(rng, -r, r), d = random_point(rng, -r, r);
    const Point m = random_point(rng, -r, r);
    const int m11 = static_cast<int>(rng() % 5) - 2, m12 = static_cast<int>(rng() % 5) - 2;
    const int m21 = static_cast<int>(rng() % 5) - 2, m22 = static_cast<int>(rng() % 5) - 2;
    if (m11 * m22 - m12 * m21 == 0 || (m11 + 1) * (m22 + 1) - m12 * m21 == 0) continue;
    const Point t1 = random_point(rng, -r, r);
    // T1 x = M x + t1; T2 x = 3m - x - T1 x (both lattice maps, invertible by the checks).
    auto T1 = [&](Point p) { return Point{m11 * p.x + m12 * p.y + t1.x, m21 * p.x + m22 * p.y + t1.y}; };
    auto T2 = [&](Point p) {
      const Point q = T1(p);
      return Point{3 * m.x - p.x - q.x, 3 * m.y - p.y - q.y};
    };
    if (a == b || c == d) continue;
    const ImplicitPoint p0 = intersect(Line::through(a, b), Line::through(c, d));
    if (!p0.valid()) continue;
    const ImplicitPoint p1 = intersect(Line::through(T1(a), T1(b)), Line::through(T1(c), T1(d)));
    const ImplicitPoint p2 = intersect(Line::through(T2(a), T2(b)), Line::through(T2(c), T2(d)));
    return {p0, p1, p2, m};
  }
}

TEST(RationalPoint, CentroidIsExact) {
  std::mt19937_64 rng(27);
  for (int i = 0; i < tilevis::test::cases(20000); ++i) {
    const Line l[6] = {random_line(rng), random_line(rng), random_line(rng),
                       random_line(rng), random_line(rng), random_line(rng)};
    const ImplicitPoint a = intersect(l[0], l[1]), b = intersect(l[2], l[3]), c = intersect(l[4], l[5]);
    if (!a.valid() || !b.valid() || !c.valid()) continue;
    const RationalPoint g = centroid(a, b, c);
    const RPoint ra = rpoint(a), rb = rpoint(b), rc = rpoint(c);
    ASSERT_EQ(rpoint(g), (RPoint{(ra.x + rb.x + rc.x) / 3, (ra.y + rb.y + rc.y) / 3}));
    ASSERT_GT(g.w.sign(), 0);
    ASSERT_TRUE(is_correctly_rounded(g.fx, big(g.x)));
    const Line t = random_line(rng);
    const RPoint o = rpoint(g);
    const int expect = sgn(Rational(t.a) * o.x + Rational(t.b) * o.y + Rational(t.c));
    ASSERT_EQ(side(t, g), expect);
    ASSERT_EQ(detail::side_exact(t, g), expect);  // the fallback alone
  }
  const CentroidCase cc = centroid_case(rng);
  EXPECT_EQ(rpoint(centroid(cc.p0, cc.p1, cc.p2)), rpoint(cc.m));
}

TEST(RationalPoint, SideOnAndNearLinesThroughTheCentroid) {
  std::mt19937_64 rng(28);
  int zeros = 0;
  for (int i = 0; i < tilevis::test::cases(20000); ++i) {
    const CentroidCase cc = centroid_case(rng);
    const RationalPoint g = centroid(cc.p0, cc.p1, cc.p2);
    Point e = random_point(rng, -kLim / 2, kLim / 2);
    if (e == cc.m) continue;
    Line l = Line::through(cc.m, e);
    if (i % 3 == 1) l.c += (rng() & 1) ? 1 : -1;
    if (i % 3 == 2 && !(e == Point{cc.m.x + 1, cc.m.y})) l = Line::through({cc.m.x + 1, cc.m.y}, e);
    const RPoint o = rpoint(g);
    const int expect = sgn(Rational(l.a) * o.x + Rational(l.b) * o.y + Rational(l.c));
    ASSERT_EQ(side(l, g), expect);
    zeros += expect == 0;
    ASSERT_EQ(in_half_plane(l, g) + in_half_plane(l.flipped(), g), 1);
  }
  EXPECT_GT(zeros, tilevis::test::cases(6000));
}

TEST(TriangleEdges, ContainsImplicitAndRationalAgreeWithSampleRule) {
  std::mt19937_64 rng(29);
  for (int i = 0; i < tilevis::test::cases(20000); ++i) {
    const Point a = random_point(rng, -100, 100), b = random_point(rng, -100, 100), c = random_point(rng, -100, 100);
    const TriangleEdges t = TriangleEdges::from(a, b, c);
    const Point s = random_point(rng, -100, 100);
    ASSERT_EQ(t.valid, orient2d(a, b, c) != 0);
    ASSERT_EQ(t.covers(s), t.contains(ImplicitPoint::from(s)));
    ASSERT_EQ(t.covers(s), t.contains(RationalPoint::from(s)));
  }
}

}  // namespace
}  // namespace tilevis::geom::test
