// Exact oracles for the geometry tests: arbitrary precision (boost::multiprecision), written
// independently of the code under test (Cramer's rule, barycentric depth, rational clipping).
#pragma once

#include <algorithm>
#include <cmath>
#include <boost/multiprecision/cpp_int.hpp>
#include <random>
#include <vector>

#include "geom/clip.h"
#include "geom/depth.h"
#include "geom/polygon.h"
#include "geom/predicates.h"
#include "geom/wide_int.h"

namespace tilevis::geom::test {

using BigInt = boost::multiprecision::cpp_int;
using Rational = boost::multiprecision::cpp_rational;

inline BigInt big(Int128 v) {
  const auto hi = static_cast<int64_t>(v >> 64);
  const auto lo = static_cast<uint64_t>(v);
  return (BigInt(hi) << 64) + BigInt(lo);
}

template <int L>
BigInt big(const WideInt<L>& v) {
  BigInt r = 0;
  for (int i = L - 1; i >= 0; --i) r = (r << 64) + BigInt(v.limb[i]);
  if (v.negative()) r -= BigInt(1) << (64 * L);
  return r;
}

template <typename T>
int sgn(const T& v) {
  return v > 0 ? 1 : (v < 0 ? -1 : 0);
}

// Exact value of a double.
inline Rational exact(double d) {
  int e = 0;
  const double m = std::frexp(d, &e);
  const BigInt mant(static_cast<int64_t>(std::ldexp(m, 53)));
  e -= 53;
  if (e >= 0) return Rational(mant << e);
  return Rational(mant, BigInt(1) << -e);
}

// boost 1.74's cpp_rational(num, den) rejects a negative den: normalise first.
inline Rational ratio(BigInt num, BigInt den) {
  if (den < 0) {
    num = -num;
    den = -den;
  }
  return Rational(num, den);
}

// Whether d is the double nearest to v (ties to an even significand).
inline bool is_correctly_rounded(double d, const BigInt& v) {
  const Rational x(v);
  const Rational err = abs(exact(d) - x);
  for (double nb : {std::nextafter(d, -INFINITY), std::nextafter(d, INFINITY)}) {
    const Rational e = abs(exact(nb) - x);
    if (e < err) return false;
    if (e == err) {
      int ex = 0;
      const auto m = static_cast<int64_t>(std::ldexp(std::frexp(d, &ex), 53));
      if ((m & 1) != 0) return false;
    }
  }
  return true;
}

struct RPoint {
  Rational x, y;
  bool operator==(const RPoint&) const = default;
};

inline RPoint rpoint(Point p) { return {Rational(p.x), Rational(p.y)}; }
inline RPoint rpoint(const ImplicitPoint& p) { return {Rational(big(p.x), BigInt(p.w)), Rational(big(p.y), BigInt(p.w))}; }
inline RPoint rpoint(const RationalPoint& p) { return {ratio(big(p.x), big(p.w)), ratio(big(p.y), big(p.w))}; }

// Orientation of three rational points.
inline Rational orient(const RPoint& a, const RPoint& b, const RPoint& c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// Intersection of line p0p1 with line q0q1 by Cramer's rule on the parametric form.
inline bool intersect_segments_lines(Point p0, Point p1, Point q0, Point q1, RPoint& out) {
  const BigInt dx1 = BigInt(p1.x) - p0.x, dy1 = BigInt(p1.y) - p0.y;
  const BigInt dx2 = BigInt(q1.x) - q0.x, dy2 = BigInt(q1.y) - q0.y;
  const BigInt det = dx1 * dy2 - dy1 * dx2;
  if (det == 0) return false;
  const BigInt ex = BigInt(q0.x) - p0.x, ey = BigInt(q0.y) - p0.y;
  const Rational t = ratio(ex * dy2 - ey * dx2, det);
  out = {Rational(p0.x) + t * Rational(dx1), Rational(p0.y) + t * Rational(dy1)};
  return true;
}

// Depth of triangle t at a rational point by barycentric interpolation.
inline Rational depth_at(const Triangle& t, const RPoint& p) {
  const RPoint a = rpoint(t.v[0].xy()), b = rpoint(t.v[1].xy()), c = rpoint(t.v[2].xy());
  const Rational area = orient(a, b, c);
  const Rational w0 = orient(b, c, p), w1 = orient(c, a, p), w2 = orient(a, b, p);
  return (w0 * t.v[0].z + w1 * t.v[1].z + w2 * t.v[2].z) / area;
}

// Polygon as rational vertices (from its implicit vertices).
inline std::vector<RPoint> rvertices(const ConvexPolygon& poly) {
  std::vector<RPoint> r;
  for (const auto& e : poly.edges()) r.push_back(rpoint(e.start));
  return r;
}

inline Rational shoelace(const std::vector<RPoint>& v) {
  Rational s = 0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const RPoint& a = v[i];
    const RPoint& b = v[(i + 1) % v.size()];
    s += a.x * b.y - b.x * a.y;
  }
  return s;
}

// Exact doubled area from the library's fan terms.
inline Rational exact_area(const ConvexPolygon& poly) {
  std::vector<AreaTerm> terms;
  doubled_area_terms(poly, terms);
  Rational s = 0;
  for (const auto& t : terms) s += ratio(big(t.num), big(t.den));
  return s;
}

// Sutherland-Hodgman in rationals: keep a*x + b*y + c >= 0.
inline std::vector<RPoint> clip_rational(const std::vector<RPoint>& poly, const Rational& a, const Rational& b,
                                         const Rational& c) {
  std::vector<RPoint> out;
  const std::size_t n = poly.size();
  for (std::size_t i = 0; i < n; ++i) {
    const RPoint& p = poly[i];
    const RPoint& q = poly[(i + 1) % n];
    const Rational fp = a * p.x + b * p.y + c, fq = a * q.x + b * q.y + c;
    if (fp >= 0) out.push_back(p);
    if ((fp > 0 && fq < 0) || (fp < 0 && fq > 0)) {
      const Rational t = fp / (fp - fq);
      out.push_back({p.x + t * (q.x - p.x), p.y + t * (q.y - p.y)});
    }
  }
  return out;
}

// The largest |coordinate| the predicates accept (2^23): random inputs span it.
inline constexpr int32_t kLim = kCoordLimit;

inline Point random_point(std::mt19937_64& rng, int32_t lo, int32_t hi) {
  std::uniform_int_distribution<int32_t> d(lo, hi);
  const int32_t x = d(rng);
  return {x, d(rng)};
}

// Strictly convex polygon: convex hull (monotone chain, positive order) of random points.
inline std::vector<Point> convex_hull(std::vector<Point> pts) {
  std::sort(pts.begin(), pts.end(), [](Point a, Point b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  if (pts.size() < 3) return {};
  std::vector<Point> h(2 * pts.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && orient2d(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
    h[k++] = pts[i];
  }
  for (std::size_t i = pts.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && orient2d(h[k - 2], h[k - 1], pts[i - 1]) <= 0) --k;
    h[k++] = pts[i - 1];
  }
  h.resize(k - 1);
  return h;
}

inline ConvexPolygon random_convex_polygon(std::mt19937_64& rng, int32_t lo, int32_t hi, int npts) {
  for (;;) {
    std::vector<Point> pts;
    for (int i = 0; i < npts; ++i) pts.push_back(random_point(rng, lo, hi));
    const auto hull = convex_hull(pts);
    if (hull.size() < 3) continue;
    // Rotate so that vertex 0 varies.
    std::vector<Point> rot(hull.size());
    const std::size_t off = rng() % hull.size();
    for (std::size_t i = 0; i < hull.size(); ++i) rot[i] = hull[(i + off) % hull.size()];
    auto poly = ConvexPolygon::from_convex_points(rot);
    if (poly) return *poly;
  }
}

}  // namespace tilevis::geom::test
