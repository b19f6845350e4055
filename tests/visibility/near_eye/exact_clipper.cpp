#include "exact_clipper.h"

#include <array>
#include <cmath>

#include <boost/multiprecision/cpp_int.hpp>

namespace tilevis::near_eye {
namespace {

using Q = boost::multiprecision::cpp_rational;
using Z = boost::multiprecision::cpp_int;

struct P4 {
  Q x, y, z, w;
};

Q exact(double v) {  // every float and double is a dyadic rational
  int e = 0;
  const double m = std::frexp(v, &e);
  Q q = Q(Z(static_cast<int64_t>(std::ldexp(m, 60))));
  e -= 60;
  if (e >= 0) return q * Q(Z(1) << e);
  return q / Q(Z(1) << -e);
}

// Round half to even of a rational.
Z round_even(const Q& v) {
  const Z num = boost::multiprecision::numerator(v), den = boost::multiprecision::denominator(v);
  Z q = num / den, r = num % den;  // truncates toward zero
  if (r < 0) {
    q -= 1;
    r += den;
  }
  const Z twice = 2 * r;
  if (twice > den || (twice == den && (q & 1) != 0)) q += 1;
  return q;
}

}  // namespace

std::vector<ExactTriangle> exact_clip(const trace::Frame& f, uint32_t depth_bits) {
  const Q gx = Q(int64_t(std::floor(65536.0 / f.width)) - 2), gy = Q(int64_t(std::floor(65536.0 / f.height)) - 2);
  // Planes c . (x, y, z, w) >= 0: near, far, guard band left, right, bottom, top.
  const std::array<std::array<Q, 4>, 6> planes = {{{0, 0, 1, 1}, {0, 0, -1, 1}, {1, 0, 0, gx}, {-1, 0, 0, gx},
                                                    {0, 1, 0, gy}, {0, -1, 0, gy}}};
  const Q half_w = Q(f.width) / 2, half_h = Q(f.height) / 2, sub = Q(int64_t(1) << f.subpixel_bits);
  const Q near = exact(f.depth_near), range = exact(f.depth_far) - exact(f.depth_near);
  const Q depth_max = Q((int64_t(1) << depth_bits) - 1);
  std::vector<ExactTriangle> out;
  uint32_t id = 0;
  for (const trace::Draw& d : f.draws)
    for (size_t t = 0; t < d.indices.size(); t += 3, ++id) {
      ExactTriangle et;
      et.id = id;
      std::vector<P4> poly;
      for (int k = 0; k < 3; ++k) {
        const trace::Vec4& v = d.vertices[d.indices[t + k]];
        poly.push_back({exact(v.x), exact(v.y), exact(v.z), exact(v.w)});
      }
      const Q det = poly[0].x * (poly[1].y * poly[2].w - poly[2].y * poly[1].w) -
                    poly[1].x * (poly[0].y * poly[2].w - poly[2].y * poly[0].w) +
                    poly[2].x * (poly[0].y * poly[1].w - poly[1].y * poly[0].w);
      et.facing = det > 0 ? 1 : det < 0 ? -1 : 0;
      for (const auto& c : planes) {
        auto dist = [&](const P4& p) { return c[0] * p.x + c[1] * p.y + c[2] * p.z + c[3] * p.w; };
        std::vector<P4> next;
        for (size_t i = 0; i < poly.size(); ++i) {
          const P4 &a = poly[i], &b = poly[(i + 1) % poly.size()];
          const Q da = dist(a), db = dist(b);
          if (da >= 0) next.push_back(a);
          if ((da >= 0) != (db >= 0)) {
            const Q s = da / (da - db);
            next.push_back({a.x + s * (b.x - a.x), a.y + s * (b.y - a.y), a.z + s * (b.z - a.z), a.w + s * (b.w - a.w)});
          }
        }
        poly.swap(next);
        if (poly.size() < 3) break;
      }
      if (poly.size() >= 3)
        for (const P4& p : poly) {
          // Inside every plane: |x|, |y| <= g w and |z| <= w, so w > 0 unless the point is the eye.
          if (p.w == 0) {
            et.polygon.clear();
            break;
          }
          const Q xw = (p.x / p.w + 1) * half_w, yw = (1 - p.y / p.w) * half_h;
          Q zw = near + range * (p.z / p.w + 1) / 2;
          if (zw < 0) zw = 0;
          if (zw > 1) zw = 1;
          et.polygon.push_back({int32_t(round_even(xw * sub)), int32_t(round_even(yw * sub)),
                                uint32_t(round_even(zw * depth_max))});
        }
      out.push_back(std::move(et));
    }
  return out;
}

}  // namespace tilevis::near_eye
