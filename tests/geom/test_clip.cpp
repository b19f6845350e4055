#include <gtest/gtest.h>

#include <random>

#include "geom/clip.h"
#include "geom/overlap.h"
#include "oracle.h"
#include "test_cases.h"

namespace tilevis::geom::test {
namespace {

// Every vertex lies exactly on its two lines, the polygon is strictly convex and its lines
// are the ones from_lines() accepts.
void expect_well_formed(const ConvexPolygon& poly) {
  if (poly.empty()) return;
  const std::size_t n = poly.size();
  ASSERT_GE(n, 3u);
  std::vector<Line> lines;
  for (std::size_t i = 0; i < n; ++i) {
    const ImplicitPoint& v = poly.vertex(i);
    ASSERT_GT(v.w, 0);
    ASSERT_EQ(side(poly.line(i), v), 0);
    ASSERT_EQ(side(poly.line((i + n - 1) % n), v), 0);
    lines.push_back(poly.line(i));
  }
  const auto rebuilt = ConvexPolygon::from_lines(lines);
  ASSERT_TRUE(rebuilt.has_value());
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(rpoint(rebuilt->vertex(i)), rpoint(poly.vertex(i)));
  // Interior point strictly inside.
  const RationalPoint g = interior_point(poly);
  for (const auto& e : poly.edges()) ASSERT_GT(side(e.line, g), 0);
}

Line random_line_in(std::mt19937_64& rng, int32_t lo, int32_t hi) {
  for (;;) {
    const Point p = random_point(rng, lo, hi), q = random_point(rng, lo, hi);
    if (!(p == q)) return Line::through(p, q);
  }
}

TEST(ConvexPolygon, Constructors) {
  const auto tri = ConvexPolygon::from_triangle(Point{0, 0}, Point{0, 10}, Point{10, 0});  // negative order
  ASSERT_EQ(tri.size(), 3u);
  EXPECT_EQ(rpoint(tri.vertex(0)), rpoint(Point{0, 0}));
  EXPECT_EQ(rpoint(tri.vertex(1)), rpoint(Point{10, 0}));
  EXPECT_EQ(exact_area(tri), Rational(100));
  expect_well_formed(tri);
  EXPECT_TRUE(ConvexPolygon::from_triangle(Point{0, 0}, Point{1, 1}, Point{2, 2}).empty());
  const auto rect = ConvexPolygon::from_rect({0, 0, 256, 512});
  EXPECT_EQ(exact_area(rect), Rational(2 * 256 * 512));
  EXPECT_DOUBLE_EQ(doubled_area(rect), 2.0 * 256 * 512);
  expect_well_formed(rect);
  EXPECT_EQ(bounding_box(rect), (Rect{0, 0, 256, 512}));
  // The tile owns [x0, x1) x [y0, y1).
  EXPECT_TRUE(covers(rect, {0, 0}));
  EXPECT_TRUE(covers(rect, {255, 511}));
  EXPECT_FALSE(covers(rect, {256, 0}));
  EXPECT_FALSE(covers(rect, {0, 512}));
  const Point square[4] = {{0, 0}, {4, 0}, {4, 4}, {0, 4}};
  EXPECT_TRUE(ConvexPolygon::from_convex_points(square).has_value());
  const Point bad[4] = {{0, 0}, {4, 0}, {4, 0}, {0, 4}};
  EXPECT_FALSE(ConvexPolygon::from_convex_points(bad).has_value());
}

// The split keeps both sides; their exact areas sum to the parent's and their samples
// partition the parent's samples. Small coordinates so that every lattice point is checked
// and many of them fall exactly on the clip lines.
TEST(Split, ConservesAreaAndPartitionsSamples) {
  std::mt19937_64 rng(91);
  int crossed = 0;
  for (int it = 0; it < tilevis::test::cases(3000); ++it) {
    const ConvexPolygon poly = random_convex_polygon(rng, -40, 40, 3 + static_cast<int>(rng() % 8));
    Line l = random_line_in(rng, -50, 50);
    if (it % 4 == 0) {  // through a vertex of the polygon when it is a lattice point
      const ImplicitPoint& v = poly.vertex(rng() % poly.size());
      l = Line::through({static_cast<int32_t>(v.x / v.w), static_cast<int32_t>(v.y / v.w)}, random_point(rng, -50, 50));
      if (l.a == 0 && l.b == 0) continue;
    }
    if (it % 4 == 1) l = poly.line(rng() % poly.size());  // along an edge
    const SplitResult r = split(poly, l);
    expect_well_formed(r.inside);
    expect_well_formed(r.outside);
    const Rational parent = exact_area(poly);
    ASSERT_EQ(parent, shoelace(rvertices(poly)));
    ASSERT_EQ(exact_area(r.inside) + exact_area(r.outside), parent);
    if (!r.inside.empty()) {
      ASSERT_EQ(exact_area(r.inside), shoelace(rvertices(r.inside)));
    }
    // Against rational Sutherland-Hodgman.
    const auto ref_in = clip_rational(rvertices(poly), l.a, l.b, l.c);
    ASSERT_EQ(exact_area(r.inside), ref_in.size() >= 3 ? shoelace(ref_in) : Rational(0));
    crossed += !r.inside.empty() && !r.outside.empty();
    for (int32_t y = -41; y <= 41; ++y)
      for (int32_t x = -41; x <= 41; ++x) {
        const Point s{x, y};
        ASSERT_EQ(int{covers(poly, s)}, int{covers(r.inside, s)} + int{covers(r.outside, s)}) << x << "," << y;
      }
    const LineRelation rel = classify(poly, l);
    ASSERT_EQ(rel == LineRelation::crosses, !r.inside.empty() && !r.outside.empty());
    if (rel == LineRelation::inside) {
      ASSERT_TRUE(r.outside.empty());
    }
  }
  EXPECT_GT(crossed, tilevis::test::cases(1000));
}

// Recursive splitting as in SVGPU §3.2.2 (both sides re-clipped by later lines): the leaves
// still conserve area exactly and cover every sample of the root exactly once.
TEST(Split, RecursivePiecesPartitionTheTriangle) {
  std::mt19937_64 rng(92);
  for (int it = 0; it < tilevis::test::cases(150); ++it) {
    const Point a = random_point(rng, -60, 60), b = random_point(rng, -60, 60), c = random_point(rng, -60, 60);
    const ConvexPolygon root = ConvexPolygon::from_triangle(a, b, c);
    if (root.empty()) continue;
    std::vector<ConvexPolygon> pieces{root};
    const int nlines = 4 + static_cast<int>(rng() % 12);
    for (int k = 0; k < nlines; ++k) {
      const Line l = random_line_in(rng, -60, 60);
      std::vector<ConvexPolygon> next;
      for (const auto& p : pieces) {
        SplitResult r = split(p, l);
        if (!r.inside.empty()) next.push_back(std::move(r.inside));
        if (!r.outside.empty()) next.push_back(std::move(r.outside));
      }
      pieces = std::move(next);
    }
    Rational total = 0;
    for (const auto& p : pieces) {
      expect_well_formed(p);
      total += exact_area(p);
    }
    ASSERT_EQ(total, exact_area(root));
    double approx = 0;
    for (const auto& p : pieces) approx += doubled_area(p);
    ASSERT_NEAR(approx, static_cast<double>(std::llabs(orient2d(a, b, c))), 1e-9 * approx);
    for (int32_t y = -61; y <= 61; ++y)
      for (int32_t x = -61; x <= 61; ++x) {
        int n = 0;
        for (const auto& p : pieces) n += covers(p, {x, y});
        ASSERT_EQ(n, int{covers(root, {x, y})});
      }
  }
}

// covered_span gives each row's covered samples as one pixel range: exactly the pixels whose
// sample covers() accepts, on pieces of split triangles, with samples on their lines (small
// integer coordinates: ties everywhere), every sub-pixel offset, and at the full range.
TEST(Coverage, SpanIsWhatCoversAccepts) {
  std::mt19937_64 rng(94);
  int64_t covered = 0, ties = 0;
  for (int it = 0; it < tilevis::test::cases(300); ++it) {
    const bool wide = it % 10 == 9;
    const int32_t lim = wide ? kCoordLimit : 60;
    const Point a = random_point(rng, -lim, lim), b = random_point(rng, -lim, lim), c = random_point(rng, -lim, lim);
    ConvexPolygon piece = ConvexPolygon::from_triangle(a, b, c);
    for (int k = 0; k < 3 && !piece.empty(); ++k) {
      SplitResult r = split(piece, random_line_in(rng, -lim, lim));
      piece = std::move(rng() % 2 ? r.inside : r.outside);
      if (piece.empty()) piece = ConvexPolygon::from_triangle(a, b, c);
    }
    if (piece.empty()) continue;
    const int32_t sb = int32_t(rng() % 5);  // sub-pixel bits 0..4
    const int32_t sx = int32_t(rng() % (1u << sb)), sy = int32_t(rng() % (1u << sb));
    // Rows and pixels around the piece's box (at the full range: a window of it).
    const Rect box = bounding_box(piece);
    const int64_t x0 = (int64_t{box.x0} >> sb) - 2, y0 = (int64_t{box.y0} >> sb) - 2;
    const int64_t x1 = std::min<int64_t>((int64_t{box.x1} >> sb) + 2, x0 + 200);
    const int64_t y1 = std::min<int64_t>((int64_t{box.y1} >> sb) + 2, y0 + 200);
    for (int64_t py = y0; py <= y1; ++py) {
      const int64_t y = (py << sb) + sy;
      if (y < -kCoordLimit || y > kCoordLimit) continue;
      const PixelSpan span = covered_span(piece, sx, int32_t(y), sb, x0, x1);
      for (int64_t px = x0; px <= x1; ++px) {
        const int64_t x = (px << sb) + sx;
        if (x < -kCoordLimit || x > kCoordLimit) continue;
        const Point s{int32_t(x), int32_t(y)};
        const bool in = covers(piece, s);
        ASSERT_EQ(in, px >= span.lo && px <= span.hi) << "piece " << it << " sample " << x << "," << y;
        covered += in;
        for (const auto& e : piece.edges()) ties += e.line.eval(s) == 0;
      }
    }
  }
  EXPECT_GT(covered, tilevis::test::cases(10000));
  EXPECT_GT(ties, tilevis::test::cases(100));  // samples on the pieces' lines were tested
}

// Large coordinates (full guard band): exact conservation through the wide bounds.
TEST(Split, ConservesAreaAtFullRange) {
  std::mt19937_64 rng(93);
  const int32_t lim = kCoordLimit;
  for (int it = 0; it < tilevis::test::cases(2000); ++it) {
    const ConvexPolygon poly = random_convex_polygon(rng, -lim, lim, 3 + static_cast<int>(rng() % 6));
    std::vector<ConvexPolygon> pieces{poly};
    for (int k = 0; k < 3; ++k) {
      const Line l = random_line_in(rng, -lim, lim);
      std::vector<ConvexPolygon> next;
      for (const auto& p : pieces) {
        SplitResult r = split(p, l);
        if (!r.inside.empty()) next.push_back(std::move(r.inside));
        if (!r.outside.empty()) next.push_back(std::move(r.outside));
      }
      pieces = std::move(next);
    }
    Rational total = 0;
    for (const auto& p : pieces) {
      expect_well_formed(p);
      total += exact_area(p);
    }
    ASSERT_EQ(total, exact_area(poly));
  }
}

TEST(Split, CanonicalOrder) {
  // Square (0,0) (8,0) (8,8) (0,8): lines top, right, bottom, left. Cut by the vertical x = 4
  // oriented with its positive side x < 4 (line from (4,0) to (4,8) has a = -8).
  const ConvexPolygon sq = ConvexPolygon::from_rect({0, 0, 8, 8});
  const Line cut = Line::through({4, 0}, {4, 8});
  const SplitResult r = split(sq, cut);
  ASSERT_EQ(r.inside.size(), 4u);
  ASSERT_EQ(r.outside.size(), 4u);
  // Inside (x <= 4): parent edges top, bottom, left in parent order, clip line after top
  // (the edge leaving the positive block).
  EXPECT_EQ(r.inside.line(0), sq.line(0));
  EXPECT_EQ(r.inside.line(1), cut);
  EXPECT_EQ(r.inside.line(2), sq.line(2));
  EXPECT_EQ(r.inside.line(3), sq.line(3));
  EXPECT_EQ(rpoint(r.inside.vertex(0)), rpoint(Point{0, 0}));
  EXPECT_EQ(rpoint(r.inside.vertex(1)), rpoint(Point{4, 0}));
  // Outside: top, right, bottom, then the flipped line after bottom.
  EXPECT_EQ(r.outside.line(0), sq.line(0));
  EXPECT_EQ(r.outside.line(1), sq.line(1));
  EXPECT_EQ(r.outside.line(2), sq.line(2));
  EXPECT_EQ(r.outside.line(3), cut.flipped());
  EXPECT_EQ(rpoint(r.outside.vertex(0)), rpoint(Point{4, 0}));
  // Through two opposite vertices: the parent's vertex representations are reused.
  const SplitResult d = split(sq, Line::through({0, 0}, {8, 8}));
  ASSERT_EQ(d.inside.size(), 3u);
  ASSERT_EQ(d.outside.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(d.inside.vertex(i).w, 1);
    EXPECT_EQ(d.outside.vertex(i).w, 1);
  }
  // A side keeping every edge is the parent itself.
  const SplitResult whole = split(sq, Line::through({0, 8}, {0, 0}));  // x >= 0 side... along left edge
  EXPECT_TRUE(whole.outside.empty() || whole.inside.empty());
}

TEST(Chord, MatchesSplitVertices) {
  std::mt19937_64 rng(94);
  for (int it = 0; it < tilevis::test::cases(5000); ++it) {
    const ConvexPolygon poly = random_convex_polygon(rng, -1000, 1000, 3 + static_cast<int>(rng() % 6));
    const Line l = random_line_in(rng, -1000, 1000);
    ImplicitPoint p, q;
    const bool ok = chord(poly, l, p, q);
    const SplitResult r = split(poly, l);
    ASSERT_EQ(ok, !r.inside.empty() && !r.outside.empty());
    if (!ok) continue;
    ASSERT_EQ(side(l, p), 0);
    ASSERT_EQ(side(l, q), 0);
    ASSERT_NE(rpoint(p), rpoint(q));
    for (std::size_t i = 0; i < r.inside.size(); ++i)
      if (r.inside.line(i) == l) {
        const auto& a = r.inside.vertex(i);
        const auto& b = r.inside.vertex((i + 1) % r.inside.size());
        ASSERT_EQ(a.x, p.x);
        ASSERT_EQ(a.w, p.w);
        ASSERT_EQ(b.y, q.y);
        ASSERT_EQ(b.w, q.w);
      }
  }
}

TEST(ClipToRect, MatchesRationalClipping) {
  std::mt19937_64 rng(95);
  for (int it = 0; it < tilevis::test::cases(5000); ++it) {
    const Point a = random_point(rng, -3000, 3000), b = random_point(rng, -3000, 3000), c = random_point(rng, -3000, 3000);
    const Rect r{-256 * static_cast<int32_t>(rng() % 8), -256 * static_cast<int32_t>(rng() % 8), 256 * static_cast<int32_t>(1 + rng() % 8),
                 256 * static_cast<int32_t>(1 + rng() % 8)};
    const Triangle t{{Vertex{a.x, a.y, 0}, Vertex{b.x, b.y, 0}, Vertex{c.x, c.y, 0}}};
    const ConvexPolygon piece = triangle_in_rect(t, r);
    expect_well_formed(piece);
    auto ref = ConvexPolygon::from_triangle(a, b, c).empty() ? std::vector<RPoint>{} : rvertices(ConvexPolygon::from_triangle(a, b, c));
    ref = clip_rational(ref, 0, 1, -r.y0);
    ref = clip_rational(ref, -1, 0, r.x1);
    ref = clip_rational(ref, 0, -1, r.y1);
    ref = clip_rational(ref, 1, 0, -r.x0);
    const Rational expect = ref.size() >= 3 ? shoelace(ref) : Rational(0);
    ASSERT_EQ(exact_area(piece), expect);
    ASSERT_EQ(piece.empty(), expect == 0);
    ASSERT_EQ(!piece.empty(), triangle_overlaps_rect(t, r));
    if (!piece.empty()) {
      const Rect bb = bounding_box(piece);
      for (const auto& v : rvertices(piece)) {
        ASSERT_LE(Rational(bb.x0), v.x);
        ASSERT_GE(Rational(bb.x1), v.x);
        ASSERT_LE(Rational(bb.y0), v.y);
        ASSERT_GE(Rational(bb.y1), v.y);
      }
      const auto leftmost = std::min_element(ref.begin(), ref.end(), [](const RPoint& p, const RPoint& q) { return p.x < q.x; });
      ASSERT_GT(Rational(bb.x0 + 1), leftmost->x);  // tight: floor of the minimum
    }
  }
}

}  // namespace
}  // namespace tilevis::geom::test
