// The tile stage's geometry, written once over a precision policy (Exact or Float):
// convex polygons in plane-based form (SVGPU §3.2.2 after Bernstein & Fussell 2009), the
// pair tests of SVGPU §3.2.1, the split that keeps both sides, the §3.3 occlusion test.
//
// Canonical edge order (the interior test point depends on it): a polygon's lines are in
// positive order (orient2d > 0, interior on the positive side), vertex i is line(i-1) ∩
// line(i). A triangle gives lines p0p1, p1p2, p2p0 (p0p2, p2p1, p1p0 when negatively ordered),
// so vertex 0 is p0; tile rectangles clip by top, right, bottom, left. A split child keeps the
// parent's bounding lines in the parent's order, with the clip line (flipped for the outside
// part) right after the edge leaving the kept side; a vertex the clip line passes through
// keeps the parent's representation.
#pragma once

#include "approx.cuh"
#include "exact.cuh"

namespace tilevis::cuda {

struct ExactP {
  static constexpr bool kExact = true;
  using Line = exact::Line;
  using V = exact::IPoint;
  using R = exact::RPoint;
  using Plane = exact::Plane;

  TV_HD static Line line(Pt p, Pt q) { return Line::through(p, q); }
  TV_HD static V vertex(Pt p) { return V::of(p); }
  TV_HD static int side(const Line& l, const V& v) { return exact::side(l, v); }
  TV_HD static V meet(const Line& a, const Line& b) { return exact::intersect(a, b); }
  TV_HD static int64_t eval(const Line& l, Pt s) { return l.eval(s); }
  TV_HD static bool in_half(const Line& l, Pt s) { return in_half_plane(l, s); }
  TV_HD static bool in_half(const Line& l, const R& r) { return exact::in_half_plane(l, r); }
  TV_HD static R interior(const V& a, const V& b, const V& c) { return exact::centroid(a, b, c); }
  TV_HD static double rx(const R& r) { return ddiv(r.fx, r.fw); }
  TV_HD static double ry(const R& r) { return ddiv(r.fy, r.fw); }
  // sign((c - a) . d) for c on the line through a with direction d: < 2^98 (I128).
  TV_HD static int along(const V& c, const Vtx& a, int64_t dx, int64_t dy) {
    return sign128((c.x - I128{a.x} * c.w) * dx + (c.y - I128{a.y} * c.w) * dy);
  }
  TV_HD static Plane plane(const Vtx& a, const Vtx& b, const Vtx& c) { return exact::plane_of(a, b, c); }
  TV_HD static int depth(const Plane& p, const Plane& q, const R& s) { return exact::depth_order(p, q, s); }
  TV_HD static int depth(const Plane& p, Pt s, uint32_t z) { return exact::depth_order(p, s, z); }
  TV_HD static int depth_edge(const Plane& p, const Vtx& a, const Vtx& b, const V& s) {
    return exact::depth_order_edge(p, a, b, s);
  }
  TV_HD static void bounds(const V& v, int64_t& fx, int64_t& fy, int64_t& cx, int64_t& cy) {
    fx = exact::floor_div(v.x, v.w);
    fy = exact::floor_div(v.y, v.w);
    cx = exact::ceil_div(v.x, v.w);
    cy = exact::ceil_div(v.y, v.w);
  }
  // Doubled area of the fan triangle (v0, a, b) = det[v0; a; b] / (w0 wa wb): the numerator
  // |x (y w - y w)| <= 2^72 2^122, three terms < 2^196 (W256); the denominator <= 2^147 (W192).
  // Each is rounded once, then divided: the polygon's area is their sum in fan order.
  TV_HD static double area_term(const V& v0, const V& a, const V& b) {
    const W256 x0 = wide<4>(v0.x), y0 = wide<4>(v0.y), w0 = wide<4>(I128{v0.w});
    const W256 xa = wide<4>(a.x), ya = wide<4>(a.y), wa = wide<4>(I128{a.w});
    const W256 xb = wide<4>(b.x), yb = wide<4>(b.y), wb = wide<4>(I128{b.w});
    const W256 num = x0 * (ya * wb - yb * wa) - y0 * (xa * wb - xb * wa) + w0 * (xa * yb - xb * ya);
    const W192 den = wide<3>(v0.w) * wide<3>(mul64(a.w, b.w));
    return ddiv(num.to_double(), den.to_double());
  }
};

struct FloatP {
  static constexpr bool kExact = false;
  using Line = approx::Line;
  using V = approx::Vec;
  using R = approx::Vec;
  using Plane = approx::Plane;

  TV_HD static Line line(Pt p, Pt q) { return Line::through(p, q); }
  TV_HD static V vertex(Pt p) { return V::of(p); }
  TV_HD static int side(const Line& l, const V& v) { return approx::side(l, v); }
  TV_HD static V meet(const Line& a, const Line& b) { return approx::intersect(a, b); }
  TV_HD static float eval(const Line& l, Pt s) { return l.eval(float(s.x), float(s.y)); }
  TV_HD static bool in_half(const Line& l, Pt s) { return approx::in_half_plane(l, V::of(s)); }
  TV_HD static bool in_half(const Line& l, const R& r) { return approx::in_half_plane(l, r); }
  TV_HD static R interior(const V& a, const V& b, const V& c) { return approx::centroid(a, b, c); }
  TV_HD static double rx(const R& r) { return r.x; }
  TV_HD static double ry(const R& r) { return r.y; }
  TV_HD static int along(const V& c, const Vtx& a, int64_t dx, int64_t dy) {
    return approx::signf(fadd(fmul(c.x - float(a.x), float(dx)), fmul(c.y - float(a.y), float(dy))));
  }
  TV_HD static Plane plane(const Vtx& a, const Vtx& b, const Vtx& c) { return approx::plane_of(a, b, c); }
  TV_HD static int depth(const Plane& p, const Plane& q, const R& s) { return approx::depth_order(p, q, s); }
  TV_HD static int depth(const Plane& p, Pt s, uint32_t z) { return approx::depth_order(p, s, z); }
  TV_HD static int depth_edge(const Plane& p, const Vtx& a, const Vtx& b, const V& s) {
    return approx::depth_order_edge(p, a, b, s);
  }
  TV_HD static void bounds(const V& v, int64_t& fx, int64_t& fy, int64_t& cx, int64_t& cy) {
    fx = int64_t(floorf(v.x));
    fy = int64_t(floorf(v.y));
    cx = int64_t(ceilf(v.x));
    cy = int64_t(ceilf(v.y));
  }
  TV_HD static double area_term(const V& v0, const V& a, const V& b) {
    const double ax = double(a.x) - v0.x, ay = double(a.y) - v0.y, bx = double(b.x) - v0.x, by = double(b.y) - v0.y;
    return ax * by - ay * bx;
  }
};

template <class P>
struct PEdge {
  typename P::Line line;
  typename P::V start;  // line(i-1) ∩ line(i)
};

// A polygon being written: edges go to `e` up to `cap`; pushing past it sets `overflow`
// (the caller grows the buffer and retries, or, in float precision, counts an anomaly).
template <class P>
struct PolyOut {
  PEdge<P>* e;
  uint32_t n, cap;
  bool overflow;
  TV_HD void push(const typename P::Line& l, const typename P::V& v) {
    if (n < cap) e[n] = {l, v};
    else overflow = true;
    ++n;
  }
};

// A front-facing triangle as the tile stage sees it (SVGPU's tile-list entry).
template <class P>
struct TileTri {
  Vtx v[3];
  typename P::Line edge[3];  // positive order, as the triangle's polygon
  typename P::Plane plane;
  Rect bbox;                 // closed, sub-pixel units
  uint32_t z_min, z_max;
  uint32_t id;               // original (trace) triangle
  uint32_t opaque;
};

// A silhouette edge as the tile stage sees it.
template <class P>
struct SilEdge {
  Vtx a, b;
  typename P::Line line;  // through a, b
  Rect bbox;
  uint32_t z_min, z_max;
};

// A triangle's edges in positive order, as its polygon's (a clockwise triangle taken backwards).
template <class P>
TV_HD inline void positive_edges(const Vtx& v0, const Vtx& v1, const Vtx& v2, typename P::Line* e) {
  if (orient2d(v0.xy(), v1.xy(), v2.xy()) > 0) {
    e[0] = P::line(v0.xy(), v1.xy());
    e[1] = P::line(v1.xy(), v2.xy());
    e[2] = P::line(v2.xy(), v0.xy());
  } else {
    e[0] = P::line(v0.xy(), v2.xy());
    e[1] = P::line(v2.xy(), v1.xy());
    e[2] = P::line(v1.xy(), v0.xy());
  }
}

// Whether the rectangle [rx0, rx1] x [ry0, ry1] (sub-pixel units) lies strictly inside the three
// integer edges a x + b y + c > 0: each edge is tested at the corner where it is least.
TV_HD inline bool rect_inside_edges(const int32_t* a, const int32_t* b, const int64_t* c, int64_t rx0, int64_t ry0,
                                    int64_t rx1, int64_t ry1) {
  bool inside = true;
  for (int k = 0; k < 3; ++k)
    inside &= int64_t(a[k]) * (a[k] > 0 ? rx0 : rx1) + int64_t(b[k]) * (b[k] > 0 ? ry0 : ry1) + c[k] > 0;
  return inside;
}

template <class P>
TV_HD inline TileTri<P> make_tile_tri(const Vtx& v0, const Vtx& v1, const Vtx& v2, uint32_t id, bool opaque) {
  TileTri<P> t;
  t.v[0] = v0;
  t.v[1] = v1;
  t.v[2] = v2;
  positive_edges<P>(v0, v1, v2, t.edge);
  t.plane = P::plane(v0, v1, v2);
  t.bbox = {tmin(tmin(v0.x, v1.x), v2.x), tmin(tmin(v0.y, v1.y), v2.y), tmax(tmax(v0.x, v1.x), v2.x),
            tmax(tmax(v0.y, v1.y), v2.y)};
  t.z_min = tmin(tmin(v0.z, v1.z), v2.z);
  t.z_max = tmax(tmax(v0.z, v1.z), v2.z);
  t.id = id;
  t.opaque = opaque ? 1u : 0u;
  return t;
}

template <class P>
TV_HD inline SilEdge<P> make_sil_edge(const Vtx& a, const Vtx& b) {
  SilEdge<P> e;
  e.a = a;
  e.b = b;
  e.line = P::line(a.xy(), b.xy());
  e.bbox = {tmin(a.x, b.x), tmin(a.y, b.y), tmax(a.x, b.x), tmax(a.y, b.y)};
  e.z_min = tmin(a.z, b.z);
  e.z_max = tmax(a.z, b.z);
  return e;
}

inline constexpr uint32_t kTileCap = 8;  // edges of a tile polygon (tile_polygon)

// The sides of a polygon's vertices (at most kSideCap) against a line, as two bit masks in
// registers: vertex k is positive where bit k of `pos` is set, negative where bit k of `neg`
// is, on the line where neither is. (An int8_t array indexed by a loop variable lives in local
// memory: every test and split of a clip step waited on it.)
inline constexpr uint32_t kSideCap = 32;
struct Sides {
  uint32_t pos = 0, neg = 0;
  TV_HD int at(uint32_t k) const { return int((pos >> k) & 1u) - int((neg >> k) & 1u); }
  TV_HD void set(uint32_t k, int s) {
    pos |= uint32_t(s > 0) << k;
    neg |= uint32_t(s < 0) << k;
  }
  TV_HD static uint32_t low_bits(uint32_t n) { return n >= 32 ? ~0u : (1u << n) - 1u; }
  // x's n bits rotated so that bit s comes to bit 0 (right) or bit 0 goes to bit s (left).
  TV_HD static uint32_t rotr(uint32_t x, uint32_t s, uint32_t n) {
    return uint32_t(((uint64_t(x) >> s) | (uint64_t(x) << (n - s))) & low_bits(n));
  }
  TV_HD static uint32_t rotl(uint32_t x, uint32_t s, uint32_t n) { return rotr(x, s == 0 ? 0 : n - s, n); }

  // Float: made the sides of a convex polygon. Float vertices (meets rounded to float) can
  // leave more than one run of positive vertices, and a split would then emit a non-convex part
  // with more edges than its bound. Keeps the first run of positive vertices (cyclically: the
  // lowest vertex that is positive after a non-positive one starts it) and a zero at either end
  // of it; every other vertex counts as negative. Returns whether a side was changed. Exact
  // polygons are convex: never called.
  TV_HD bool regularize(uint32_t n) {
    const uint32_t full = low_bits(n);
    const uint32_t starts = pos & ~rotl(pos, 1, n);  // positive after a non-positive vertex
    if (starts == 0) return false;                  // all positive, or none: nothing to split
    const uint32_t start = uint32_t(ctz32(starts));
    const uint32_t run = uint32_t(ctz32(~rotr(pos, start, n)));  // < n: some vertex is not positive
    const uint32_t end = start + run >= n ? start + run - n : start + run;  // first vertex after the run
    const uint32_t before = start == 0 ? n - 1 : start - 1;
    const uint32_t kept = rotl(low_bits(run), start, n);  // the run
    const uint32_t rest = full & ~kept;
    const uint32_t zero_kept = full & ~pos & ~neg & rest & ((1u << end) | (1u << before));
    const bool changed = (~neg & rest & ~zero_kept) != 0;  // a positive or zero made negative
    pos = kept;
    neg = rest & ~zero_kept;
    return changed;
  }
};

template <class P>
TV_HD inline Sides sides_of(const PEdge<P>* poly, uint32_t n, const typename P::Line& l) {
  Sides s;
  for (uint32_t i = 0; i < n; ++i) s.set(i, P::side(l, poly[i].start));
  return s;
}

// The triangle's polygon (positive order, vertex 0 = v0) clipped to the tile rectangle by
// its top, right, bottom and left lines, keeping the inside. <= 3 + 4 = 7 edges when exact.
// Returns the edge count (0: empty); `overflow` when a float polygon outgrew kTileCap.
template <class P>
TV_HD inline uint32_t tile_polygon(const TileTri<P>& t, const Rect& r, PEdge<P>* out, bool& overflow) {
  PEdge<P> buf[kTileCap];
  PEdge<P>* cur = out;
  PEdge<P>* next = buf;
  Pt p0 = t.v[0].xy(), p1 = t.v[1].xy(), p2 = t.v[2].xy();
  const int64_t area = orient2d(p0, p1, p2);
  if (area == 0) return 0;
  if (area < 0) {
    const Pt s = p1;
    p1 = p2;
    p2 = s;
  }
  cur[0] = {t.edge[0], P::vertex(p0)};
  cur[1] = {t.edge[1], P::vertex(p1)};
  cur[2] = {t.edge[2], P::vertex(p2)};
  uint32_t n = 3;
  const Pt c[4] = {{r.x0, r.y0}, {r.x1, r.y0}, {r.x1, r.y1}, {r.x0, r.y1}};
  // A rectangle line with the triangle's bounding box on its inner side has every vertex of
  // every part of the triangle on that side too: clip_to_rect would skip it, and so does this.
  const bool inside[4] = {t.bbox.y0 >= r.y0, t.bbox.x1 <= r.x1, t.bbox.y1 <= r.y1, t.bbox.x0 >= r.x0};
  for (int k = 0; k < 4; ++k) {
    if (inside[k]) continue;
    const typename P::Line l = P::line(c[k], c[(k + 1) & 3]);
    bool pos = false, neg = false;
    for (uint32_t i = 0; i < n; ++i) {
      const int s = P::side(l, cur[i].start);
      pos |= s > 0;
      neg |= s < 0;
    }
    if (!neg) continue;
    if (!pos) return 0;
    PolyOut<P> o{next, 0, kTileCap, false};
    // Float: the sides made those of a convex polygon (Sides::regularize), so no part outgrows it.
    Sides sg = sides_of<P>(cur, n, l);
    if constexpr (!P::kExact) sg.regularize(n);
    int si = sg.at(0);
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t j = i + 1 == n ? 0 : i + 1;
      const int sn = sg.at(j);
      if (si > 0 || sn > 0) {
        o.push(cur[i].line, si >= 0 ? cur[i].start : P::meet(l, cur[i].line));
        if (sn <= 0) o.push(l, sn == 0 ? cur[j].start : P::meet(cur[i].line, l));
      }
      si = sn;
    }
    if (o.overflow) {
      overflow = true;
      o.n = kTileCap;
    }
    n = o.n;
    PEdge<P>* s = cur;
    cur = next;
    next = s;
  }
  if (cur != out)
    for (uint32_t i = 0; i < n; ++i) out[i] = cur[i];
  return n;
}

// Sides of a polygon's vertices against l: whether some vertex is strictly positive / negative.
template <class P>
TV_HD inline void line_sides(const PEdge<P>* poly, uint32_t n, const typename P::Line& l, bool& pos, bool& neg) {
  pos = neg = false;
  for (uint32_t i = 0; i < n; ++i) {
    const int s = P::side(l, poly[i].start);
    pos |= s > 0;
    neg |= s < 0;
  }
}

// Test 3's chord of AB's line through a polygon, edge i's part in it (j = i + 1 mod n, si and sn
// the sides of vertices i and j): where the line's edge of the inside part starts (`first`: the
// sides go from positive to not), and where it ends (`second`: from not positive to positive).
// survives() takes the last edge that gives each; a warp can make every edge's at once and take
// the highest lane's (clip.cu).
template <class P>
TV_HD inline bool chord_first(const PEdge<P>* poly, uint32_t i, uint32_t j, int si, int sn, const typename P::Line& l,
                              typename P::V& v) {
  if (!(si > 0 && sn <= 0)) return false;
  v = sn == 0 ? poly[j].start : P::meet(poly[i].line, l);
  return true;
}
template <class P>
TV_HD inline bool chord_second(const PEdge<P>* poly, uint32_t i, int si, int sn, const typename P::Line& l,
                               typename P::V& v) {
  if (!(si <= 0 && sn > 0)) return false;
  v = si == 0 ? poly[i].start : P::meet(l, poly[i].line);
  return true;
}

// Test 3 at the chord's ends: is the edge nearer than the triangle at either end of their overlap?
template <class P>
TV_HD inline bool chord_nearer(const TileTri<P>& tt, const SilEdge<P>& e, const typename P::V& first,
                               const typename P::V& second) {
  const Pt a = e.a.xy(), b = e.b.xy();
  const int64_t dx = int64_t{e.b.x} - e.a.x, dy = int64_t{e.b.y} - e.a.y;
  // sign(z_triangle - z_edge) at each end of the overlap; > 0: the edge is nearer there.
  const int s1 = P::along(first, e.a, dx, dy) < 0 ? P::depth(tt.plane, a, e.a.z) : P::depth_edge(tt.plane, e.a, e.b, first);
  if (s1 > 0) return true;
  const int s2 = P::along(second, e.b, dx, dy) > 0 ? P::depth(tt.plane, b, e.b.z) : P::depth_edge(tt.plane, e.a, e.b, second);
  // Level at both ends: the edge lies in the triangle's plane over the overlap and can bound a
  // coplanar occluder (golden.cpp survives()).
  return s2 > 0 || (s1 == 0 && s2 == 0);
}

// Test 3's chord of line l through an n-gon: each end as the last edge gives it (side_at(k):
// vertex k's side of l), poly[0].start where none does.
template <class P, class SideAt>
TV_HD inline void chord_of(const PEdge<P>* poly, uint32_t n, const typename P::Line& l, SideAt&& side_at,
                           typename P::V& first, typename P::V& second) {
  first = second = poly[0].start;
  const int s0 = side_at(0);
  int si = s0;
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t j = i + 1 == n ? 0 : i + 1;
    const int sn = j == 0 ? s0 : side_at(j);
    chord_first<P>(poly, i, j, si, sn, l, first);
    chord_second<P>(poly, i, si, sn, l, second);
    si = sn;
  }
}

// Edge i's part in chord_of (sides sg): bit 0 when it gives `first` (vf), bit 1 when it gives
// `second` (vs). Lane i of k_clip_long's warp runs it; the highest edge that gives each end is
// chord_of's answer.
template <class P>
TV_HD inline uint32_t chord_ends_at(const PEdge<P>* poly, uint32_t n, const typename P::Line& l, const Sides& sg,
                                    uint32_t i, typename P::V& vf, typename P::V& vs) {
  const uint32_t j = i + 1 == n ? 0 : i + 1;
  const int si = sg.at(i), sn = sg.at(j);
  return uint32_t(chord_first<P>(poly, i, j, si, sn, l, vf)) | uint32_t(chord_second<P>(poly, i, si, sn, l, vs)) << 1;
}

// Test 3 of a pair that passed tests 2 and 1: the chord of AB's line through the polygon and the
// depths at its ends.
template <class P, class SideAt>
TV_HD inline bool chord_survives(const PEdge<P>* poly, uint32_t n, const TileTri<P>& tt, const SilEdge<P>& e,
                                 SideAt&& side_at) {
  typename P::V first, second;
  chord_of<P>(poly, n, e.line, side_at, first, second);
  return chord_nearer<P>(tt, e, first, second);
}

// SVGPU §3.2.1 test 2 (exact form): AB misses the polygon's interior when some polygon line has
// both ends on its outer side or on it (int64 edge functions); otherwise the separating axis
// along AB itself is ruled out by test 1, which finds vertices strictly on both sides of AB's line.
template <class P>
TV_HD inline bool misses(const PEdge<P>* poly, uint32_t n, const SilEdge<P>& e) {
  const Pt a = e.a.xy(), b = e.b.xy();
  if (a == b) return true;
  for (uint32_t i = 0; i < n; ++i)
    if (P::eval(poly[i].line, a) <= 0 && P::eval(poly[i].line, b) <= 0) return true;
  return false;
}

// Tests 2 and 1 of a polygon of at most kSideCap edges: true when AB may meet its interior and
// its vertices lie strictly on both sides of AB's line (touching counts as one side), their sides
// left in `sides`; test 3 (chord_survives) then decides. kOnePass: both tests in one loop, each
// edge read once (the same values). Measured on an H200 (reports/cuda/clip_alloc_fuse_h200.md):
// in survives(), which a thread or a warp's lane runs on its own item, one pass took 17 % off
// million exact's clip stage; in k_clip_long's walk, where 32 lanes test one piece and most leave
// test 2's loop early, it made float hot_tile and slivers 5-9 % slower, so the walk keeps two.
template <class P, bool kOnePass = false>
TV_HD inline bool crosses(const PEdge<P>* poly, uint32_t n, const SilEdge<P>& e, Sides& sides) {
  if constexpr (kOnePass) {
    const Pt a = e.a.xy(), b = e.b.xy();
    if (n == 0 || a == b) return false;
    Sides sd;
    for (uint32_t i = 0; i < n; ++i) {
      if (P::eval(poly[i].line, a) <= 0 && P::eval(poly[i].line, b) <= 0) return false;
      sd.set(i, P::side(e.line, poly[i].start));
    }
    sides = sd;
  } else {
    if (n == 0 || misses<P>(poly, n, e)) return false;
    sides = sides_of<P>(poly, n, e.line);
  }
  return sides.pos != 0 && sides.neg != 0;
}

// SVGPU §3.2.1 tests 1-3 of a silhouette edge against a (piece of a) triangle. true: the
// pair survives and the piece must be split by the edge's line. Where `sides` is given (and
// n <= kSideCap), the vertices' sides of AB's line, which tests 1 and 3 compute, are left
// there for split() to take over: a surviving pair's split needs them again.
template <class P>
TV_HD inline bool survives(const PEdge<P>* poly, uint32_t n, const TileTri<P>& tt, const SilEdge<P>& e,
                           Sides* sides = nullptr) {
  // The pair survives only if tests 1, 2 and 3 all pass, so they may run in any order: the
  // cheap one first.
  if (n <= kSideCap) {
    Sides sd;
    if (!crosses<P, true>(poly, n, e, sd)) return false;
    if (sides) *sides = sd;
    return chord_survives<P>(poly, n, tt, e, [&](uint32_t k) { return sd.at(k); });
  }
  if (misses<P>(poly, n, e)) return false;
  bool pos = false, neg = false;
  line_sides<P>(poly, n, e.line, pos, neg);
  if (!pos || !neg) return false;
  return chord_survives<P>(poly, n, tt, e, [&](uint32_t k) { return P::side(e.line, poly[k].start); });
}

// Edge i's share of a split with the sides given: the inside part's edges it starts (0 to 2, in
// order, handed to `in`) and the outside part's (to `out`). split_sides hands over edge 0's,
// then edge 1's, ...; a warp can make every edge's at once, each placed by a prefix sum of
// split_counts (clip.cu): the same edges in the same order.
template <class P, class In, class Out>
TV_HD inline void split_edge(const PEdge<P>* poly, uint32_t n, const typename P::Line& l, const typename P::Line& lf,
                             const Sides& sg, uint32_t i, In&& in, Out&& out) {
  const uint32_t j = i + 1 == n ? 0 : i + 1;
  const int si = sg.at(i), sn = sg.at(j);
  const typename P::Line& li = poly[i].line;
  if (si > 0 || sn > 0) {
    in(li, si >= 0 ? poly[i].start : P::meet(l, li));
    if (sn <= 0) in(l, sn == 0 ? poly[j].start : P::meet(li, l));
  }
  if (si < 0 || sn < 0) {
    out(li, si <= 0 ? poly[i].start : P::meet(lf, li));
    if (sn >= 0) out(lf, sn == 0 ? poly[j].start : P::meet(li, lf));
  }
}
// split_edge's share written where a prefix sum of split_counts places it: `at`, that sum over the
// edges before i, gives the inside part's position (low 16 bits) and the outside part's (high);
// each part's edges past `cap` are not written (only float arithmetic can make them).
template <class P>
TV_HD inline void split_edge_placed(const PEdge<P>* poly, uint32_t n, const typename P::Line& l,
                                    const typename P::Line& lf, const Sides& sg, uint32_t i, uint32_t at,
                                    PEdge<P>* in, PEdge<P>* out, uint32_t cap) {
  uint32_t ia = at & 0xffffu, oa = at >> 16;
  split_edge<P>(
      poly, n, l, lf, sg, i,
      [&](const typename P::Line& e, const typename P::V& v) {
        if (ia < cap) in[ia] = {e, v};
        ++ia;
      },
      [&](const typename P::Line& e, const typename P::V& v) {
        if (oa < cap) out[oa] = {e, v};
        ++oa;
      });
}
// How many edges split_edge hands to `in` (low 16 bits) and to `out` (high 16 bits).
TV_HD inline uint32_t split_counts(uint32_t n, const Sides& sg, uint32_t i) {
  const uint32_t j = i + 1 == n ? 0 : i + 1;
  const int si = sg.at(i), sn = sg.at(j);
  const uint32_t in = si > 0 || sn > 0 ? 1u + (sn <= 0) : 0u, out = si < 0 || sn < 0 ? 1u + (sn >= 0) : 0u;
  return in | out << 16;
}

// split's pass with the sides given.
template <class P>
TV_HD inline void split_sides(const PEdge<P>* poly, uint32_t n, const typename P::Line& l, const Sides& sg,
                              PolyOut<P>& in, PolyOut<P>& out) {
  const typename P::Line lf = l.flipped();
  for (uint32_t i = 0; i < n; ++i)
    split_edge<P>(
        poly, n, l, lf, sg, i, [&](const typename P::Line& e, const typename P::V& v) { in.push(e, v); },
        [&](const typename P::Line& e, const typename P::V& v) { out.push(e, v); });
}

// Splits a polygon that `l` crosses into inside = poly ∩ {l >= 0} and outside = poly ∩
// {l <= 0}, in one pass over the vertices (signs: one positive block, one negative block).
// Float: the signs made convex first (Sides::regularize; `regularized` says whether they
// changed). `sides`: survives()'s, of the same vertices against the same line.
template <class P>
TV_HD inline void split(const PEdge<P>* poly, uint32_t n, const typename P::Line& l, PolyOut<P>& in, PolyOut<P>& out,
                        bool* regularized = nullptr, const Sides* sides = nullptr) {
  if (n <= kSideCap) {
    Sides sg = sides ? *sides : sides_of<P>(poly, n, l);
    if constexpr (!P::kExact) {
      const bool changed = sg.regularize(n);
      if (regularized) *regularized = changed;
    }
    split_sides<P>(poly, n, l, sg, in, out);
    return;
  }
  // More vertices than the masks hold (exact pieces of long chains): each side computed twice.
  const typename P::Line lf = l.flipped();
  const int s0 = P::side(l, poly[0].start);
  int si = s0;
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t j = i + 1 == n ? 0 : i + 1;
    const int sn = j == 0 ? s0 : P::side(l, poly[j].start);
    const typename P::Line& li = poly[i].line;
    if (si > 0 || sn > 0) {
      in.push(li, si >= 0 ? poly[i].start : P::meet(l, li));
      if (sn <= 0) in.push(l, sn == 0 ? poly[j].start : P::meet(li, l));
    }
    if (si < 0 || sn < 0) {
      out.push(li, si <= 0 ? poly[i].start : P::meet(lf, li));
      if (sn >= 0) out.push(lf, sn == 0 ? poly[j].start : P::meet(li, lf));
    }
    si = sn;
  }
}

// An occluder as the occlusion loop streams it: what the cheap tests need (32 bytes); the
// full triangle is read only past them.
struct OccRec {
  Rect bbox;
  uint32_t z_min, id, tri, pad;
};

// An occluder as the hybrid's detector sweeps it (hybrid.cu det_positions): what a member's step
// and may_cross read, in one 32-byte load, and the triangle to read past them.
struct alignas(16) DetRec {
  uint32_t z_min, z_max, id, tri;
  Rect bbox;
};

// SVGPU §3.3: the piece is hidden if an original opaque triangle nearer at its interior
// point q (the centroid of its first three vertices; qx, qy its doubles) contains that point;
// equal depth: the earlier-submitted triangle stays in front. Occluders come nearest first
// (by z_min); the first hit ends the search, and an occluder whose nearest point is behind
// the piece's farthest ends it too. `tests` counts exact containment tests (the occluder's
// bounding box, widened by a margin far above the error of the test point's doubles, rejects
// first).
//
// One occluder's verdict, independent of the others (so a team can judge many at once and
// keep the sequential loop's result: the first that ends the search decides).
enum class OccVerdict { skip, tested, hides, ends };

template <class P>
TV_HD inline OccVerdict occluder_verdict(const typename P::R& q, double qx, double qy, const TileTri<P>& tt,
                                         const TileTri<P>* tris, const OccRec& o) {
  if (o.z_min > tt.z_max) return OccVerdict::ends;
  if (o.id == tt.id) return OccVerdict::skip;
  if (qx < o.bbox.x0 - 1.0 || qx > o.bbox.x1 + 1.0 || qy < o.bbox.y0 - 1.0 || qy > o.bbox.y1 + 1.0)
    return OccVerdict::skip;
  const TileTri<P>& u = tris[o.tri];
  if (!P::in_half(u.edge[0], q) || !P::in_half(u.edge[1], q) || !P::in_half(u.edge[2], q)) return OccVerdict::tested;
  const int order = P::depth(u.plane, tt.plane, q);
  return order < 0 || (order == 0 && u.id < tt.id) ? OccVerdict::hides : OccVerdict::tested;
}

template <class P>
TV_HD inline bool covers(const PEdge<P>* poly, uint32_t n, Pt s) {
  for (uint32_t i = 0; i < n; ++i)
    if (!P::in_half(poly[i].line, s)) return false;
  return n > 0;
}

// Smallest closed integer rectangle holding the polygon.
template <class P>
TV_HD inline Rect bounding_box(const PEdge<P>* poly, uint32_t n) {
  int64_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  for (uint32_t i = 0; i < n; ++i) {
    int64_t fx, fy, cx, cy;
    P::bounds(poly[i].start, fx, fy, cx, cy);
    if (i == 0 || fx < x0) x0 = fx;
    if (i == 0 || fy < y0) y0 = fy;
    if (i == 0 || cx > x1) x1 = cx;
    if (i == 0 || cy > y1) y1 = cy;
  }
  return {int32_t(x0), int32_t(y0), int32_t(x1), int32_t(y1)};
}

template <class P>
TV_HD inline double doubled_area(const PEdge<P>* poly, uint32_t n) {
  double sum = 0;
  for (uint32_t i = 1; i + 1 < n; ++i) sum = dadd(sum, P::area_term(poly[0].start, poly[i].start, poly[i + 1].start));
  return sum;
}

// ---- float areas that never lie about sign ----------------------------------------------------
//
// A float piece's vertices are meets of its lines rounded to float. On a sliver the rounding
// can move a vertex across the piece's opposite side: the vertex chain folds over, and the
// shoelace of the float vertices comes out negative (or positive for a region that is empty).
// The lines themselves are exact (integer a, b and an integer anchor, each exact in float), so
// the region a float piece bounds, the intersection of its half-planes within its triangle's
// tile polygon, has an exact area. The float area is used where its sign is proven: the float
// vertices (as doubles) form a convex polygon in positive order, every turn and every fan
// triangle from vertex 0 certified positive by Shewchuk's orient2d filter. Elsewhere the area is
// that of the exact region (exact clipping, ExactP), which is never negative.

// Shewchuk's ccwerrboundA, (3 + 16 eps) eps with eps = 2^-53: |det| above it times the sum of
// the magnitudes of its two products has the sign of the exact determinant of double inputs.
inline constexpr double kOrientErrBound = 3.3306690738754716e-16;

TV_HD inline bool orient_positive(double ax, double ay, double bx, double by, double cx, double cy) {
  const double t1 = (bx - ax) * (cy - ay), t2 = (by - ay) * (cx - ax);
  const double det = t1 - t2;
  return det > kOrientErrBound * (fabs(t1) + fabs(t2));
}

// Whether the float vertices are proven to form a convex polygon in positive order (repeated
// vertices, whose area terms are exactly 0, are passed over). Then every fan term of
// doubled_area is positive, and so is the float area. No local arrays: it runs in the occlusion
// kernels, for every visible float piece.
TV_HD inline bool certified_convex(const PEdge<FloatP>* poly, uint32_t n) {
  if (n < 3 || n > kSideCap) return false;
  auto same = [&](uint32_t i, uint32_t j) {
    return poly[i].start.x == poly[j].start.x && poly[i].start.y == poly[j].start.y;
  };
  uint32_t distinct = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t h0 = i == 0 ? n - 1 : i - 1;
    if (same(i, h0)) continue;  // a repeat of the vertex before it
    ++distinct;
    uint32_t j = i + 1 == n ? 0 : i + 1, steps = 0;
    while (same(j, i) && ++steps < n) j = j + 1 == n ? 0 : j + 1;
    const auto& A = poly[h0].start;
    const auto& B = poly[i].start;
    const auto& C = poly[j].start;
    if (same(j, h0) || same(j, i)) return false;  // fewer than 3 distinct vertices
    if (!orient_positive(A.x, A.y, B.x, B.y, C.x, C.y)) return false;
  }
  if (distinct < 3) return false;
  const auto& O = poly[0].start;
  for (uint32_t i = 1; i + 1 < n; ++i) {
    if (same(i, i + 1) || same(i, 0) || same(i + 1, 0)) continue;  // an area term of exactly 0
    if (!orient_positive(O.x, O.y, poly[i].start.x, poly[i].start.y, poly[i + 1].start.x, poly[i + 1].start.y))
      return false;
  }
  return true;
}

// The exact line a float line stands for: a (x - ox) + b (y - oy) with integer a, b, ox, oy.
TV_HD inline exact::Line exact_line(const approx::Line& l) {
  const int64_t a = int64_t(l.a), b = int64_t(l.b);
  return {a, b, -(a * int64_t(l.ox) + b * int64_t(l.oy))};
}

// The doubled area of the region a float piece bounds: its triangle's tile polygon (exact)
// clipped by each of the piece's lines, exactly; >= 0 (a convex polygon's fan terms are >= 0
// and keep their sign when rounded). `overflow`: the region outgrew the buffers (a piece of
// more than kRegionCap - kTileCap lines), nothing computed.
inline constexpr uint32_t kRegionCap = 24;
template <class FP>  // FloatP
#if defined(__CUDACC__)
__noinline__
#endif
TV_HD double exact_region_doubled_area(const PEdge<FP>* poly, uint32_t n, const TileTri<FP>& t, const Rect& r,
                                       bool& overflow) {
  if (n + kTileCap > kRegionCap) {
    overflow = true;
    return 0;
  }
  const TileTri<ExactP> xt = make_tile_tri<ExactP>(t.v[0], t.v[1], t.v[2], t.id, t.opaque != 0);
  PEdge<ExactP> a[kRegionCap], b[kRegionCap];
  bool unused = false;
  uint32_t m = tile_polygon<ExactP>(xt, r, a, unused);
  PEdge<ExactP>* cur = a;
  PEdge<ExactP>* next = b;
  for (uint32_t i = 0; i < n && m > 0; ++i) {
    const exact::Line l = exact_line(poly[i].line);
    bool pos, neg;
    line_sides<ExactP>(cur, m, l, pos, neg);
    if (!neg) continue;
    if (!pos) return 0;  // the region is empty (at most a segment)
    PolyOut<ExactP> in{next, 0, kRegionCap, false}, out{nullptr, 0, 0, false};
    split<ExactP>(cur, m, l, in, out);
    if (in.overflow) {
      overflow = true;
      return 0;
    }
    m = in.n;
    PEdge<ExactP>* s = cur;
    cur = next;
    next = s;
  }
  return m >= 3 ? doubled_area<ExactP>(cur, m) : 0.0;
}

}  // namespace tilevis::cuda
