// Plane-based clipping of convex polygons by lines (SVGPU §3.2.2, after Bernstein & Fussell
// 2009): vertices are classified exactly in/on/out, both sides are kept, new vertices are
// intersections of two original lines.
//
// Canonical edge order (reproduced by the CUDA reference, since the interior test point
// depends on it): a child lists the parent's edges that bound it, in the parent's order,
// with the clip line inserted right after the last of them in cyclic order (the edge whose
// end vertex is on or beyond the line). A side that keeps every parent edge is the parent,
// unchanged. A vertex where the clip line passes exactly through a parent vertex keeps the
// parent's representation of that vertex.
#pragma once

#include "geom/fixed.h"
#include "geom/polygon.h"
#include "geom/predicates.h"

namespace tilevis::geom {

// Where a polygon lies with respect to a line; `inside` / `outside` include touching it
// along an edge or at a vertex (the other side would have zero area).
enum class LineRelation { inside, outside, crosses, empty };

LineRelation classify(const ConvexPolygon& poly, const Line& l);

// inside = poly ∩ {l >= 0}, outside = poly ∩ {l <= 0}; zero-area parts come back empty.
// The outside part's clip line is l.flipped(). inside and outside must be distinct objects,
// neither of them poly (they are cleared before poly is read).
void split(const ConvexPolygon& poly, const Line& l, ConvexPolygon& inside, ConvexPolygon& outside);

struct SplitResult {
  ConvexPolygon inside, outside;
};
inline SplitResult split(const ConvexPolygon& poly, const Line& l) {
  SplitResult r;
  split(poly, l, r.inside, r.outside);
  return r;
}

// poly ∩ {l >= 0} only.
ConvexPolygon clip(const ConvexPolygon& poly, const Line& l);

// poly ∩ r, clipping by r's lines in from_rect order (top, right, bottom, left).
ConvexPolygon clip_to_rect(const ConvexPolygon& poly, const Rect& r);
inline ConvexPolygon triangle_in_rect(const Triangle& t, const Rect& r) {
  return clip_to_rect(ConvexPolygon::from_triangle(t), r);
}

// The chord of line l through the polygon (SVGPU §3.2.1 test 3 crossing points): the two
// vertices split() puts on l in the inside part, `first` where l's edge starts and `second`
// where it ends, in the same representation. false (outputs untouched) unless classify()
// says crosses.
bool chord(const ConvexPolygon& poly, const Line& l, ImplicitPoint& first, ImplicitPoint& second);

// Whether segment ab meets the polygon's interior (zero-area contact excluded): separating
// axis over the polygon's lines and ab's line. A degenerate segment (a == b) never does.
bool segment_overlaps(const ConvexPolygon& poly, Point a, Point b);

}  // namespace tilevis::geom
