#include <gtest/gtest.h>

#include <random>

#include "geom/depth.h"
#include "oracle.h"
#include "test_cases.h"

namespace tilevis::geom::test {
namespace {

Vertex random_vertex(std::mt19937_64& rng, int32_t range, int depth_bits) {
  const Point p = random_point(rng, -range, range);
  const uint64_t zmax = (uint64_t{1} << depth_bits) - 1;
  uint64_t z = rng() & zmax;
  if (rng() % 8 == 0) z = (rng() & 1) ? zmax : 0;  // extremes of the depth range
  return {p.x, p.y, static_cast<uint32_t>(z)};
}

Triangle random_triangle(std::mt19937_64& rng, int32_t range, int depth_bits) {
  for (;;) {
    Triangle t{{random_vertex(rng, range, depth_bits), random_vertex(rng, range, depth_bits),
                random_vertex(rng, range, depth_bits)}};
    if (doubled_area(t) != 0) return t;
  }
}

Line random_line(std::mt19937_64& rng, int32_t range) {
  for (;;) {
    const Point p = random_point(rng, -range, range), q = random_point(rng, -range, range);
    if (!(p == q)) return Line::through(p, q);
  }
}

TEST(DepthPlane, SmallFlagAndNormalisation) {
  const Triangle t{{Vertex{0, 0, 10}, Vertex{0, 100, 20}, Vertex{100, 0, 30}}};  // negative area
  const DepthPlane p = DepthPlane::from(t);
  EXPECT_TRUE(p.valid());
  EXPECT_GT(p.area, 0);
  EXPECT_TRUE(p.small);
  const Triangle big_z{{Vertex{0, 0, 1u << 26}, Vertex{0, 100, 20}, Vertex{100, 0, 30}}};
  EXPECT_FALSE(DepthPlane::from(big_z).small);
  const Triangle flat{{Vertex{0, 0, 1}, Vertex{5, 5, 2}, Vertex{10, 10, 3}}};
  EXPECT_FALSE(DepthPlane::from(flat).valid());
  // Depth at the vertices is exact.
  for (const auto& v : t.v) {
    EXPECT_EQ(depth_order(p, v.xy(), v.z), 0);
    EXPECT_EQ(depth_order(p, v.xy(), v.z + 1), -1);
    EXPECT_EQ(quantized_depth(p, v.xy(), 24), v.z);
  }
}

class DepthOrder : public ::testing::TestWithParam<int> {};

TEST_P(DepthOrder, AtSamplesMatchesOracle) {
  const int bits = GetParam();
  std::mt19937_64 rng(31 + static_cast<uint64_t>(bits));
  const BigInt zmax = (BigInt(1) << bits) - 1;
  for (int i = 0; i < tilevis::test::cases(30000); ++i) {
    const Triangle a = random_triangle(rng, kLim, bits), b = random_triangle(rng, kLim, bits);
    const DepthPlane pa = DepthPlane::from(a), pb = DepthPlane::from(b);
    const Point s = random_point(rng, -kLim, kLim);
    const Rational za = depth_at(a, rpoint(s)), zb = depth_at(b, rpoint(s));
    ASSERT_EQ(depth_order(pa, pb, s), sgn(za - zb));
    const uint32_t z = static_cast<uint32_t>(rng() & ((uint64_t{1} << bits) - 1));
    ASSERT_EQ(depth_order(pa, s, z), sgn(za - Rational(z)));
    // Quantised depth: round half to even, clamped.
    const Rational r = za;
    BigInt fl = boost::multiprecision::numerator(r) / boost::multiprecision::denominator(r);
    if (Rational(fl) > r) fl -= 1;
    const Rational frac = r - Rational(fl);
    if (frac > Rational(1, 2) || (frac == Rational(1, 2) && (fl & 1) != 0)) fl += 1;
    if (fl < 0) fl = 0;
    if (fl > zmax) fl = zmax;
    ASSERT_EQ(BigInt(quantized_depth(pa, s, bits)), fl);
  }
}

// Triangles sharing edge v0v1 (same z there): equal depth on the whole line v0v1, so every
// point on it is an exact tie; nudging a z by one decides it.
TEST_P(DepthOrder, TiesAlongASharedEdge) {
  const int bits = GetParam();
  std::mt19937_64 rng(41 + static_cast<uint64_t>(bits));
  int ties = 0;
  for (int i = 0; i < tilevis::test::cases(6000); ++i) {
    const Triangle a = random_triangle(rng, kLim, bits);
    Triangle b = a;
    b.v[2] = random_vertex(rng, kLim, bits);
    if (doubled_area(b) == 0) continue;
    const bool nudge = i % 2 == 1;
    if (nudge) b.v[0].z = b.v[0].z == 0 ? 1 : b.v[0].z - 1;
    const DepthPlane pa = DepthPlane::from(a), pb = DepthPlane::from(b);
    const Line shared = Line::through(a.v[0].xy(), a.v[1].xy());
    // Implicit points on the shared line.
    ImplicitPoint on[3];
    int n = 0;
    while (n < 3) {
      const ImplicitPoint p = intersect(shared, random_line(rng, kLim));
      if (p.valid()) on[n++] = p;
    }
    for (const auto& p : on) {
      const RPoint o = rpoint(p);
      const int expect = sgn(depth_at(a, o) - depth_at(b, o));
      ASSERT_EQ(depth_order(pa, pb, p), expect);
      if (!nudge) {
        ASSERT_EQ(expect, 0);
      }
      ties += expect == 0;
    }
    // A rational point on the shared line: the centroid of three collinear implicit points.
    const RationalPoint g = centroid(on[0], on[1], on[2]);
    const int expect = sgn(depth_at(a, rpoint(g)) - depth_at(b, rpoint(g)));
    ASSERT_EQ(depth_order(pa, pb, g), expect);
    if (!nudge) {
      ASSERT_EQ(expect, 0);
    }
    // Lattice points on the shared line (the vertices themselves).
    ASSERT_EQ(depth_order(pa, pb, a.v[1].xy()), 0);
  }
  EXPECT_GT(ties, tilevis::test::cases(8000));
}

// Coplanar triangles on z = z0 + gx x + gy y (integer gradient): ties everywhere.
TEST_P(DepthOrder, CoplanarTrianglesTieEverywhere) {
  const int bits = GetParam();
  std::mt19937_64 rng(51 + static_cast<uint64_t>(bits));
  const int64_t zmax = (int64_t{1} << bits) - 1;
  for (int i = 0; i < tilevis::test::cases(3000); ++i) {
    const int64_t gx = static_cast<int64_t>(rng() % 7) - 3, gy = static_cast<int64_t>(rng() % 7) - 3;
    const int32_t range = 1 << (bits - 5);
    const int64_t z0 = zmax / 2;
    auto on_plane = [&](Point p) { return Vertex{p.x, p.y, static_cast<uint32_t>(z0 + gx * p.x + gy * p.y)}; };
    auto tri = [&]() {
      for (;;) {
        Triangle t{{on_plane(random_point(rng, -range, range)), on_plane(random_point(rng, -range, range)),
                    on_plane(random_point(rng, -range, range))}};
        if (doubled_area(t) != 0) return t;
      }
    };
    const Triangle a = tri(), b = tri();
    const DepthPlane pa = DepthPlane::from(a), pb = DepthPlane::from(b);
    ASSERT_EQ(depth_order(pa, pb, random_point(rng, -kLim, kLim)), 0);
    const ImplicitPoint p = intersect(random_line(rng, kLim), random_line(rng, kLim));
    if (p.valid()) {
      ASSERT_EQ(depth_order(pa, pb, p), 0);
    }
    ImplicitPoint q[3];
    for (auto& v : q) {
      do v = intersect(random_line(rng, kLim), random_line(rng, kLim));
      while (!v.valid());
    }
    const RationalPoint g = centroid(q[0], q[1], q[2]);
    ASSERT_EQ(depth_order(pa, pb, g), 0);
    // One unit off at one vertex.
    Triangle c = b;
    c.v[1].z += 1;
    const DepthPlane pc = DepthPlane::from(c);
    ASSERT_EQ(depth_order(pc, pb, g), sgn(depth_at(c, rpoint(g)) - depth_at(b, rpoint(g))));
    if (p.valid()) {
      ASSERT_EQ(depth_order(pc, pb, p), sgn(depth_at(c, rpoint(p)) - depth_at(b, rpoint(p))));
    }
  }
}

TEST_P(DepthOrder, AtImplicitAndRationalPointsMatchesOracle) {
  const int bits = GetParam();
  std::mt19937_64 rng(61 + static_cast<uint64_t>(bits));
  for (int i = 0; i < tilevis::test::cases(10000); ++i) {
    const Triangle a = random_triangle(rng, kLim, bits), b = random_triangle(rng, kLim, bits);
    const DepthPlane pa = DepthPlane::from(a), pb = DepthPlane::from(b);
    ImplicitPoint q[3];
    for (auto& v : q) {
      do v = intersect(random_line(rng, kLim), random_line(rng, kLim));
      while (!v.valid());
    }
    ASSERT_EQ(depth_order(pa, pb, q[0]), sgn(depth_at(a, rpoint(q[0])) - depth_at(b, rpoint(q[0]))));
    const RationalPoint g = centroid(q[0], q[1], q[2]);
    ASSERT_EQ(depth_order(pa, pb, g), sgn(depth_at(a, rpoint(g)) - depth_at(b, rpoint(g))));
  }
}

// Depth of segment AB at a point on its line, by projection onto AB (independent of the
// dominant-axis formula in the library).
Rational edge_depth(const Vertex& a, const Vertex& b, const RPoint& p) {
  const Rational dx = Rational(b.x) - a.x, dy = Rational(b.y) - a.y;
  const Rational t = ((p.x - a.x) * dx + (p.y - a.y) * dy) / (dx * dx + dy * dy);
  return Rational(a.z) + t * (Rational(b.z) - Rational(a.z));
}

TEST_P(DepthOrder, PlaneVersusSilhouetteEdge) {
  const int bits = GetParam();
  std::mt19937_64 rng(71 + static_cast<uint64_t>(bits));
  int ties = 0;
  for (int i = 0; i < tilevis::test::cases(20000); ++i) {
    const Triangle t = random_triangle(rng, kLim, bits);
    Vertex a = random_vertex(rng, kLim, bits), b = random_vertex(rng, kLim, bits);
    const int mode = i % 3;
    if (mode >= 1) {  // the edge is an edge of the triangle: ties all along it
      a = t.v[0];
      b = t.v[1];
      if (mode == 2) a.z = a.z == 0 ? 1 : a.z - 1;
    }
    if (a.xy() == b.xy()) continue;
    const DepthPlane pt = DepthPlane::from(t);
    const Line ab = Line::through(a.xy(), b.xy());
    for (int k = 0; k < 3; ++k) {
      // Crossings with the triangle's edge lines (test 3's points 4 and 5) or random lines.
      const Line other = k < 2 ? Line::through(t.v[k].xy(), t.v[k + 1].xy()) : random_line(rng, kLim);
      const ImplicitPoint p = intersect(ab, other);
      if (!p.valid()) continue;
      const RPoint o = rpoint(p);
      const int expect = sgn(depth_at(t, o) - edge_depth(a, b, o));
      ASSERT_EQ(depth_order_edge(pt, a, b, p), expect);
      if (mode == 1) {
        ASSERT_EQ(expect, 0);
      }
      ties += expect == 0;
    }
  }
  EXPECT_GT(ties, tilevis::test::cases(5000));
}

INSTANTIATE_TEST_SUITE_P(Bits, DepthOrder, ::testing::Values(16, 24, 26, 27, 32));

TEST(DepthOrder, MixedSmallAndWidePlanes) {
  std::mt19937_64 rng(81);
  for (int i = 0; i < tilevis::test::cases(20000); ++i) {
    const Triangle a = random_triangle(rng, kLim, 24), b = random_triangle(rng, kLim, 32);
    const DepthPlane pa = DepthPlane::from(a), pb = DepthPlane::from(b);
    const Point s = random_point(rng, -kLim, kLim);
    ASSERT_EQ(depth_order(pa, pb, s), sgn(depth_at(a, rpoint(s)) - depth_at(b, rpoint(s))));
    ASSERT_EQ(depth_order(pb, pa, s), -depth_order(pa, pb, s));
  }
}

// The wide fallbacks on their own (the filter decides almost every random case before them),
// and the extreme magnitudes of every bound: corners of the band, z at 0 and 2^D - 1.
TEST(DepthOrder, ExactFallbacksMatchOracleAtExtremes) {
  std::mt19937_64 rng(82);
  const int32_t L = kCoordLimit;
  const int32_t corner[4] = {-L, -L + 1, L - 1, L};
  for (int bits : {24, 26, 27, 32}) {
    const uint32_t zmax = static_cast<uint32_t>((uint64_t{1} << bits) - 1);
    auto extreme_vertex = [&](bool extreme) {
      if (!extreme) return random_vertex(rng, L, bits);
      return Vertex{corner[rng() % 4], corner[rng() % 4], (rng() & 1) ? zmax : 0u};
    };
    auto extreme_point = [&](bool extreme) {
      return extreme ? Point{corner[rng() % 4], corner[rng() % 4]} : random_point(rng, -L, L);
    };
    auto extreme_line = [&](bool extreme) {
      for (;;) {
        const Point p = extreme_point(extreme), q = extreme_point(extreme);
        if (!(p == q)) return Line::through(p, q);
      }
    };
    for (int i = 0; i < tilevis::test::cases(4000); ++i) {
      const bool ex = i % 2 == 0;
      Triangle a, b;
      do a = Triangle{{extreme_vertex(ex), extreme_vertex(ex), extreme_vertex(ex)}};
      while (doubled_area(a) == 0);
      do b = Triangle{{extreme_vertex(ex), extreme_vertex(ex), extreme_vertex(ex)}};
      while (doubled_area(b) == 0);
      const DepthPlane pa = DepthPlane::from(a), pb = DepthPlane::from(b);
      const Point s = extreme_point(ex);
      const int at_s = sgn(depth_at(a, rpoint(s)) - depth_at(b, rpoint(s)));
      ASSERT_EQ(depth_order(pa, pb, s), at_s);
      ASSERT_EQ(detail::depth_order_sample_wide(pa, pb, s), at_s);
      ImplicitPoint q[3];
      for (auto& v : q) {
        do v = intersect(extreme_line(ex), extreme_line(false));
        while (!v.valid());
      }
      const int at_q = sgn(depth_at(a, rpoint(q[0])) - depth_at(b, rpoint(q[0])));
      ASSERT_EQ(depth_order(pa, pb, q[0]), at_q);
      ASSERT_EQ(detail::depth_order_implicit_exact(pa, pb, q[0]), at_q);
      const RationalPoint g = centroid(q[0], q[1], q[2]);
      const int at_g = sgn(depth_at(a, rpoint(g)) - depth_at(b, rpoint(g)));
      ASSERT_EQ(depth_order(pa, pb, g), at_g);
      ASSERT_EQ(detail::depth_order_rational_exact(pa, pb, g), at_g);
      // Edge: a's edge v0v1 against plane b at a point on it.
      if (a.v[0].xy() == a.v[1].xy()) continue;
      const ImplicitPoint on = intersect(Line::through(a.v[0].xy(), a.v[1].xy()), extreme_line(ex));
      if (!on.valid()) continue;
      const int at_e = sgn(depth_at(b, rpoint(on)) - edge_depth(a.v[0], a.v[1], rpoint(on)));
      ASSERT_EQ(depth_order_edge(pb, a.v[0], a.v[1], on), at_e);
    }
  }
}

}  // namespace
}  // namespace tilevis::geom::test
