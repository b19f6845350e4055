// Primitive setup's per-vertex and per-triangle arithmetic, shared by the pipeline's setup
// (setup.cu) and the tiled z-buffer (zbuffer.cu): facing from the exact sign of det[x y w],
// near/far and guard-band clipping in clip space (double precision, Sutherland-Hodgman,
// intersection in homogeneous form from the inside vertex), viewport transform and snapping.
// The double arithmetic uses explicit round-to-nearest operations (never contracted to FMA),
// so the device reproduces the host's setup bit for bit.
#pragma once

#include <cmath>

#include "pipeline.cuh"

namespace tilevis::cuda {

// Guard band half-widths in NDC: window x = (ndc + 1) pixels / 2 stays below 2^15 pixels in
// magnitude.
inline double guard_band(uint32_t pixels) { return std::floor(65536.0 / pixels) - 2.0; }

struct ClipV {
  double x, y, z, w;
  uint32_t index;  // global vertex index; kNone when made by clipping
};

inline constexpr uint32_t kMaxClipVerts = 16;  // 3 + one per plane (convex): 9


// Plane k as a distance c . (x, y, z, w), inside when >= 0, evaluated left to right.
TV_HD inline double distance(int k, double gx, double gy, const ClipV& v) {
  double cx = 0, cy = 0, cz = 0, cw = 1;
  switch (k) {
    case 0: cz = 1; break;               // near: z >= -w
    case 1: cz = -1; break;              // far: z <= w
    case 2: cx = 1; cw = gx; break;      // guard band left
    case 3: cx = -1; cw = gx; break;     // right
    case 4: cy = 1; cw = gy; break;      // bottom
    default: cy = -1; cw = gy; break;    // top
  }
  return dadd(dadd(dadd(dmul(cx, v.x), dmul(cy, v.y)), dmul(cz, v.z)), dmul(cw, v.w));
}

// The intersection of edge (in, out) with a plane in homogeneous form, din·out − dout·in
// (din >= 0 > dout), scaled exactly by a power of two: it keeps its relative precision next to
// the eye, where the interpolated form cancels (host setup.cpp intersect()).
TV_HD inline ClipV intersect(const ClipV& in, const ClipV& out, double din, double dout) {
  ClipV v{dsub(dmul(din, out.x), dmul(dout, in.x)), dsub(dmul(din, out.y), dmul(dout, in.y)),
          dsub(dmul(din, out.z), dmul(dout, in.z)), dsub(dmul(din, out.w), dmul(dout, in.w)), kNone};
  double m = dabs(v.x);
  if (dabs(v.y) > m) m = dabs(v.y);
  if (dabs(v.z) > m) m = dabs(v.z);
  if (dabs(v.w) > m) m = dabs(v.w);
  if (m > 0 && m <= 1.7976931348623157e308) {
    const int e = ilogb(m);
    v.x = scalbn(v.x, -e);
    v.y = scalbn(v.y, -e);
    v.z = scalbn(v.z, -e);
    v.w = scalbn(v.w, -e);
  }
  return v;
}

// Clips the triangle against the six planes. Returns the vertex count (0: culled) and
// whether a plane cut it.
TV_HD inline uint32_t clip_triangle(const float4* vertices, const uint32_t* indices, double gx, double gy, uint64_t t,
                                    ClipV* poly, bool& cut) {
  ClipV scratch[kMaxClipVerts];
  uint32_t n = 3;
  for (int k = 0; k < 3; ++k) {
    const uint32_t vi = indices[3 * t + k];
    const float4 v = vertices[vi];
    poly[k] = {double(v.x), double(v.y), double(v.z), double(v.w), vi};
  }
  cut = false;
  for (int p = 0; p < 6; ++p) {
    uint32_t inside = 0;
    for (uint32_t i = 0; i < n; ++i) inside += distance(p, gx, gy, poly[i]) >= 0;
    if (inside == 0) return 0;
    if (inside == n) continue;
    cut = true;
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; ++i) {
      const ClipV& va = poly[i];
      const ClipV& vb = poly[i + 1 == n ? 0 : i + 1];
      const double da = distance(p, gx, gy, va), db = distance(p, gx, gy, vb);
      if (da >= 0 && m < kMaxClipVerts) scratch[m++] = va;
      if ((da >= 0) != (db >= 0)) {
        const ClipV& in = da >= 0 ? va : vb;
        const ClipV& out = da >= 0 ? vb : va;
        const double din = da >= 0 ? da : db, dout = da >= 0 ? db : da;
        if (m < kMaxClipVerts) scratch[m++] = intersect(in, out, din, dout);
      }
    }
    for (uint32_t i = 0; i < m; ++i) poly[i] = scratch[i];
    n = m;
  }
  return n < 3 ? 0 : n;
}

// Sign of det[x y w] of the trace triangle's clip-space vertices, exactly: > 0 front-facing
// (counter-clockwise in NDC) for every piece clipping leaves, 0 when the eye lies in its plane.
// Products of two floats are exact in double; each triple product is split into p + e by an
// FMA; the twelve doubles are summed into a non-overlapping expansion (Shewchuk's
// Grow-Expansion), whose largest component carries the sign (model/geom/homogeneous.h).
TV_HD inline int clip_facing(const float4& a, const float4& b, const float4& c) {
  double h[12];
  int n = 0;
  const double xs[3] = {a.x, b.x, c.x}, ys[3] = {a.y, b.y, c.y}, ws[3] = {a.w, b.w, c.w};
  const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 2, 0}, {1, 0, 2}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < 6; ++k) {
    const double sign = (k & 1) ? -1.0 : 1.0;
    const double ab = dmul(dmul(sign, xs[perm[k][0]]), ys[perm[k][1]]);
    const double p = dmul(ab, ws[perm[k][2]]);
    const double parts[2] = {p, dfma(ab, ws[perm[k][2]], -p)};
    for (double q : parts) {
      int m = 0;
      for (int i = 0; i < n; ++i) {
        const double sum = dadd(q, h[i]);
        const double bv = dsub(sum, q);
        const double err = dadd(dsub(q, dsub(sum, bv)), dsub(h[i], bv));
        q = sum;
        if (err != 0) h[m++] = err;
      }
      if (q != 0) h[m++] = q;
      n = m;
    }
  }
  return n == 0 ? 0 : (h[n - 1] > 0 ? 1 : -1);
}


// Sign of det[x y w] (setup.cuh clip_facing) where a filter settles it: the six triple products
// in double (x y is exact, times w rounds by at most 2^-53 relative) and their sum are within
// 2^-48 of the total of their magnitudes; 0 when the sum is that close to zero (then only the
// exact expansion decides).
TV_HD inline int facing_filter(const float4& a, const float4& b, const float4& c) {
  const double t[6] = {dmul(dmul(double(a.x), double(b.y)), double(c.w)),
                       dmul(dmul(-double(a.x), double(c.y)), double(b.w)),
                       dmul(dmul(double(b.x), double(c.y)), double(a.w)),
                       dmul(dmul(-double(b.x), double(a.y)), double(c.w)),
                       dmul(dmul(double(c.x), double(a.y)), double(b.w)),
                       dmul(dmul(-double(c.x), double(b.y)), double(a.w))};
  double sum = 0, mag = 0;
  for (double v : t) {
    sum = dadd(sum, v);
    mag = dadd(mag, dabs(v));
  }
  const double bound = dmul(mag, 0x1p-48);
  return sum > bound ? 1 : sum < -bound ? -1 : 0;  // 0: not settled (the exact expansion decides)
}

// The exact sign of det[x y w]: the filter where it settles it, else the expansion.
TV_HD inline int clip_facing_fast(const float4& a, const float4& b, const float4& c) {
  const int f = facing_filter(a, b, c);
  return f != 0 ? f : clip_facing(a, b, c);
}

// A clipped vertex has w > 0 and |x|, |y| <= g w exactly; rounding can leave it a hair
// outside the band or, next to w = 0, with w <= 0: project it onto the band's edge in the
// direction of its coordinate (host setup's Snapper::project).
TV_HD inline double project(double c, double inv_w, double w, double g) {
  if (!(w > 0)) return c > 0 ? g : c < 0 ? -g : 0.0;
  const double q = dmul(c, inv_w);
  return q > g ? g : q < -g ? -g : q;
}

TV_HD inline double round_even(double v) {
#if defined(__CUDA_ARCH__)
  return rint(v);
#else
  return std::nearbyint(v);  // default rounding mode: to nearest, ties to even
#endif
}

// Viewport transform (y down) and snap: x, y to 1/2^subpixel_bits pixel, rounded to nearest
// even (scaling by a power of two is exact, so rounding the product is rounding the
// coordinate); guard-band clipping has kept every vertex inside |x| < 2^15 pixels.
TV_HD inline Vtx snap(const FrameDev& f, double gx, double gy, const ClipV& v) {
  const double half_w = dmul(double(f.width), 0.5), half_h = dmul(double(f.height), 0.5);
  const double near = double(f.depth_near), range = dsub(double(f.depth_far), double(f.depth_near));
  const double sub = double(1u << f.subpixel_bits);
  const double inv_w = ddiv(1.0, v.w);
  const double xw = dmul(dadd(project(v.x, inv_w, v.w, gx), 1.0), half_w);
  const double yw = dmul(dsub(1.0, project(v.y, inv_w, v.w, gy)), half_h);
  const double zn = v.w > 0 ? dmul(v.z, inv_w) : 0.0;  // depth is clamped to [0, 1] by snap_depth
  const double zw = dadd(near, dmul(dmul(range, dadd(zn, 1.0)), 0.5));
  Vtx s;
  s.x = int32_t(round_even(dmul(xw, sub)));
  s.y = int32_t(round_even(dmul(yw, sub)));
  s.z = snap_depth(zw, f.depth_bits);
  return s;
}

// Vertex i alone: its snap and whether it lies inside every plane (w 1), else zeros (w 0). A
// triangle whose three vertices are inside is its own clipped polygon, with these snaps.
TV_HD inline int4 snapped_vertex(const FrameDev& f, double gx, double gy, const float4* vertices, uint64_t i) {
  const float4 fv = vertices[i];
  const ClipV v{double(fv.x), double(fv.y), double(fv.z), double(fv.w), uint32_t(i)};
  bool inside = true;
  for (int p = 0; p < 6; ++p) inside &= distance(p, gx, gy, v) >= 0;
  const Vtx s = inside ? snap(f, gx, gy, v) : Vtx{0, 0, 0};
  return make_int4(s.x, s.y, int32_t(s.z), inside ? 1 : 0);
}

}  // namespace tilevis::cuda
