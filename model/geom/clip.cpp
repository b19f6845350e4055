#include "geom/clip.h"

#include <array>
#include <utility>

namespace tilevis::geom {
namespace {

// Exact side of every vertex; small polygons (the common case) need no allocation.
class VertexSides {
 public:
  VertexSides(const ConvexPolygon& poly, const Line& l) : m_n(poly.size()) {
    if (m_n > m_inline.size()) {
      m_heap.resize(m_n);
      m_data = m_heap.data();
    } else {
      m_data = m_inline.data();
    }
    for (std::size_t i = 0; i < m_n; ++i) {
      const int s = side(l, poly.vertex(i));
      m_data[i] = static_cast<int8_t>(s);
      m_any_pos |= s > 0;
      m_any_neg |= s < 0;
    }
  }
  int operator[](std::size_t i) const { return m_data[i]; }
  bool any_positive() const { return m_any_pos; }
  bool any_negative() const { return m_any_neg; }

 private:
  std::size_t m_n;
  std::array<int8_t, 32> m_inline{};
  std::vector<int8_t> m_heap;
  int8_t* m_data = nullptr;
  bool m_any_pos = false, m_any_neg = false;
};

// One side (sigma = +1: l >= 0, sigma = -1: l <= 0) of a polygon that l crosses. Signs around
// a strictly convex polygon form one block > 0, at most one 0, one block < 0, at most one 0:
// the kept edges are those with a strictly positive (times sigma) end, the clip line follows
// the unique edge leaving the positive block.
void emit_side(const ConvexPolygon& poly, const VertexSides& s, const Line& l, int sigma, ConvexPolygon& out) {
  const std::size_t n = poly.size();
  const Line clip_line = sigma > 0 ? l : l.flipped();
  out.clear();
  out.reserve(n + 1);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t next = i + 1 == n ? 0 : i + 1;
    const int si = sigma * s[i];
    const int sn = sigma * s[next];
    if (si <= 0 && sn <= 0) continue;
    const Line& li = poly.line(i);
    // intersect() is sign-normalised, so l and its flip give the same representation.
    out.push_edge(li, si >= 0 ? poly.vertex(i) : intersect(clip_line, li));
    if (sn <= 0) out.push_edge(clip_line, sn == 0 ? poly.vertex(next) : intersect(li, clip_line));
  }
}

}  // namespace

LineRelation classify(const ConvexPolygon& poly, const Line& l) {
  if (poly.empty()) return LineRelation::empty;
  const VertexSides s(poly, l);
  if (!s.any_negative()) return LineRelation::inside;
  if (!s.any_positive()) return LineRelation::outside;
  return LineRelation::crosses;
}

void split(const ConvexPolygon& poly, const Line& l, ConvexPolygon& inside, ConvexPolygon& outside) {
  if (poly.empty()) {
    inside.clear();
    outside.clear();
    return;
  }
  const VertexSides s(poly, l);
  if (!s.any_negative()) {
    inside = poly;
    outside.clear();
    return;
  }
  if (!s.any_positive()) {
    outside = poly;
    inside.clear();
    return;
  }
  emit_side(poly, s, l, 1, inside);
  emit_side(poly, s, l, -1, outside);
}

ConvexPolygon clip(const ConvexPolygon& poly, const Line& l) {
  if (poly.empty()) return {};
  const VertexSides s(poly, l);
  if (!s.any_negative()) return poly;
  if (!s.any_positive()) return {};
  ConvexPolygon out;
  emit_side(poly, s, l, 1, out);
  return out;
}

ConvexPolygon clip_to_rect(const ConvexPolygon& poly, const Rect& r) {
  if (poly.empty() || r.x0 >= r.x1 || r.y0 >= r.y1) return {};
  const Point c[4] = {{r.x0, r.y0}, {r.x1, r.y0}, {r.x1, r.y1}, {r.x0, r.y1}};  // from_rect's lines
  ConvexPolygon cur = poly;
  ConvexPolygon next;
  for (int i = 0; i < 4; ++i) {
    const Line l = Line::through(c[i], c[(i + 1) % 4]);
    const VertexSides s(cur, l);
    if (!s.any_negative()) continue;  // no allocation for a polygon already inside
    if (!s.any_positive()) return {};
    emit_side(cur, s, l, 1, next);
    std::swap(cur, next);
  }
  return cur;
}

bool chord(const ConvexPolygon& poly, const Line& l, ImplicitPoint& first, ImplicitPoint& second) {
  if (poly.empty()) return false;
  const VertexSides s(poly, l);
  if (!s.any_negative() || !s.any_positive()) return false;
  const std::size_t n = poly.size();
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t next = i + 1 == n ? 0 : i + 1;
    if (s[i] > 0 && s[next] <= 0)  // the edge leaving the positive block: l's edge starts here
      first = s[next] == 0 ? poly.vertex(next) : intersect(poly.line(i), l);
    if (s[i] <= 0 && s[next] > 0)  // the edge entering it: l's edge ends here
      second = s[i] == 0 ? poly.vertex(i) : intersect(l, poly.line(i));
  }
  return true;
}

bool segment_overlaps(const ConvexPolygon& poly, Point a, Point b) {
  if (poly.empty() || a == b) return false;
  for (const auto& e : poly.edges())
    if (e.line.eval(a) <= 0 && e.line.eval(b) <= 0) return false;
  const Line l = Line::through(a, b);
  bool pos = false, neg = false;
  for (const auto& e : poly.edges()) {
    const int s = side(l, e.start);
    pos |= s > 0;
    neg |= s < 0;
  }
  return pos && neg;
}

}  // namespace tilevis::geom
