// Exact 2-D predicates on snapped points, on implicit points (intersections of two lines
// through snapped points) and on rational interior points. No epsilon: every sign is the
// sign of an exact integer; the floating-point filters below only short-cut a sign that the
// error bound proves equal to the exact one.
//
// Bounds use g = 2^23 (|x|,|y| <= g for every snapped point, sample or tile corner) and
// Delta = 2g = 2^24 (any coordinate difference). README.md tabulates them.
//
// Orientation: orient2d(a,b,c) > 0 when a,b,c turn counter-clockwise in (x,y) taken as
// plain numbers; since screen y grows downward this looks clockwise on screen. Polygons keep
// their lines in that positive order, interior on the positive side of every line.
#pragma once

#include <array>
#include <cstdint>
#include <cstdlib>

#include "geom/fixed.h"
#include "geom/wide_int.h"

namespace tilevis::geom {

constexpr int sign_of(int64_t v) { return (v > 0) - (v < 0); }
constexpr int sign_of(Int128 v) { return (v > 0) - (v < 0); }

// (b-a) x (c-a). |differences| <= 2^24, |products| <= 2^48, |result| <= 2^49: int64.
constexpr int64_t orient2d(Point a, Point b, Point c) {
  return (int64_t{b.x} - a.x) * (int64_t{c.y} - a.y) - (int64_t{b.y} - a.y) * (int64_t{c.x} - a.x);
}

// Signed doubled area of a triangle (orient2d of its vertices), |.| <= 2^49.
constexpr int64_t doubled_area(Point a, Point b, Point c) { return orient2d(a, b, c); }
constexpr int64_t doubled_area(const Triangle& t) {
  return orient2d(t.v[0].xy(), t.v[1].xy(), t.v[2].xy());
}

// The line a*x + b*y + c = 0 through snapped p and q, oriented so that eval(r) equals
// orient2d(p, q, r): positive on the interior side of a positively ordered polygon.
// |a|,|b| <= 2^24; |c| = |p.x q.y - p.y q.x| <= 2 g^2 = 2^47.
struct Line {
  int64_t a = 0, b = 0, c = 0;

  static constexpr Line through(Point p, Point q) {
    return {int64_t{p.y} - q.y, int64_t{q.x} - p.x, int64_t{p.x} * q.y - int64_t{p.y} * q.x};
  }

  constexpr Line flipped() const { return {-a, -b, -c}; }

  // |a x| + |b y| + |c| <= 2^47 + 2^47 + 2^47 < 2^49: int64, partial sums included.
  constexpr int64_t eval(Point s) const { return a * s.x + b * s.y + c; }

  // The tie rule (README.md, "Tie rule"): a point exactly on the line belongs to the
  // positive side iff the point nudged by (eps, eps^2) enters it, i.e. the inward normal
  // (a,b) is lexicographically positive. For triangle edges this is D3D's top-left rule:
  // a > 0 is a left edge (interior to its right), a == 0 && b > 0 a top edge (interior below).
  // Exactly one of a line and its flip owns the boundary, since (a,b) != (0,0).
  constexpr bool owns_boundary() const { return a > 0 || (a == 0 && b > 0); }

  friend constexpr bool operator==(const Line&, const Line&) = default;
};

// Closed/open half-plane membership of a snapped point under the tie rule.
constexpr bool in_half_plane(const Line& l, Point s) {
  const int64_t e = l.eval(s);
  return e > 0 || (e == 0 && l.owns_boundary());
}

// Homogeneous point (x : y : w), w > 0: the intersection of two lines through snapped points.
// |w| <= 2 Delta^2 = 2^49, |x|,|y| <= 2 * 2^24 * 2^47 = 2^72 (Int128). A snapped point is
// stored reduced as (x : y : 1); predicates depend only on the rational point, never on
// which representation of it is held.
struct ImplicitPoint {
  Int128 x = 0, y = 0;
  int64_t w = 0;  // 0 only for the "no intersection" result of intersect()

  static constexpr ImplicitPoint from(Point p) { return {p.x, p.y, 1}; }
  constexpr bool valid() const { return w != 0; }
};

// l1 x l2 (cross product of coefficient vectors), normalised to w > 0; w == 0 when parallel.
// w = a1 b2 - a2 b1: 2^48 + 2^48 = 2^49. x = b1 c2 - b2 c1: 2^71 + 2^71 = 2^72. int64 x int64
// products are taken in Int128 (one widening multiply each).
constexpr ImplicitPoint intersect(const Line& l1, const Line& l2) {
  Int128 x = Int128{l1.b} * l2.c - Int128{l2.b} * l1.c;
  Int128 y = Int128{l1.c} * l2.a - Int128{l2.c} * l1.a;
  int64_t w = l1.a * l2.b - l2.a * l1.b;
  if (w < 0) {
    x = -x;
    y = -y;
    w = -w;
  }
  return {x, y, w};
}

// sign(a x + b y + c w) = side of the rational point (x/w, y/w), w > 0.
// |a x| <= 2^24 * 2^72 = 2^96, |b y| <= 2^96, |c w| <= 2^47 * 2^49 = 2^96: sum < 2^98, Int128.
inline int side(const Line& l, const ImplicitPoint& p) {
  const Int128 s = Int128{l.a} * p.x + Int128{l.b} * p.y + Int128{l.c} * p.w;
  return sign_of(s);
}

inline bool in_half_plane(const Line& l, const ImplicitPoint& p) {
  const int s = side(l, p);
  return s > 0 || (s == 0 && l.owns_boundary());
}

// Relative error allowance of every floating-point filter: 2^-47 = 64 u (u = 2^-53). Each
// filter's own derivation needs at most 8 u (conversions, products and sums of <= 6 terms,
// all of integers, so no underflow), see the comment at each filter.
inline constexpr double kFilterRelErr = 0x1p-47;

// Rational point (x : y : w), w > 0, used as the interior test point of a polygon piece
// (SVGPU §3.3 centroid test). For the centroid of three implicit vertices
// |x|,|y| <= 3 * 2^72 * 2^49 * 2^49 < 2^172 and w = 3 w0 w1 w2 <= 3 * 2^147 < 2^149: Int192.
// fx, fy, fw are the correctly rounded doubles of x, y, w for the filters.
struct RationalPoint {
  Int192 x{}, y{}, w{};
  double fx = 0, fy = 0, fw = 0;

  static RationalPoint from(const ImplicitPoint& p);
  static RationalPoint from(Point p) { return from(ImplicitPoint::from(p)); }
};

// Centroid (p0 + p1 + p2) / 3: the interior point of a strictly convex polygon whose first
// three vertices are p0, p1, p2 (they are never collinear there).
RationalPoint centroid(const ImplicitPoint& p0, const ImplicitPoint& p1, const ImplicitPoint& p2);

namespace detail {
int side_exact(const Line& l, const RationalPoint& p);
}

// sign(a x + b y + c w). Exact value: |a x| <= 2^24 * 2^172, |c w| <= 2^47 * 2^149, sum
// < 2^198: Int256. Filter: a, b, c are exact doubles (<= 47 bits); each of the 3 products
// carries <= 2u (conversion of x,y,w + product rounding), 2 additions add u each relative to
// S = sum |terms|: error <= 4u S (1 + O(u)), and the computed S is >= S (1 - 3u), so
// |f| > 2^-47 S_computed proves sign(f) exact.
inline int side(const Line& l, const RationalPoint& p) {
  const double ta = static_cast<double>(l.a) * p.fx;
  const double tb = static_cast<double>(l.b) * p.fy;
  const double tc = static_cast<double>(l.c) * p.fw;
  const double f = ta + tb + tc;
  const double bound = (std::fabs(ta) + std::fabs(tb) + std::fabs(tc)) * kFilterRelErr;
  if (f > bound) return 1;
  if (f < -bound) return -1;
  return detail::side_exact(l, p);
}

inline bool in_half_plane(const Line& l, const RationalPoint& p) {
  const int s = side(l, p);
  return s > 0 || (s == 0 && l.owns_boundary());
}

// The three edge lines of a snapped triangle in positive order (interior positive), for
// sample coverage and for the occluder side of the SVGPU §3.3 test. Lines match
// ConvexPolygon::from_triangle exactly, so both give the same coverage.
struct TriangleEdges {
  std::array<Line, 3> edge{};
  bool valid = false;  // false for a zero-area triangle, which covers nothing

  static constexpr TriangleEdges from(Point p0, Point p1, Point p2) {
    const int64_t area = orient2d(p0, p1, p2);
    if (area == 0) return {};
    if (area > 0) return {{Line::through(p0, p1), Line::through(p1, p2), Line::through(p2, p0)}, true};
    return {{Line::through(p0, p2), Line::through(p2, p1), Line::through(p1, p0)}, true};
  }
  static constexpr TriangleEdges from(const Triangle& t) {
    return from(t.v[0].xy(), t.v[1].xy(), t.v[2].xy());
  }

  // Sample coverage under the tie rule (D3D top-left rule).
  constexpr bool covers(Point s) const {
    return valid && in_half_plane(edge[0], s) && in_half_plane(edge[1], s) && in_half_plane(edge[2], s);
  }
  bool contains(const ImplicitPoint& p) const {
    return valid && in_half_plane(edge[0], p) && in_half_plane(edge[1], p) && in_half_plane(edge[2], p);
  }
  bool contains(const RationalPoint& p) const {
    return valid && in_half_plane(edge[0], p) && in_half_plane(edge[1], p) && in_half_plane(edge[2], p);
  }
};

}  // namespace tilevis::geom
