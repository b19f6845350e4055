// cuda_ref's exact arithmetic against model/geom's, on the host: the two are independent
// implementations of the same predicates, so any decision (or rounding) they disagree on is
// a bug in one of them. Random inputs over the whole coordinate range, plus the adversarial
// ones where filters must fall back to exact arithmetic (points on lines, coplanar planes).
#include <algorithm>
#include <cmath>
#include <utility>
#include <cstdio>
#include <cstring>
#include <random>

#include <gtest/gtest.h>

#include "geom/clip.h"
#include "geom/depth.h"
#include "geom/fixed.h"
#include "geom/polygon.h"
#include "geom/predicates.h"
#include "poly.cuh"

namespace g = tilevis::geom;
namespace c = tilevis::cuda;

namespace {

std::mt19937_64 rng(20261122);

int32_t coord(int32_t lim = (1 << 23) - 1) { return std::uniform_int_distribution<int32_t>(-lim, lim)(rng); }
uint32_t depth() { return std::uniform_int_distribution<uint32_t>(0, (1u << 24) - 1)(rng); }

g::Line gline(const c::ILine& l) { return {l.a, l.b, l.c}; }
g::ImplicitPoint gpoint(const c::exact::IPoint& p) { return {p.x, p.y, p.w}; }

template <int L>
g::WideInt<L> gwide(const c::Wide<L>& w) {
  g::WideInt<L> r{};
  for (int i = 0; i < L; ++i) r.limb[i] = w.limb[i];
  return r;
}

TEST(CudaPredicates, WideToDoubleRoundsLikeGeom) {
  for (int k = 0; k < 200000; ++k) {
    c::Wide<5> w;
    const int top = int(rng() % 5);
    for (int i = 0; i < 5; ++i) w.limb[i] = i <= top ? rng() : 0;
    if (k % 3 == 0) {  // a tie: 54 significant bits ending in 1, nothing below
      const int shift = int(rng() % 200);
      w = c::Wide<5>::of(int64_t((rng() >> 10) | 1));
      for (int s = 0; s < shift; ++s) w = w + w;
    }
    if (k % 2) w = -w;
    ASSERT_EQ(w.to_double(), gwide(w).to_double()) << k;
  }
}

TEST(CudaPredicates, Int128ToDoubleIsCorrectlyRounded) {
  for (int k = 0; k < 200000; ++k) {
    c::I128 v = static_cast<c::I128>((static_cast<c::U128>(rng()) << 64) | rng());
    v >>= int(rng() % 127);
    if (k % 4 == 0) v = (v | 1) << int(rng() % 60);
    ASSERT_EQ(c::i128_to_double(v), static_cast<double>(v)) << k;
  }
}

TEST(CudaPredicates, SnapDepthMatchesGeom) {
  std::uniform_real_distribution<double> u(-0.1, 1.1);
  for (int k = 0; k < 200000; ++k) {
    double z = u(rng);
    const uint32_t bits = 1 + uint32_t(rng() % 32);
    if (k % 5 == 0) z = (double(rng() % ((uint64_t{1} << bits) - 1)) + 0.5) / double((uint64_t{1} << bits) - 1);
    ASSERT_EQ(c::snap_depth(z, bits), g::snap_depth(z, int(bits))) << z << " " << bits;
  }
}

TEST(CudaPredicates, SidesOfImplicitAndRationalPoints) {
  for (int k = 0; k < 50000; ++k) {
    const c::Pt p[6] = {{coord(), coord()}, {coord(), coord()}, {coord(), coord()},
                        {coord(), coord()}, {coord(), coord()}, {coord(), coord()}};
    const c::ILine l1 = c::ILine::through(p[0], p[1]), l2 = c::ILine::through(p[2], p[3]), l3 = c::ILine::through(p[4], p[5]);
    const auto q = c::exact::intersect(l1, l2);
    if (q.w == 0) continue;
    const auto gq = g::intersect(gline(l1), gline(l2));
    ASSERT_EQ(gq.x, q.x);
    ASSERT_EQ(gq.w, q.w);
    ASSERT_EQ(c::exact::side(l3, q), g::side(gline(l3), gq));
    ASSERT_EQ(c::exact::side(l1, q), 0);  // on its own line: exactly
    const auto q2 = c::exact::intersect(l2, l3), q3 = c::exact::intersect(l3, l1);
    if (q2.w == 0 || q3.w == 0) continue;
    const auto r = c::exact::centroid(q, q2, q3);
    const auto gr = g::centroid(gq, gpoint(q2), gpoint(q3));
    ASSERT_EQ(r.fx, gr.fx);
    ASSERT_EQ(r.fw, gr.fw);
    const c::ILine l4 = c::ILine::through(p[k % 6], p[(k + 1) % 6]);
    ASSERT_EQ(c::exact::side(l4, r), g::side(gline(l4), gr));
  }
}

TEST(CudaPredicates, DepthOrdersAgreeIncludingTies) {
  for (int k = 0; k < 30000; ++k) {
    c::Vtx a[3], b[3];
    for (auto& v : a) v = {coord(1 << 20), coord(1 << 20), depth()};
    for (auto& v : b) v = {coord(1 << 20), coord(1 << 20), depth()};
    if (k % 3 == 0) b[0] = a[0], b[1] = a[1], b[2] = a[2];  // coplanar: every order is a tie
    const auto pa = c::exact::plane_of(a[0], a[1], a[2]), pb = c::exact::plane_of(b[0], b[1], b[2]);
    const g::Triangle ta{{g::Vertex{a[0].x, a[0].y, a[0].z}, g::Vertex{a[1].x, a[1].y, a[1].z}, g::Vertex{a[2].x, a[2].y, a[2].z}}};
    const g::Triangle tb{{g::Vertex{b[0].x, b[0].y, b[0].z}, g::Vertex{b[1].x, b[1].y, b[1].z}, g::Vertex{b[2].x, b[2].y, b[2].z}}};
    const auto ga = g::DepthPlane::from(ta), gb = g::DepthPlane::from(tb);
    if (pa.area == 0 || pb.area == 0) continue;
    ASSERT_EQ(pa.alpha, ga.alpha);
    ASSERT_EQ(pa.gamma, ga.gamma);
    ASSERT_EQ(pa.fgamma, ga.fgamma);
    const c::ILine l1 = c::ILine::through(a[0].xy(), b[1].xy()), l2 = c::ILine::through(a[2].xy(), b[0].xy());
    const c::ILine l3 = c::ILine::through(a[1].xy(), b[2].xy());
    const auto q1 = c::exact::intersect(l1, l2), q2 = c::exact::intersect(l2, l3), q3 = c::exact::intersect(l3, l1);
    if (q1.w == 0 || q2.w == 0 || q3.w == 0) continue;
    const auto r = c::exact::centroid(q1, q2, q3);
    const auto gr = g::centroid(gpoint(q1), gpoint(q2), gpoint(q3));
    const int o = c::exact::depth_order(pa, pb, r);
    ASSERT_EQ(o, g::depth_order(ga, gb, gr));
    if (k % 3 == 0) {
      ASSERT_EQ(o, 0);
    }
    ASSERT_EQ(c::exact::depth_order(pa, b[0].xy(), b[0].z), g::depth_order(ga, g::Point{b[0].x, b[0].y}, b[0].z));
    // Test 3: a point on segment a0-b1's line (its intersection with l2).
    ASSERT_EQ(c::exact::depth_order_edge(pa, a[0], b[1], q1),
              g::depth_order_edge(ga, g::Vertex{a[0].x, a[0].y, a[0].z}, g::Vertex{b[1].x, b[1].y, b[1].z}, gpoint(q1)));
  }
}

TEST(CudaPredicates, SplitKeepsGeomsCanonicalOrderAndRepresentation) {
  using E = c::PEdge<c::ExactP>;
  for (int k = 0; k < 20000; ++k) {
    const int32_t lim = 1 << (10 + k % 13);
    const c::Vtx v0{coord(lim), coord(lim), 0}, v1{coord(lim), coord(lim), 0}, v2{coord(lim), coord(lim), 0};
    if (c::orient2d(v0.xy(), v1.xy(), v2.xy()) == 0) continue;
    const auto tt = c::make_tile_tri<c::ExactP>(v0, v1, v2, 0, true);
    const int32_t x0 = coord(lim), y0 = coord(lim);
    const c::Rect rect{x0, y0, x0 + 1 + int32_t(rng() % uint64_t(lim)), y0 + 1 + int32_t(rng() % uint64_t(lim))};
    E poly[c::kTileCap];
    bool overflow = false;
    const uint32_t n = c::tile_polygon<c::ExactP>(tt, rect, poly, overflow);
    const g::ConvexPolygon gp = g::clip_to_rect(g::ConvexPolygon::from_triangle(g::Point{v0.x, v0.y}, g::Point{v1.x, v1.y},
                                                                                g::Point{v2.x, v2.y}),
                                                g::Rect{rect.x0, rect.y0, rect.x1, rect.y1});
    ASSERT_EQ(n, gp.size());
    if (n == 0) continue;
    for (uint32_t i = 0; i < n; ++i) {
      ASSERT_EQ(gline(poly[i].line), gp.line(i));
      ASSERT_EQ(poly[i].start.x, gp.vertex(i).x);
      ASSERT_EQ(poly[i].start.w, gp.vertex(i).w);
    }
    const c::ILine l = c::ILine::through({coord(lim), coord(lim)}, {coord(lim), coord(lim)});
    bool pos, neg;
    c::line_sides<c::ExactP>(poly, n, l, pos, neg);
    ASSERT_EQ(pos && neg, g::classify(gp, gline(l)) == g::LineRelation::crosses);
    if (!pos || !neg) continue;
    E in_e[16], out_e[16];
    c::PolyOut<c::ExactP> in{in_e, 0, 16, false}, out{out_e, 0, 16, false};
    c::split<c::ExactP>(poly, n, l, in, out);
    const auto gs = g::split(gp, gline(l));
    ASSERT_EQ(in.n, gs.inside.size());
    ASSERT_EQ(out.n, gs.outside.size());
    for (uint32_t i = 0; i < in.n; ++i) {
      ASSERT_EQ(gline(in_e[i].line), gs.inside.line(i));
      ASSERT_EQ(in_e[i].start.y, gs.inside.vertex(i).y);
      ASSERT_EQ(in_e[i].start.w, gs.inside.vertex(i).w);
    }
    for (uint32_t i = 0; i < out.n; ++i) {
      ASSERT_EQ(gline(out_e[i].line), gs.outside.line(i));
      ASSERT_EQ(out_e[i].start.x, gs.outside.vertex(i).x);
    }
    ASSERT_EQ(c::doubled_area<c::ExactP>(in_e, in.n), g::doubled_area(gs.inside));
    const c::Rect b = c::bounding_box<c::ExactP>(out_e, out.n);
    const g::Rect gb = g::bounding_box(gs.outside);
    ASSERT_EQ(b.x0, gb.x0);
    ASSERT_EQ(b.y1, gb.y1);
  }
}

// k_clip_long's warp split (clip.cu): each edge's share (split_edge) made on its own, in no
// particular order, and placed by a prefix sum of split_counts with split()'s room (m + 1 edges
// a part) is split_sides' polygons, edge for edge. Pieces of 3 to 12 edges: tile polygons of
// random triangles, split again and again with the inside part kept, by lines through their
// vertices (sides of 0), random lines and corner cuts; float with its sides regularized, exact
// as it is. (No float split here runs past the room; the placement stops at it as push does.)
template <class P>
std::pair<double, double> vxy(const typename P::V& v) {
  if constexpr (P::kExact) return {double(v.x) / double(v.w), double(v.y) / double(v.w)};
  else return {v.x, v.y};
}

// A random triangle (depths random or 0) clipped to a random rectangle at the scale of case k
// (2^(8 + k % 15)), and the points its test lines go through: random ones, or the triangle's
// vertices and the rectangle's corners (often the polygon's vertices: sides of 0).
template <class P>
struct RandomPiece {
  int32_t lim = 0;
  c::Vtx v[3];
  c::TileTri<P> tt;
  c::Rect rect;
  c::PEdge<P> poly[32];
  uint32_t n = 0;

  bool make(int k, bool depths) {
    lim = 1 << (8 + k % 15);
    for (c::Vtx& x : v) {
      const int32_t px = coord(lim), py = coord(lim);
      x = {px, py, depths ? depth() : 0u};
    }
    if (c::orient2d(v[0].xy(), v[1].xy(), v[2].xy()) == 0) return false;
    tt = c::make_tile_tri<P>(v[0], v[1], v[2], 0, true);
    const int32_t x0 = coord(lim), y0 = coord(lim);
    rect = {x0, y0, x0 + 1 + int32_t(rng() % uint64_t(lim)), y0 + 1 + int32_t(rng() % uint64_t(lim))};
    bool overflow = false;
    n = c::tile_polygon<P>(tt, rect, poly, overflow);
    return true;
  }
  // A line's two points for case k: through a vertex or a corner, two of them, or random points.
  std::pair<c::Pt, c::Pt> line_points(int k) {
    const c::Pt pts[7] = {v[0].xy(), v[1].xy(), v[2].xy(), {rect.x0, rect.y0}, {rect.x1, rect.y0}, {rect.x1, rect.y1},
                          {rect.x0, rect.y1}};
    const c::Pt p = k % 3 == 0 ? c::Pt{coord(lim), coord(lim)} : pts[rng() % 7];
    const c::Pt q = k % 3 == 1 ? pts[rng() % 7] : c::Pt{coord(lim), coord(lim)};
    return {p, q};
  }
};

template <class P>
void split_by_edges_is_split() {
  using E = c::PEdge<P>;
  uint64_t splits = 0, on_line = 0, past_room = 0, longest = 0;
  RandomPiece<P> rp;
  for (int k = 0; k < 6000; ++k) {
    if (!rp.make(k, false)) continue;
    const int32_t lim = rp.lim;
    E* const poly = rp.poly;
    uint32_t n = rp.n;
    for (int step = 0; step < 16 && n >= 3 && n < 13; ++step) {
      auto [p, q] = rp.line_points(k);
      if (step % 2 == 1) {  // a corner cut off, the rest kept: one edge more each time
        const uint32_t i = uint32_t(rng() % n);
        const auto [xi, yi] = vxy<P>(poly[i].start);
        const auto [xp, yp] = vxy<P>(poly[(i + n - 1) % n].start);
        const auto [xn, yn] = vxy<P>(poly[(i + 1) % n].start);
        const double f = 0.05 + 0.3 * std::uniform_real_distribution<double>(0, 1)(rng);
        p = {int32_t(std::llround(xi + f * (xp - xi))), int32_t(std::llround(yi + f * (yp - yi)))};
        q = {int32_t(std::llround(xi + f * (xn - xi))), int32_t(std::llround(yi + f * (yn - yi)))};
        if (P::side(P::line(p, q), poly[i].start) > 0) std::swap(p, q);
      }
      if (q == p) q = {coord(lim), coord(lim)};
      const auto l = P::line(p, q);
      c::Sides sg = c::sides_of<P>(poly, n, l);
      if (sg.pos == 0 || sg.neg == 0) continue;
      if constexpr (!P::kExact) sg.regularize(n);
      const uint32_t cap = n + 1;
      E in_e[32], out_e[32];
      c::PolyOut<P> in{in_e, 0, cap, false}, out{out_e, 0, cap, false};
      c::split_sides<P>(poly, n, l, sg, in, out);
      ++splits;
      on_line += (c::Sides::low_bits(n) & ~sg.pos & ~sg.neg) != 0;
      past_room += in.overflow || out.overflow;
      longest = std::max<uint64_t>(longest, n);
      uint32_t at[33] = {};
      for (uint32_t i = 0; i < n; ++i) at[i + 1] = at[i] + c::split_counts(n, sg, i);
      ASSERT_EQ(at[n] & 0xffffu, in.n);
      ASSERT_EQ(at[n] >> 16, out.n);
      E pin[32], pout[32];
      const auto lf = l.flipped();
      for (uint32_t r = 0; r < n; ++r) {
        const uint32_t i = (r * 7 + 3) % n == r ? r : (n - 1 - r);  // not in order
        c::split_edge_placed<P>(poly, n, l, lf, sg, i, at[i], pin, pout, cap);  // k_clip_long's placing
      }
      // Field by field (exact's records have padding).
      auto same = [](const E& x, const E& y) {
        if constexpr (P::kExact) return x.line == y.line && x.start.x == y.start.x && x.start.y == y.start.y && x.start.w == y.start.w;
        else return std::memcmp(&x, &y, sizeof(E)) == 0;
      };
      for (uint32_t i = 0; i < std::min(in.n, cap); ++i) ASSERT_TRUE(same(in_e[i], pin[i])) << "inside edge " << i;
      for (uint32_t i = 0; i < std::min(out.n, cap); ++i) ASSERT_TRUE(same(out_e[i], pout[i])) << "outside edge " << i;
      n = std::min(in.n, cap);
      std::memcpy(static_cast<void*>(poly), in_e, sizeof(E) * n);
    }
  }
  std::printf("%llu splits, %llu with a vertex on the line, %llu past the room, pieces of up to %llu edges\n",
              (unsigned long long)splits, (unsigned long long)on_line, (unsigned long long)past_room,
              (unsigned long long)longest);
  EXPECT_GT(on_line, 100u);  // the counts of a vertex on the line (sides of 0) are covered
  EXPECT_GE(longest, 12u);
}

TEST(CudaPredicates, SplitByEdgesPlacedByCountsIsSplitFloat) { split_by_edges_is_split<c::FloatP>(); }
TEST(CudaPredicates, SplitByEdgesPlacedByCountsIsSplitExact) { split_by_edges_is_split<c::ExactP>(); }

// Test 3's chord as k_clip_long's warp makes it (lane i: chord_ends_at of edge i; each end from
// the highest lane that gives it, poly[0].start where none does) against chord_of's loop, over
// the pieces and lines of split_by_edges_is_split's kind, silhouette edges of random depths. The
// sides are the raw ones survives() uses: in float they need not be a convex polygon's (more
// than one change of sign), where "the last edge" is what makes the two agree.
template <class P>
void chord_by_lanes_is_chord() {
  using E = c::PEdge<P>;
  using V = typename P::V;
  auto same_v = [](const V& x, const V& y) {
    if constexpr (P::kExact) return x.x == y.x && x.y == y.y && x.w == y.w;
    else return std::memcmp(&x, &y, sizeof(V)) == 0;
  };
  uint64_t chords = 0, several = 0, survived = 0, zero_side = 0;
  RandomPiece<P> rp;
  for (int k = 0; k < 6000; ++k) {
    if (!rp.make(k, true)) continue;
    const int32_t lim = rp.lim;
    const auto& tt = rp.tt;
    E* const poly = rp.poly;
    uint32_t n = rp.n;
    for (int step = 0; step < 16 && n >= 3 && n < 13; ++step) {
      auto [p, q] = rp.line_points(k);
      if (q == p) q = {coord(lim), coord(lim)};
      const c::Vtx a{p.x, p.y, depth()}, b{q.x, q.y, depth()};
      const auto e = c::make_sil_edge<P>(a, b);
      const c::Sides sg = c::sides_of<P>(poly, n, e.line);
      if (sg.pos != 0 && sg.neg != 0) {
        ++chords;
        zero_side += (c::Sides::low_bits(n) & ~sg.pos & ~sg.neg) != 0;
        V first, second;
        c::chord_of<P>(poly, n, e.line, [&](uint32_t i) { return sg.at(i); }, first, second);
        V lf = poly[0].start, ls = poly[0].start;
        int hf = -1, hs = -1, gives = 0;
        for (uint32_t r = 0; r < n; ++r) {
          const uint32_t i = (r * 5 + 2) % n == r ? r : (n - 1 - r);  // lanes in no order
          V vf = poly[0].start, vs = poly[0].start;
          const uint32_t h = c::chord_ends_at<P>(poly, n, e.line, sg, i, vf, vs);
          gives += (h & 1u) != 0;
          if ((h & 1u) && int(i) > hf) hf = int(i), lf = vf;
          if ((h & 2u) && int(i) > hs) hs = int(i), ls = vs;
        }
        several += gives > 1;
        ASSERT_TRUE(same_v(first, lf)) << "first, piece of " << n << " edges";
        ASSERT_TRUE(same_v(second, ls)) << "second, piece of " << n << " edges";
        const bool by_lanes = c::chord_nearer<P>(tt, e, lf, ls);
        ASSERT_EQ(by_lanes, c::chord_survives<P>(poly, n, tt, e, [&](uint32_t i) { return sg.at(i); }));
        survived += by_lanes;
      }
      // On to a smaller piece: the inside part of the line's split (regularized in float, as
      // the clip does), when it has room.
      if (sg.pos == 0 || sg.neg == 0) continue;
      c::Sides sr = sg;
      if constexpr (!P::kExact) sr.regularize(n);
      E in_e[32], out_e[32];
      c::PolyOut<P> in{in_e, 0, n + 1, false}, out{out_e, 0, n + 1, false};
      c::split_sides<P>(poly, n, e.line, sr, in, out);
      if (in.overflow || in.n < 3) break;
      n = in.n;
      std::memcpy(static_cast<void*>(poly), in_e, sizeof(E) * n);
    }
  }
  std::printf("%llu chords, %llu with a vertex on the line, %llu with more than one edge giving an end, %llu survive\n",
              (unsigned long long)chords, (unsigned long long)zero_side, (unsigned long long)several,
              (unsigned long long)survived);
  EXPECT_GT(chords, 1000u);
  EXPECT_GT(zero_side, 10u);
  EXPECT_GT(survived, 100u);
  EXPECT_GT(chords - survived, 100u);
  if constexpr (!P::kExact) {
    EXPECT_GT(several, 0u);  // float signs that change more than twice: covered
  }
}

TEST(CudaPredicates, ChordByLanesIsChordFloat) { chord_by_lanes_is_chord<c::FloatP>(); }
TEST(CudaPredicates, ChordByLanesIsChordExact) { chord_by_lanes_is_chord<c::ExactP>(); }

}  // namespace

// add_repeated (the hybrid fold's per-pixel areas) against the additions one at a time, bit for
// bit: sums with low bits set, sums at and beyond 2^52 where a sample's share is below the ulp
// (ties to even included), zero, the ends of the double range, and counts that cross several
// binades.
TEST(CudaPredicates, RepeatedAdditionIsTheLoopsBitForBit) {
  std::mt19937_64 rng(7);
  std::vector<double> starts = {0.0, 0.5, 1.0, 3.0, 0x1p52 - 1.0, 0x1p52, 0x1p52 + 1.0, 0x1p53 - 1.0, 0x1p53,
                                0x1p53 + 2.0, 0x1p54 + 2.0, 0x1p51 + 0.5, 0x1p50 + 0.25,
                                // one addition a step: subnormal, below 2^-968, from 2^1022
                                0x1p-1070, 0x1p-1000, 0x1.8p-969, 0x1p1022, 0x1.fp1023};
  for (int k = 0; k < 200; ++k) {
    const double mant = std::uniform_real_distribution<double>(1.0, 2.0)(rng);
    starts.push_back(std::ldexp(mant, int(rng() % 70) - 8));
  }
  const uint64_t counts[] = {0, 1, 2, 3, 7, 64, 1000, 4097, 100000};
  for (const double x : starts)
    for (const double a : {1.0, 0.5, 0.25, 0.125, 0.0625})
      for (const uint64_t m : counts) {
        double loop = x;
        for (uint64_t i = 0; i < m; ++i) loop = c::dadd(loop, a);
        const double fast = c::add_repeated(x, a, m);
        ASSERT_EQ(std::memcmp(&loop, &fast, sizeof(double)), 0)
            << std::hexfloat << "x " << x << " a " << a << " m " << m << ": " << loop << " vs " << fast;
      }
}
