// Exact triangle/tile and segment/tile overlap for binning (tiling engine).
//
// Choice: overlap means the interiors intersect (positive-area intersection for triangles,
// a segment point strictly inside the rectangle for edges); touching along a border or at a
// corner does not count. This never misses a sample: a triangle covers s iff s + (eps, eps^2)
// is in its interior (tie rule, predicates.h), and a tile owns s iff s + (eps, eps^2) is in
// the tile's interior, so a covered sample of the tile puts that point in both interiors.
// A silhouette segment lying on a tile border changes nothing inside the tile, whose pieces
// are already clipped to that border.
#pragma once

#include <algorithm>

#include "geom/fixed.h"
#include "geom/predicates.h"

namespace tilevis::geom {

namespace detail {
// max and min over the rectangle's corners of l.eval: the corner picked by the sign of each
// coefficient; |value| < 2^49 (Line::eval).
constexpr int64_t max_over_rect(const Line& l, const Rect& r) {
  return l.a * (l.a > 0 ? r.x1 : r.x0) + l.b * (l.b > 0 ? r.y1 : r.y0) + l.c;
}
constexpr int64_t min_over_rect(const Line& l, const Rect& r) {
  return l.a * (l.a > 0 ? r.x0 : r.x1) + l.b * (l.b > 0 ? r.y0 : r.y1) + l.c;
}
}  // namespace detail

// Separating axis: the two axes of the rectangle and the three edge normals of the triangle
// (for convex polygons with disjoint interiors some edge line of one of them separates).
// A zero-area triangle has no interior and overlaps nothing.
constexpr bool triangle_overlaps_rect(Point p0, Point p1, Point p2, const Rect& r) {
  const int64_t area = orient2d(p0, p1, p2);
  if (area == 0) return false;
  if (std::max({p0.x, p1.x, p2.x}) <= r.x0 || std::min({p0.x, p1.x, p2.x}) >= r.x1) return false;
  if (std::max({p0.y, p1.y, p2.y}) <= r.y0 || std::min({p0.y, p1.y, p2.y}) >= r.y1) return false;
  const Line e0 = Line::through(p0, p1), e1 = Line::through(p1, p2), e2 = Line::through(p2, p0);
  if (area > 0) {
    return detail::max_over_rect(e0, r) > 0 && detail::max_over_rect(e1, r) > 0 &&
           detail::max_over_rect(e2, r) > 0;
  }
  return detail::min_over_rect(e0, r) < 0 && detail::min_over_rect(e1, r) < 0 &&
         detail::min_over_rect(e2, r) < 0;
}

constexpr bool triangle_overlaps_rect(const Triangle& t, const Rect& r) {
  return triangle_overlaps_rect(t.v[0].xy(), t.v[1].xy(), t.v[2].xy(), r);
}

// Separating axis: the rectangle's axes and ab's line. a == b overlaps nothing.
constexpr bool segment_overlaps_rect(Point a, Point b, const Rect& r) {
  if (a == b) return false;
  if (std::max(a.x, b.x) <= r.x0 || std::min(a.x, b.x) >= r.x1) return false;
  if (std::max(a.y, b.y) <= r.y0 || std::min(a.y, b.y) >= r.y1) return false;
  const Line l = Line::through(a, b);
  return detail::max_over_rect(l, r) > 0 && detail::min_over_rect(l, r) < 0;
}

}  // namespace tilevis::geom
