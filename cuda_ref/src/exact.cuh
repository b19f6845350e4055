// Exact integer geometry of the tile stage (precision `exact`). Every decision is the sign of
// an exact integer; the double-precision filters only short-cut a sign their error bound
// proves, so decisions equal those of any other exact implementation of the same predicates.
//
// Bounds (DESIGN.md "Numbers"): snapped |X|, |Y| <= g = 2^23 (tile corners included),
// coordinate differences <= 2^24, depth Z < 2^D with D <= 32.
#pragma once

#include "wide.cuh"

namespace tilevis::cuda {

struct Pt {
  int32_t x, y;
};
TV_HD inline bool operator==(Pt a, Pt b) { return a.x == b.x && a.y == b.y; }

struct Vtx {
  int32_t x, y;
  uint32_t z;
  TV_HD Pt xy() const { return {x, y}; }
};
TV_HD inline bool operator==(const Vtx& a, const Vtx& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

// Tile rectangle in sub-pixel units; owns [x0, x1) x [y0, y1) of samples.
struct Rect {
  int32_t x0, y0, x1, y1;
};

template <class T>
TV_HD inline T tmin(T a, T b) { return b < a ? b : a; }
template <class T>
TV_HD inline T tmax(T a, T b) { return a < b ? b : a; }

// (b - a) x (c - a): differences <= 2^24, products <= 2^48, result <= 2^49 (int64).
TV_HD inline int64_t orient2d(Pt a, Pt b, Pt c) {
  return (int64_t{b.x} - a.x) * (int64_t{c.y} - a.y) - (int64_t{b.y} - a.y) * (int64_t{c.x} - a.x);
}

// Depth in window space -> D-bit integer: clamp to [0, 1], then round z (2^D - 1) to nearest,
// ties to even, on the EXACT product: z's 53-bit integer significand times 2^D - 1 is below
// 2^53 2^32 = 2^85 (U128). A double product would round first.
TV_HD inline uint32_t snap_depth(double z, uint32_t depth_bits) {
  const uint64_t max_value = (uint64_t{1} << depth_bits) - 1;
  if (!(z > 0.0)) return 0;
  if (z >= 1.0) return uint32_t(max_value);
  uint64_t bits;
  __builtin_memcpy(&bits, &z, 8);
  const int biased = int(bits >> 52);  // z in (0, 1): sign 0
  uint64_t significand = bits & ((uint64_t{1} << 52) - 1);
  int shift;  // z = significand 2^-shift
  if (biased == 0) {
    shift = 1074;
  } else {
    significand |= uint64_t{1} << 52;
    shift = 1075 - biased;  // >= 53
  }
  if (shift >= 86) return 0;  // value < 2^85 2^-86 = 1/2
  const U128 product = U128{significand} * max_value;
  U128 q = product >> shift;
  const U128 rem = product & ((U128{1} << shift) - 1);
  const U128 half = U128{1} << (shift - 1);
  if (rem > half || (rem == half && (q & 1) != 0)) ++q;
  return uint32_t(q);
}

// ---- binning overlap (interiors must meet; touching does not count) ----------------------

// Line a x + b y + c through p, q with eval(r) = orient2d(p, q, r): |a|, |b| <= 2^24,
// |c| <= 2^47, |eval| < 2^49.
struct ILine {
  int64_t a, b, c;
  TV_HD static ILine through(Pt p, Pt q) {
    return {int64_t{p.y} - q.y, int64_t{q.x} - p.x, int64_t{p.x} * q.y - int64_t{p.y} * q.x};
  }
  TV_HD ILine flipped() const { return {-a, -b, -c}; }
  TV_HD int64_t eval(Pt s) const { return a * s.x + b * s.y + c; }
  // Tie rule: a point on the line belongs to the side (a, b) points into when (a, b) is
  // lexicographically positive: the side s + (eps, eps^2) enters. D3D's top-left rule.
  TV_HD bool owns_boundary() const { return a > 0 || (a == 0 && b > 0); }
  // Extremes of eval over the closed rectangle: the corner picked by each coefficient's sign.
  TV_HD int64_t max_over(const Rect& r) const { return a * (a > 0 ? r.x1 : r.x0) + b * (b > 0 ? r.y1 : r.y0) + c; }
  TV_HD int64_t min_over(const Rect& r) const { return a * (a > 0 ? r.x0 : r.x1) + b * (b > 0 ? r.y0 : r.y1) + c; }
};
TV_HD inline bool operator==(const ILine& l, const ILine& m) { return l.a == m.a && l.b == m.b && l.c == m.c; }

TV_HD inline bool in_half_plane(const ILine& l, Pt s) {
  const int64_t e = l.eval(s);
  return e > 0 || (e == 0 && l.owns_boundary());
}

// Separating axes: the rectangle's two axes and the triangle's three edge normals.
TV_HD inline bool triangle_overlaps_rect(Pt p0, Pt p1, Pt p2, const Rect& r) {
  const int64_t area = orient2d(p0, p1, p2);
  if (area == 0) return false;
  if (tmax(tmax(p0.x, p1.x), p2.x) <= r.x0 || tmin(tmin(p0.x, p1.x), p2.x) >= r.x1) return false;
  if (tmax(tmax(p0.y, p1.y), p2.y) <= r.y0 || tmin(tmin(p0.y, p1.y), p2.y) >= r.y1) return false;
  const ILine e0 = ILine::through(p0, p1), e1 = ILine::through(p1, p2), e2 = ILine::through(p2, p0);
  if (area > 0) return e0.max_over(r) > 0 && e1.max_over(r) > 0 && e2.max_over(r) > 0;
  return e0.min_over(r) < 0 && e1.min_over(r) < 0 && e2.min_over(r) < 0;
}

TV_HD inline bool segment_overlaps_rect(Pt a, Pt b, const Rect& r) {
  if (a == b) return false;
  if (tmax(a.x, b.x) <= r.x0 || tmin(a.x, b.x) >= r.x1) return false;
  if (tmax(a.y, b.y) <= r.y0 || tmin(a.y, b.y) >= r.y1) return false;
  const ILine l = ILine::through(a, b);
  return l.max_over(r) > 0 && l.min_over(r) < 0;
}

// ---- exact points and predicates ----------------------------------------------------------

// Relative error allowance of the floating-point filters: 2^-47 (each filter needs <= 8 u).
inline constexpr double kFilterRelErr = 0x1p-47;

namespace exact {

using Line = ILine;

// Homogeneous (x : y : w), w > 0: a snapped point (w = 1) or the meet of two lines through
// snapped points: w = a1 b2 - a2 b1 <= 2^49, |x|, |y| <= 2^72 (I128).
struct IPoint {
  I128 x, y;
  int64_t w;
  TV_HD static IPoint of(Pt p) { return {I128{p.x}, I128{p.y}, 1}; }
};

TV_HD inline IPoint intersect(const Line& l1, const Line& l2) {
  I128 x = mul64(l1.b, l2.c) - mul64(l2.b, l1.c);
  I128 y = mul64(l1.c, l2.a) - mul64(l2.c, l1.a);
  int64_t w = l1.a * l2.b - l2.a * l1.b;
  if (w < 0) {
    x = -x;
    y = -y;
    w = -w;
  }
  return {x, y, w};
}

// |a x|, |b y| <= 2^24 2^72, |c w| <= 2^47 2^49: sum < 2^98 (I128).
TV_HD inline int side(const Line& l, const IPoint& p) {
  return sign128(I128{l.a} * p.x + I128{l.b} * p.y + I128{l.c} * p.w);
}

// Interior test point of a piece (SVGPU §3.3 centroid): the centroid of its vertices 0, 1, 2.
// x = sum x_i w_j w_k: 3 2^72 2^98 < 2^172; w = 3 w0 w1 w2 < 2^149 (W192). fx, fy, fw are
// the correctly rounded doubles, for filters and the occluder bounding-box pre-test.
struct RPoint {
  W192 x, y, w;
  double fx, fy, fw;
};

TV_HD inline RPoint centroid(const IPoint& p0, const IPoint& p1, const IPoint& p2) {
  const W192 w12 = wide<3>(mul64(p1.w, p2.w)), w02 = wide<3>(mul64(p0.w, p2.w)), w01 = wide<3>(mul64(p0.w, p1.w));
  RPoint r;
  r.x = wide<3>(p0.x) * w12 + wide<3>(p1.x) * w02 + wide<3>(p2.x) * w01;
  r.y = wide<3>(p0.y) * w12 + wide<3>(p1.y) * w02 + wide<3>(p2.y) * w01;
  r.w = wide<3>(int64_t{3}) * wide<3>(p0.w) * w12;
  r.fx = r.x.to_double();
  r.fy = r.y.to_double();
  r.fw = r.w.to_double();
  return r;
}

// sign(a x + b y + c w) < 2^198 (W256). Filter: three products of exactly converted
// coefficients by correctly rounded coordinates (2u each), two sums: |error| <= 4u S.
TV_HD inline int side(const Line& l, const RPoint& p) {
  const double ta = dmul(i64_to_double(l.a), p.fx);
  const double tb = dmul(i64_to_double(l.b), p.fy);
  const double tc = dmul(i64_to_double(l.c), p.fw);
  const double f = dadd(dadd(ta, tb), tc);
  const double bound = dmul(dadd(dadd(dabs(ta), dabs(tb)), dabs(tc)), kFilterRelErr);
  if (f > bound) return 1;
  if (f < -bound) return -1;
  const W256 s = wide<4>(l.a) * wide<4>(p.x) + wide<4>(l.b) * wide<4>(p.y) + wide<4>(l.c) * wide<4>(p.w);
  return s.sign();
}

template <class P>
TV_HD inline bool in_half_plane(const Line& l, const P& p) {
  const int s = side(l, p);
  return s > 0 || (s == 0 && l.owns_boundary());
}

// area z = alpha x + beta y + gamma, area = |doubled area| <= 2^49; |alpha|, |beta| < 2^(25+D)
// (int64 for D <= 32); |gamma| <= 2^(50+D) (I128).
struct Plane {
  int64_t alpha, beta;
  I128 gamma;
  int64_t area;  // 0: degenerate
  double falpha, fbeta, fgamma, farea;
};

// The plane's integer part, for any vertices (area 0: degenerate; the coefficients are then
// whatever the products give, and no caller may use them).
struct IntPlane {
  int64_t alpha, beta;
  I128 gamma;
  int64_t area;
};

TV_HD inline IntPlane int_plane_of(const Vtx& v0, const Vtx& v1, const Vtx& v2) {
  int64_t area = orient2d(v0.xy(), v1.xy(), v2.xy());
  const int64_t dx1 = int64_t{v1.x} - v0.x, dy1 = int64_t{v1.y} - v0.y, dz1 = int64_t{v1.z} - v0.z;
  const int64_t dx2 = int64_t{v2.x} - v0.x, dy2 = int64_t{v2.y} - v0.y, dz2 = int64_t{v2.z} - v0.z;
  // Normal d1 x d2 has z-component area; |dy dz| <= 2^24 2^32, so alpha, beta <= 2^57.
  int64_t alpha = -(dy1 * dz2 - dz1 * dy2);
  int64_t beta = -(dz1 * dx2 - dx1 * dz2);
  I128 gamma = mul64(area, int64_t{v0.z}) - mul64(alpha, v0.x) - mul64(beta, v0.y);
  if (area < 0) {
    area = -area;
    alpha = -alpha;
    beta = -beta;
    gamma = -gamma;
  }
  return {alpha, beta, gamma, area};
}

TV_HD inline Plane plane_of(const Vtx& v0, const Vtx& v1, const Vtx& v2) {
  Plane p{};
  const IntPlane q = int_plane_of(v0, v1, v2);
  if (q.area == 0) return p;
  p.alpha = q.alpha;
  p.beta = q.beta;
  p.gamma = q.gamma;
  p.area = q.area;
  p.falpha = i64_to_double(q.alpha);
  p.fbeta = i64_to_double(q.beta);
  p.fgamma = i128_to_double(q.gamma);
  p.farea = i64_to_double(q.area);
  return p;
}

template <int L, class T>
TV_HD inline Wide<L> plane_numerator(const Plane& d, const T& x, const T& y, const T& w) {
  return wide<L>(d.alpha) * wide<L>(x) + wide<L>(d.beta) * wide<L>(y) + wide<L>(d.gamma) * wide<L>(w);
}

// sign(z_p - z_q) at the interior point (SVGPU §3.3). M = alpha x + beta y + gamma w <
// 2^(200+D); M_p area_q - M_q area_p < 2^(250+D) <= 2^282 (W320). Filter: 8u of the sum.
TV_HD inline int depth_order(const Plane& p, const Plane& q, const RPoint& s) {
  const double p1 = dmul(p.falpha, s.fx), p2 = dmul(p.fbeta, s.fy), p3 = dmul(p.fgamma, s.fw);
  const double q1 = dmul(q.falpha, s.fx), q2 = dmul(q.fbeta, s.fy), q3 = dmul(q.fgamma, s.fw);
  const double f = dsub(dmul(dadd(dadd(p1, p2), p3), q.farea), dmul(dadd(dadd(q1, q2), q3), p.farea));
  const double mag = dadd(dmul(dadd(dadd(dabs(p1), dabs(p2)), dabs(p3)), q.farea),
                          dmul(dadd(dadd(dabs(q1), dabs(q2)), dabs(q3)), p.farea));
  const double bound = dmul(mag, kFilterRelErr);
  if (f > bound) return 1;
  if (f < -bound) return -1;
  const W320 mp = plane_numerator<5>(p, s.x, s.y, s.w);
  const W320 mq = plane_numerator<5>(q, s.x, s.y, s.w);
  return (mp * wide<5>(q.area) - mq * wide<5>(p.area)).sign();
}

// sign(z_p(a) - z) at a snapped point against a stored depth: |N| < 2^(51+D), |z area| < 2^81
// (I128).
TV_HD inline int depth_order(const Plane& p, Pt s, uint32_t z) {
  const I128 n = I128{p.alpha} * s.x + I128{p.beta} * s.y + p.gamma;
  return sign128(n - I128{z} * p.area);
}

// SVGPU §3.2.1 test 3: sign(z_p(s) - z_AB(s)) for an implicit point s on line AB, z_AB the
// depth interpolated along AB. On AB's dominant axis k: t = num / den with |num|, |den| <=
// 2^73; z_AB = E / den, |E| <= 2^(74+D) (I128); sign(M den - E area w) < 2^(174+D) (W256).
TV_HD inline int depth_order_edge(const Plane& p, const Vtx& a, const Vtx& b, const IPoint& s) {
  const int64_t dx = int64_t{b.x} - a.x, dy = int64_t{b.y} - a.y;
  I128 num, den;
  if ((dx < 0 ? -dx : dx) >= (dy < 0 ? -dy : dy)) {
    num = s.x - I128{a.x} * s.w;
    den = I128{dx} * s.w;
  } else {
    num = s.y - I128{a.y} * s.w;
    den = I128{dy} * s.w;
  }
  if (den < 0) {
    num = -num;
    den = -den;
  }
  const I128 e = I128{a.z} * den + (I128{b.z} - I128{a.z}) * num;
  const double x = i128_to_double(s.x), y = i128_to_double(s.y), w = i64_to_double(s.w);
  const double p1 = dmul(p.falpha, x), p2 = dmul(p.fbeta, y), p3 = dmul(p.fgamma, w);
  const double fden = i128_to_double(den);
  const double t1 = dmul(dadd(dadd(p1, p2), p3), fden);
  const double t2 = dmul(i128_to_double(e), dmul(p.farea, w));
  const double f = dsub(t1, t2);
  const double mag = dadd(dmul(dadd(dadd(dabs(p1), dabs(p2)), dabs(p3)), fden), dabs(t2));
  const double bound = dmul(mag, kFilterRelErr);
  if (f > bound) return 1;
  if (f < -bound) return -1;
  const W256 m = plane_numerator<4>(p, s.x, s.y, I128{s.w});
  return (m * wide<4>(den) - wide<4>(e) * wide<4>(mul64(p.area, s.w))).sign();
}

// floor(n / d), d > 0, |n / d| < 2^31: a double estimate (off by at most one) corrected
// exactly, so no 128-bit division is needed on the device.
TV_HD inline int64_t floor_div(I128 n, int64_t d) {
  double qd = ddiv(i128_to_double(n), i64_to_double(d));
  int64_t q = static_cast<int64_t>(qd < 0 ? qd - 1.0 : qd);  // below or at the floor, within 2
  I128 r = n - I128{q} * d;
  while (r < 0) {
    --q;
    r += d;
  }
  while (r >= d) {
    ++q;
    r -= d;
  }
  return q;
}
TV_HD inline int64_t ceil_div(I128 n, int64_t d) { return -floor_div(-n, d); }

}  // namespace exact
}  // namespace tilevis::cuda
