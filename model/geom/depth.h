// Exact depth comparisons: the plane of a snapped triangle against another plane (z-buffer
// truth, SVGPU §3.3 occlusion) or against a silhouette edge's depth (SVGPU §3.2.1 test 3).
// Depth z is an unsigned integer of D <= 32 bits, Z = 2^D - 1; window-space z is affine in
// screen x,y, so plane and edge interpolation are exact rationals.
//
// Results are sign(z_first - z_second) in {-1, 0, 1}; which of smaller or larger z is
// "nearer" is the caller's depth-test convention, not decided here.
#pragma once

#include <cstdint>

#include "geom/fixed.h"
#include "geom/predicates.h"
#include "geom/wide_int.h"

namespace tilevis::geom {

// area * z(x, y) = alpha x + beta y + gamma, area = doubled area > 0 (sign-normalised).
// With dy, dx <= 2^24 and dz <= Z < 2^D:
//   area <= 2^49                              (int64)
//   |alpha|, |beta| <= 2 * 2^24 * Z < 2^(25+D) (int64 for D <= 32: 2^57)
//   |gamma| = |area z0 - alpha x0 - beta y0| <= 2^(49+D) + 2 * 2^(25+D) * 2^23 = 2^(50+D)
//                                             (Int128: 2^82 at D = 32)
// small: every z < 2^26, which selects the Int128 path of depth_order at a sample.
struct DepthPlane {
  int64_t alpha = 0, beta = 0;
  Int128 gamma = 0;
  int64_t area = 0;  // 0: degenerate triangle, no plane
  bool small = false;
  double falpha = 0, fbeta = 0, fgamma = 0, farea = 0;  // correctly rounded, for filters

  static DepthPlane from(const Triangle& t);
  constexpr bool valid() const { return area > 0; }
};

namespace detail {
int depth_order_sample_wide(const DepthPlane& p, const DepthPlane& q, Point s);
int depth_order_implicit_exact(const DepthPlane& p, const DepthPlane& q, const ImplicitPoint& s);
int depth_order_rational_exact(const DepthPlane& p, const DepthPlane& q, const RationalPoint& s);
int depth_order_edge_exact(const DepthPlane& p, const ImplicitPoint& s, Int128 e, Int128 den);
}  // namespace detail

// Numerator of area * z at a snapped point: |alpha x| + |beta y| <= 2 * 2^(25+D) * 2^23 =
// 2^(49+D), plus |gamma| <= 2^(50+D): < 2^(51+D), Int128.
inline Int128 depth_numerator(const DepthPlane& p, Point s) {
  return Int128{p.alpha} * s.x + Int128{p.beta} * s.y + p.gamma;
}

// sign(z_p(s) - z_q(s)) at a sample. Cross-multiplied: |N_p area_q| < 2^(51+D) * 2^49, the
// difference < 2^(101+D): Int128 while D <= 26 (both planes small), Int192 otherwise.
inline int depth_order(const DepthPlane& p, const DepthPlane& q, Point s) {
  if (p.small && q.small) {
    const Int128 d = depth_numerator(p, s) * q.area - depth_numerator(q, s) * p.area;
    return sign_of(d);
  }
  return detail::depth_order_sample_wide(p, q, s);
}

// sign(z_p(s) - z) for a stored depth value z < 2^32: |z area| < 2^81, |N| < 2^83, Int128.
inline int depth_order(const DepthPlane& p, Point s, uint32_t z) {
  return sign_of(depth_numerator(p, s) - Int128{z} * p.area);
}

// z_p(s) rounded to nearest (ties to even) and clamped to [0, 2^depth_bits - 1]: the depth a
// fixed-point z-buffer of that width would store (the "quantized" truth variant).
uint32_t quantized_depth(const DepthPlane& p, Point s, int depth_bits);

// sign(z_p(s) - z_q(s)) at an implicit point (x : y : w), w > 0.
// M = alpha x + beta y + gamma w: 2 * 2^(25+D) * 2^72 + 2^(50+D) * 2^49 < 2^(100+D);
// z = M / (area w), so sign = sign(M_p area_q - M_q area_p) < 2^(150+D) <= 2^182: Int192.
// Filter: alpha, beta, gamma, x, y, w each rounded once (u), 3 products (u), 2 sums,
// one product by area (u), one difference: error <= 8u of the sum of |terms|.
inline int depth_order(const DepthPlane& p, const DepthPlane& q, const ImplicitPoint& s) {
  const double x = static_cast<double>(s.x), y = static_cast<double>(s.y), w = static_cast<double>(s.w);
  const double p1 = p.falpha * x, p2 = p.fbeta * y, p3 = p.fgamma * w;
  const double q1 = q.falpha * x, q2 = q.fbeta * y, q3 = q.fgamma * w;
  const double f = (p1 + p2 + p3) * q.farea - (q1 + q2 + q3) * p.farea;
  const double mag = (std::fabs(p1) + std::fabs(p2) + std::fabs(p3)) * q.farea +
                     (std::fabs(q1) + std::fabs(q2) + std::fabs(q3)) * p.farea;
  const double bound = mag * kFilterRelErr;
  if (f > bound) return 1;
  if (f < -bound) return -1;
  return detail::depth_order_implicit_exact(p, q, s);
}

// sign(z_p(s) - z_q(s)) at a rational interior point (SVGPU §3.3 occlusion test).
// M = alpha x + beta y + gamma w: 2 * 2^(25+D) * 2^172 + 2^(50+D) * 2^149 < 2^(200+D);
// M_p area_q - M_q area_p < 2^(250+D) <= 2^282: Int320. Same filter as above (x, y, w are
// the correctly rounded fx, fy, fw).
inline int depth_order(const DepthPlane& p, const DepthPlane& q, const RationalPoint& s) {
  const double p1 = p.falpha * s.fx, p2 = p.fbeta * s.fy, p3 = p.fgamma * s.fw;
  const double q1 = q.falpha * s.fx, q2 = q.fbeta * s.fy, q3 = q.fgamma * s.fw;
  const double f = (p1 + p2 + p3) * q.farea - (q1 + q2 + q3) * p.farea;
  const double mag = (std::fabs(p1) + std::fabs(p2) + std::fabs(p3)) * q.farea +
                     (std::fabs(q1) + std::fabs(q2) + std::fabs(q3)) * p.farea;
  const double bound = mag * kFilterRelErr;
  if (f > bound) return 1;
  if (f < -bound) return -1;
  return detail::depth_order_rational_exact(p, q, s);
}

// SVGPU §3.2.1 test 3: sign(z_p(s) - z_AB(s)) where s is an implicit point ON the line AB
// (e.g. an intersection of line AB with an edge line of the triangle, as chord() returns)
// and z_AB is the depth of segment AB interpolated linearly in screen space.
// Precondition: a.xy() != b.xy() and s lies on line AB (then the result is exact).
//
// Parameter along AB on its dominant axis k (|b_k - a_k| >= the other, so != 0):
// t = (s_k - a_k w) / ((b_k - a_k) w): |den| <= 2^24 * 2^49 = 2^73,
// |num| <= 2^72 + 2^23 * 2^49 = 2^73 (Int128). z_AB = E / den with
// E = z_a den + (z_b - z_a) num: |E| <= Z 2^73 + Z 2^73 = 2^(74+D) (Int128, 2^106).
// z_p = M / (area w) with |M| < 2^(100+D) as above; sign(M den - E area w):
// 2^(173+D) + 2^(172+D) < 2^(174+D) <= 2^206: Int256. Filter: 8u as above.
inline int depth_order_edge(const DepthPlane& p, const Vertex& a, const Vertex& b, const ImplicitPoint& s) {
  const int64_t dx = int64_t{b.x} - a.x, dy = int64_t{b.y} - a.y;
  Int128 num, den;
  if (std::llabs(dx) >= std::llabs(dy)) {
    num = s.x - Int128{a.x} * s.w;
    den = Int128{dx} * s.w;
  } else {
    num = s.y - Int128{a.y} * s.w;
    den = Int128{dy} * s.w;
  }
  if (den < 0) {
    num = -num;
    den = -den;
  }
  const Int128 e = Int128{a.z} * den + (Int128{b.z} - Int128{a.z}) * num;
  const double x = static_cast<double>(s.x), y = static_cast<double>(s.y), w = static_cast<double>(s.w);
  const double p1 = p.falpha * x, p2 = p.fbeta * y, p3 = p.fgamma * w;
  const double fden = static_cast<double>(den);
  const double t1 = (p1 + p2 + p3) * fden;
  const double t2 = static_cast<double>(e) * (p.farea * w);
  const double f = t1 - t2;
  const double mag = (std::fabs(p1) + std::fabs(p2) + std::fabs(p3)) * fden + std::fabs(t2);
  const double bound = mag * kFilterRelErr;
  if (f > bound) return 1;
  if (f < -bound) return -1;
  return detail::depth_order_edge_exact(p, s, e, den);
}

}  // namespace tilevis::geom
