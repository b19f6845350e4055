#include "geom/predicates.h"

namespace tilevis::geom {

RationalPoint RationalPoint::from(const ImplicitPoint& p) {
  RationalPoint r;
  r.x = wide<3>(p.x);
  r.y = wide<3>(p.y);
  r.w = wide<3>(p.w);
  r.fx = static_cast<double>(p.x);
  r.fy = static_cast<double>(p.y);
  r.fw = static_cast<double>(p.w);
  return r;
}

// x = x0 w1 w2 + x1 w0 w2 + x2 w0 w1: each w w <= 2^98 (Int128), times |x| <= 2^72 gives
// 2^170, sum < 2^172; w = 3 w0 w1 w2 < 2^149. Int192 throughout.
RationalPoint centroid(const ImplicitPoint& p0, const ImplicitPoint& p1, const ImplicitPoint& p2) {
  const Int192 w12 = wide<3>(Int128{p1.w} * p2.w);
  const Int192 w02 = wide<3>(Int128{p0.w} * p2.w);
  const Int192 w01 = wide<3>(Int128{p0.w} * p1.w);
  RationalPoint r;
  r.x = wide<3>(p0.x) * w12 + wide<3>(p1.x) * w02 + wide<3>(p2.x) * w01;
  r.y = wide<3>(p0.y) * w12 + wide<3>(p1.y) * w02 + wide<3>(p2.y) * w01;
  r.w = wide<3>(int64_t{3}) * wide<3>(p0.w) * w12;
  r.fx = r.x.to_double();
  r.fy = r.y.to_double();
  r.fw = r.w.to_double();
  return r;
}

namespace detail {

// < 2^198 (predicates.h): Int256.
int side_exact(const Line& l, const RationalPoint& p) {
  const Int256 s = wide<4>(l.a) * wide<4>(p.x) + wide<4>(l.b) * wide<4>(p.y) + wide<4>(l.c) * wide<4>(p.w);
  return s.sign();
}

}  // namespace detail
}  // namespace tilevis::geom
