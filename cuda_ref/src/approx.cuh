// float32 geometry of the tile stage (precision `float`), as SVGPU computed it: edge
// functions anchored at a snapped point, explicit float vertices from line intersections,
// float plane interpolation of depth, centroid test points. No exactness is claimed: its
// disagreement with `exact` is measured (tilevis compare), never hidden.
#pragma once

#include "exact.cuh"

namespace tilevis::cuda::approx {

// a (x - ox) + b (y - oy): a, b and the anchor are exact in float (|values| <= 2^24);
// anchoring keeps the products small, as window-relative edge functions do in hardware.
struct Line {
  float a, b, ox, oy;
  TV_HD static Line through(Pt p, Pt q) {
    return {float(int64_t{p.y} - q.y), float(int64_t{q.x} - p.x), float(p.x), float(p.y)};
  }
  TV_HD Line flipped() const { return {-a, -b, ox, oy}; }
  TV_HD float eval(float x, float y) const { return fadd(fmul(a, x - ox), fmul(b, y - oy)); }
  // eval split for a row: eval(x, y) = fadd(fmul(a, x - ox), row(y)), bit for bit.
  TV_HD float row(float y) const { return fmul(b, y - oy); }
  TV_HD float eval_row(float x, float r) const { return fadd(fmul(a, x - ox), r); }
  TV_HD bool owns_boundary() const { return a > 0 || (a == 0 && b > 0); }
};

struct Vec {
  float x, y;
  TV_HD static Vec of(Pt p) { return {float(p.x), float(p.y)}; }
};

TV_HD inline int signf(float v) { return (v > 0) - (v < 0); }

TV_HD inline int side(const Line& l, const Vec& p) { return signf(l.eval(p.x, p.y)); }

template <class P>
TV_HD inline bool in_half_plane(const Line& l, const P& p) {
  const int s = side(l, p);
  return s > 0 || (s == 0 && l.owns_boundary());
}

// l1's anchor moved along l1 to l2: t = -l2(o1) / (a2 b1 - b2 a1).
TV_HD inline Vec intersect(const Line& l1, const Line& l2) {
  const float den = l2.a * l1.b - l2.b * l1.a;
  if (den == 0) return {l1.ox, l1.oy};
  const float t = -l2.eval(l1.ox, l1.oy) / den;
  return {l1.ox + t * l1.b, l1.oy - t * l1.a};
}

// z(x, y) = z0 + gx (x - x0) + gy (y - y0).
struct Plane {
  float gx, gy, x0, y0, z0;
  bool valid;
  TV_HD float at(float x, float y) const { return z0 + gx * (x - x0) + gy * (y - y0); }
};

TV_HD inline Plane plane_of(const Vtx& v0, const Vtx& v1, const Vtx& v2) {
  const float dx1 = float(v1.x - v0.x), dy1 = float(v1.y - v0.y), dz1 = float(v1.z) - float(v0.z);
  const float dx2 = float(v2.x - v0.x), dy2 = float(v2.y - v0.y), dz2 = float(v2.z) - float(v0.z);
  const float area = dx1 * dy2 - dy1 * dx2;
  Plane p{};
  if (area == 0) return p;
  p.gx = (dz1 * dy2 - dy1 * dz2) / area;
  p.gy = (dx1 * dz2 - dz1 * dx2) / area;
  p.x0 = float(v0.x);
  p.y0 = float(v0.y);
  p.z0 = float(v0.z);
  p.valid = true;
  return p;
}

TV_HD inline Vec centroid(const Vec& p0, const Vec& p1, const Vec& p2) {
  return {(p0.x + p1.x + p2.x) * (1.0f / 3.0f), (p0.y + p1.y + p2.y) * (1.0f / 3.0f)};
}

TV_HD inline int depth_order(const Plane& p, const Plane& q, const Vec& s) {
  return signf(p.at(s.x, s.y) - q.at(s.x, s.y));
}

TV_HD inline int depth_order(const Plane& p, Pt s, uint32_t z) { return signf(p.at(float(s.x), float(s.y)) - float(z)); }

// Test 3 in float: the edge's depth interpolated along its dominant axis.
TV_HD inline int depth_order_edge(const Plane& p, const Vtx& a, const Vtx& b, const Vec& s) {
  const float dx = float(b.x - a.x), dy = float(b.y - a.y);
  const float t = (dx < 0 ? -dx : dx) >= (dy < 0 ? -dy : dy) ? (s.x - float(a.x)) / dx : (s.y - float(a.y)) / dy;
  const float z = float(a.z) + t * (float(b.z) - float(a.z));
  return signf(p.at(s.x, s.y) - z);
}

}  // namespace tilevis::cuda::approx
