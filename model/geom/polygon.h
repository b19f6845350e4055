// Convex polygons in plane-based form (Bernstein & Fussell 2009, as SVGPU §3.2.2 uses it):
// a polygon is its list of supporting lines, each through two snapped points, in positive
// order with the interior on the positive side; vertex i is the intersection of lines i-1
// and i (the vertex is stored with the edge leaving it, as in SVGPU), computed once from the
// original lines and never from other computed vertices, so clipping never compounds error
// and bit bounds never grow with the number of clips.
//
// Invariants: empty, or >= 3 edges, strictly convex (no two consecutive lines parallel, no
// repeated vertex, positive area), every vertex with w > 0.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include "geom/fixed.h"
#include "geom/predicates.h"
#include "geom/wide_int.h"

namespace tilevis::geom {

class ConvexPolygon {
 public:
  struct Edge {
    Line line;
    ImplicitPoint start;  // line(i-1) ∩ line(i)
  };

  ConvexPolygon() = default;

  // Lines p0p1, p1p2, p2p0 when orient2d(p0,p1,p2) > 0, else p0p2, p2p1, p1p0, so vertex 0 is
  // always p0. Zero area gives the empty polygon.
  static ConvexPolygon from_triangle(Point p0, Point p1, Point p2);
  static ConvexPolygon from_triangle(const Triangle& t) {
    return from_triangle(t.v[0].xy(), t.v[1].xy(), t.v[2].xy());
  }
  // Lines in the order y = y0 (screen top), x = x1, y = y1, x = x0; vertex 0 is (x0, y0).
  static ConvexPolygon from_rect(const Rect& r);
  // Vertices of a strictly convex polygon in positive order; nullopt if they are not.
  static std::optional<ConvexPolygon> from_convex_points(std::span<const Point> pts);
  // Lines in positive order; nullopt unless they bound a strictly convex polygon with
  // every line contributing an edge.
  static std::optional<ConvexPolygon> from_lines(std::span<const Line> lines);

  bool empty() const { return m_edges.empty(); }
  std::size_t size() const { return m_edges.size(); }
  const Line& line(std::size_t i) const { return m_edges[i].line; }
  const ImplicitPoint& vertex(std::size_t i) const { return m_edges[i].start; }
  std::span<const Edge> edges() const { return m_edges; }

  // For the clipper: appends an edge without checking the invariants.
  void clear() { m_edges.clear(); }
  void reserve(std::size_t n) { m_edges.reserve(n); }
  void push_edge(const Line& line, const ImplicitPoint& start) { m_edges.push_back({line, start}); }

 private:
  std::vector<Edge> m_edges;
};

// Sample coverage under the tie rule (predicates.h): s is covered iff s + (eps, eps^2) lies
// inside. Coverage depends only on the closed region, so pieces that partition a region
// partition its covered samples (README.md, "Tie rule").
inline bool covers(const ConvexPolygon& poly, Point s) {
  if (poly.empty()) return false;
  for (const auto& e : poly.edges())
    if (!in_half_plane(e.line, s)) return false;
  return true;
}

// The samples of one row that the polygon covers, as a range of pixels: pixel px's sample is
// ((px << sb) + sx, sy), a snapped point. Returns [lo, hi] within [px0, px1] (lo > hi: none),
// exactly the px for which covers(poly, sample) holds, without testing each: a line's
// condition a x + b y + c >= t (t = 0 where it owns its boundary, else 1: the tie rule) is
// A px >= t - B with A = a 2^sb, B = a sx + b sy + c, one exact integer bound on px (convexity:
// the covered pixels of a row are one range). |A px| = |a (px << sb)| <= 2^47 and |B| < 2^49
// (predicates.h's bounds): int64.
struct PixelSpan {
  int64_t lo = 0, hi = -1;
};
PixelSpan covered_span(const ConvexPolygon& poly, int32_t sx, int32_t sy, int32_t sb, int64_t px0, int64_t px1);

inline bool contains(const ConvexPolygon& poly, const RationalPoint& p) {
  if (poly.empty()) return false;
  for (const auto& e : poly.edges())
    if (!in_half_plane(e.line, p)) return false;
  return true;
}

// SVGPU §3.3 interior test point: the centroid of vertices 0, 1, 2. Strictly interior since
// the polygon is strictly convex. Depends on the canonical edge order (clip.h), which the
// CUDA reference reproduces. Precondition: !poly.empty().
inline RationalPoint interior_point(const ConvexPolygon& poly) {
  return centroid(poly.vertex(0), poly.vertex(1), poly.vertex(2));
}

// Exact doubled area as a sum of fan triangles (v0, vi, vi+1), i = 1..n-2, each the positive
// rational num / den with num = det[v0; vi; vi+1] (rows x, y, w) and den = w0 wi wi+1:
// |x (y w - y w)| <= 2^72 * 2^122 = 2^194, three such terms < 2^196 (Int256);
// den <= 2^147 (Int192). The polygon's doubled area is exactly the sum of its terms.
struct AreaTerm {
  Int256 num{};
  Int192 den{};
};
void doubled_area_terms(const ConvexPolygon& poly, std::vector<AreaTerm>& out);

// The doubled area in double: terms are positive, each rounded within 3u, so the relative
// error is below (n + 2) u.
double doubled_area(const ConvexPolygon& poly);

// Smallest integer rectangle [x0, x1] x [y0, y1] (closed) containing the closed polygon.
// Precondition: !poly.empty().
Rect bounding_box(const ConvexPolygon& poly);

}  // namespace tilevis::geom
