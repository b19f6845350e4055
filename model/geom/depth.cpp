#include "geom/depth.h"

namespace tilevis::geom {

DepthPlane DepthPlane::from(const Triangle& t) {
  const Vertex& v0 = t.v[0];
  const Vertex& v1 = t.v[1];
  const Vertex& v2 = t.v[2];
  int64_t area = orient2d(v0.xy(), v1.xy(), v2.xy());
  if (area == 0) return {};
  const int64_t dx1 = int64_t{v1.x} - v0.x, dy1 = int64_t{v1.y} - v0.y, dz1 = int64_t{v1.z} - v0.z;
  const int64_t dx2 = int64_t{v2.x} - v0.x, dy2 = int64_t{v2.y} - v0.y, dz2 = int64_t{v2.z} - v0.z;
  // Plane normal n = d1 x d2, n_z = area: area (z - z0) = -n_x (x - x0) - n_y (y - y0).
  // |dy dz| <= 2^24 * 2^32 = 2^56, so n_x, n_y <= 2^57: int64.
  int64_t alpha = -(dy1 * dz2 - dz1 * dy2);
  int64_t beta = -(dz1 * dx2 - dx1 * dz2);
  Int128 gamma = Int128{area} * v0.z - Int128{alpha} * v0.x - Int128{beta} * v0.y;
  if (area < 0) {
    area = -area;
    alpha = -alpha;
    beta = -beta;
    gamma = -gamma;
  }
  DepthPlane p;
  p.alpha = alpha;
  p.beta = beta;
  p.gamma = gamma;
  p.area = area;
  p.small = ((v0.z | v1.z | v2.z) >> 26) == 0;
  p.falpha = static_cast<double>(alpha);
  p.fbeta = static_cast<double>(beta);
  p.fgamma = static_cast<double>(gamma);
  p.farea = static_cast<double>(area);
  return p;
}

uint32_t quantized_depth(const DepthPlane& p, Point s, int depth_bits) {
  const Int128 max_value = (Int128{1} << depth_bits) - 1;
  const Int128 n = depth_numerator(p, s);
  Int128 q = n / p.area;
  Int128 r = n % p.area;
  if (r < 0) {  // floor division
    q -= 1;
    r += p.area;
  }
  const Int128 twice = 2 * r;  // < 2^50
  if (twice > p.area || (twice == p.area && (q & 1) != 0)) q += 1;
  if (q < 0) return 0;
  if (q > max_value) return static_cast<uint32_t>(max_value);
  return static_cast<uint32_t>(q);
}

namespace detail {

// < 2^(101+D) <= 2^133: Int192.
int depth_order_sample_wide(const DepthPlane& p, const DepthPlane& q, Point s) {
  const Int192 np = wide<3>(depth_numerator(p, s));
  const Int192 nq = wide<3>(depth_numerator(q, s));
  return (np * wide<3>(q.area) - nq * wide<3>(p.area)).sign();
}

template <int L, typename P>
WideInt<L> plane_numerator(const DepthPlane& d, const P& x, const P& y, const P& w) {
  return wide<L>(d.alpha) * wide<L>(x) + wide<L>(d.beta) * wide<L>(y) + wide<L>(d.gamma) * wide<L>(w);
}

// < 2^(150+D) <= 2^182: Int192.
int depth_order_implicit_exact(const DepthPlane& p, const DepthPlane& q, const ImplicitPoint& s) {
  const Int128 w = s.w;
  const Int192 mp = plane_numerator<3>(p, s.x, s.y, w);
  const Int192 mq = plane_numerator<3>(q, s.x, s.y, w);
  return (mp * wide<3>(q.area) - mq * wide<3>(p.area)).sign();
}

// < 2^(250+D) <= 2^282: Int320.
int depth_order_rational_exact(const DepthPlane& p, const DepthPlane& q, const RationalPoint& s) {
  const Int320 mp = plane_numerator<5>(p, s.x, s.y, s.w);
  const Int320 mq = plane_numerator<5>(q, s.x, s.y, s.w);
  return (mp * wide<5>(q.area) - mq * wide<5>(p.area)).sign();
}

// < 2^(174+D) <= 2^206: Int256.
int depth_order_edge_exact(const DepthPlane& p, const ImplicitPoint& s, Int128 e, Int128 den) {
  const Int128 w = s.w;
  const Int256 m = plane_numerator<4>(p, s.x, s.y, w);
  return (m * wide<4>(den) - wide<4>(e) * wide<4>(Int128{p.area} * s.w)).sign();
}

}  // namespace detail
}  // namespace tilevis::geom
