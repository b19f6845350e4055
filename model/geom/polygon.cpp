#include "geom/polygon.h"

#include <algorithm>

namespace tilevis::geom {

ConvexPolygon ConvexPolygon::from_triangle(Point p0, Point p1, Point p2) {
  ConvexPolygon poly;
  const int64_t area = orient2d(p0, p1, p2);
  if (area == 0) return poly;
  if (area < 0) std::swap(p1, p2);
  poly.m_edges.reserve(4);  // one clip adds at most one edge
  poly.push_edge(Line::through(p0, p1), ImplicitPoint::from(p0));
  poly.push_edge(Line::through(p1, p2), ImplicitPoint::from(p1));
  poly.push_edge(Line::through(p2, p0), ImplicitPoint::from(p2));
  return poly;
}

ConvexPolygon ConvexPolygon::from_rect(const Rect& r) {
  ConvexPolygon poly;
  if (r.x0 >= r.x1 || r.y0 >= r.y1) return poly;
  const Point c[4] = {{r.x0, r.y0}, {r.x1, r.y0}, {r.x1, r.y1}, {r.x0, r.y1}};
  poly.m_edges.reserve(5);
  for (int i = 0; i < 4; ++i) poly.push_edge(Line::through(c[i], c[(i + 1) % 4]), ImplicitPoint::from(c[i]));
  return poly;
}

std::optional<ConvexPolygon> ConvexPolygon::from_convex_points(std::span<const Point> pts) {
  const std::size_t n = pts.size();
  if (n < 3) return std::nullopt;
  for (std::size_t i = 0; i < n; ++i)
    if (orient2d(pts[i], pts[(i + 1) % n], pts[(i + 2) % n]) <= 0) return std::nullopt;
  for (std::size_t i = 1; i + 1 < n; ++i)  // winds exactly once
    if (orient2d(pts[0], pts[i], pts[i + 1]) <= 0) return std::nullopt;
  ConvexPolygon poly;
  poly.m_edges.reserve(n + 1);
  for (std::size_t i = 0; i < n; ++i) poly.push_edge(Line::through(pts[i], pts[(i + 1) % n]), ImplicitPoint::from(pts[i]));
  return poly;
}

std::optional<ConvexPolygon> ConvexPolygon::from_lines(std::span<const Line> lines) {
  const std::size_t n = lines.size();
  if (n < 3) return std::nullopt;
  ConvexPolygon poly;
  poly.m_edges.reserve(n + 1);
  for (std::size_t i = 0; i < n; ++i) {
    const Line& prev = lines[(i + n - 1) % n];
    const Line& cur = lines[i];
    if (prev.a * cur.b - cur.a * prev.b <= 0) return std::nullopt;  // must turn left
    poly.push_edge(cur, intersect(prev, cur));
  }
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      if (j != i && j != (i + n - 1) % n && side(lines[j], poly.vertex(i)) <= 0) return std::nullopt;
  return poly;
}

// det[v0; vi; vj] with rows (x, y, w): see the bound in polygon.h (Int256).
void doubled_area_terms(const ConvexPolygon& poly, std::vector<AreaTerm>& out) {
  out.clear();
  const std::size_t n = poly.size();
  if (n < 3) return;
  const ImplicitPoint& v0 = poly.vertex(0);
  const Int256 x0 = wide<4>(v0.x), y0 = wide<4>(v0.y), w0 = wide<4>(v0.w);
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const ImplicitPoint& a = poly.vertex(i);
    const ImplicitPoint& b = poly.vertex(i + 1);
    const Int256 xa = wide<4>(a.x), ya = wide<4>(a.y), wa = wide<4>(a.w);
    const Int256 xb = wide<4>(b.x), yb = wide<4>(b.y), wb = wide<4>(b.w);
    AreaTerm t;
    t.num = x0 * (ya * wb - yb * wa) - y0 * (xa * wb - xb * wa) + w0 * (xa * yb - xb * ya);
    t.den = wide<3>(v0.w) * wide<3>(Int128{a.w} * b.w);
    out.push_back(t);
  }
}

double doubled_area(const ConvexPolygon& poly) {
  std::vector<AreaTerm> terms;
  doubled_area_terms(poly, terms);
  double sum = 0;
  for (const auto& t : terms) sum += t.num.to_double() / t.den.to_double();
  return sum;
}

namespace {
template <class T>  // Int128 or int64_t
T floor_div(T n, int64_t d) {  // d > 0
  T q = n / d;
  if (n % d < 0) q -= 1;
  return q;
}
template <class T>
T ceil_div(T n, int64_t d) { return -floor_div(-n, d); }
}  // namespace

Rect bounding_box(const ConvexPolygon& poly) {
  Int128 x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool first = true;
  for (const auto& e : poly.edges()) {
    const ImplicitPoint& v = e.start;
    const Int128 fx = floor_div(v.x, v.w), fy = floor_div(v.y, v.w);
    const Int128 cx = ceil_div(v.x, v.w), cy = ceil_div(v.y, v.w);
    if (first || fx < x0) x0 = fx;
    if (first || fy < y0) y0 = fy;
    if (first || cx > x1) x1 = cx;
    if (first || cy > y1) y1 = cy;
    first = false;
  }
  // Vertices of a polygon built from in-band points lie in their convex hull: int32.
  return {static_cast<int32_t>(x0), static_cast<int32_t>(y0), static_cast<int32_t>(x1), static_cast<int32_t>(y1)};
}

PixelSpan covered_span(const ConvexPolygon& poly, int32_t sx, int32_t sy, int32_t sb, int64_t px0, int64_t px1) {
  if (poly.empty()) return {};
  int64_t lo = px0, hi = px1;
  for (const auto& e : poly.edges()) {
    const Line& l = e.line;
    const int64_t a = l.a * (int64_t{1} << sb);
    const int64_t k = int64_t{l.owns_boundary() ? 0 : 1} - (l.a * sx + l.b * sy + l.c);  // a px >= k
    if (a > 0) lo = std::max(lo, ceil_div(k, a));
    else if (a < 0) hi = std::min(hi, floor_div(-k, -a));
    else if (k > 0) return {};
    if (lo > hi) return {};
  }
  return {lo, hi};
}

}  // namespace tilevis::geom
