#include "visibility/svgpu.h"

#include <algorithm>

namespace tilevis::vis::svgpu {
namespace {

using geom::ImplicitPoint;
using geom::Int128;

// sign((c - a) · d) for an implicit point c on the line through a with direction d:
// |x - a.x w| <= 2^72 + 2^23 · 2^49 = 2^73, times |d| <= 2^24, two terms: < 2^98 (Int128).
int along(const ImplicitPoint& c, const geom::Vertex& a, int64_t dx, int64_t dy) {
  const Int128 v = (c.x - Int128{a.x} * c.w) * dx + (c.y - Int128{a.y} * c.w) * dy;
  return (v > 0) - (v < 0);
}

}  // namespace

Triangle Triangle::from(const geom::Vertex& a, const geom::Vertex& b, const geom::Vertex& c) {
  Triangle t;
  t.tri = geom::Triangle{{a, b, c}};
  t.edges = geom::TriangleEdges::from(t.tri);
  t.plane = geom::DepthPlane::from(t.tri);
  t.bbox = {std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y})};
  t.z_min = std::min({a.z, b.z, c.z});
  t.z_max = std::max({a.z, b.z, c.z});
  return t;
}

Edge Edge::from(const geom::Vertex& a, const geom::Vertex& b) {
  return {a, b, geom::Line::through(a.xy(), b.xy()), std::min(a.z, b.z), std::max(a.z, b.z),
          {std::min(a.x, b.x), std::min(a.y, b.y), std::max(a.x, b.x), std::max(a.y, b.y)}};
}

bool shares_edge(const Edge& e, const geom::Triangle& t) {
  for (int i = 0; i < 3; ++i) {
    const geom::Vertex &p = t.v[i], &q = t.v[(i + 1) % 3];
    if ((p == e.a && q == e.b) || (p == e.b && q == e.a)) return true;
  }
  return false;
}

bool survives(const geom::ConvexPolygon& piece, const Triangle& t, const Edge& e) {
  if (geom::classify(piece, e.line) != geom::LineRelation::crosses) return false;  // test 1
  if (!geom::segment_overlaps(piece, e.a.xy(), e.b.xy())) return false;            // test 2
  // Test 3: depth is affine along the segment, so the two ends of its part inside the piece decide.
  ImplicitPoint first, second;
  if (!geom::chord(piece, e.line, first, second)) return false;
  const int64_t dx = int64_t{e.b.x} - e.a.x, dy = int64_t{e.b.y} - e.a.y;
  // sign(z_triangle - z_edge) at each end of the overlap; > 0: the edge is nearer there.
  const int s1 = along(first, e.a, dx, dy) < 0 ? geom::depth_order(t.plane, e.a.xy(), e.a.z)
                                               : geom::depth_order_edge(t.plane, e.a, e.b, first);
  if (s1 > 0) return true;
  const int s2 = along(second, e.b, dx, dy) > 0 ? geom::depth_order(t.plane, e.b.xy(), e.b.z)
                                                : geom::depth_order_edge(t.plane, e.a, e.b, second);
  return s2 > 0 || (s1 == 0 && s2 == 0);
}

bool occludes(const Triangle& u, uint32_t u_id, const Triangle& t, uint32_t t_id, const geom::RationalPoint& q) {
  if (!u.edges.contains(q)) return false;
  const int order = geom::depth_order(u.plane, t.plane, q);
  return order < 0 || (order == 0 && u_id < t_id);
}

bool opposite_neighbours(const geom::Triangle& t, const geom::Triangle& u) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (t.v[i] == u.v[(j + 1) % 3] && t.v[(i + 1) % 3] == u.v[j]) return true;
  return false;
}

bool planes_cross(const geom::ConvexPolygon& region, const Triangle& t, const Triangle& u) {
  if (!may_cross(t, u)) return false;  // one side everywhere (or touching), or apart on screen
  geom::ConvexPolygon overlap = region;
  for (const geom::Line& l : u.edges.edge) {
    overlap = geom::clip(overlap, l);
    if (overlap.empty()) return false;
  }
  bool nearer = false, farther = false;
  for (const auto& e : overlap.edges()) {
    const int order = geom::depth_order(u.plane, t.plane, e.start);
    nearer = nearer || order < 0;
    farther = farther || order > 0;
  }
  return nearer && farther;
}

}  // namespace tilevis::vis::svgpu
