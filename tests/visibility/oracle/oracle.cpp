#include "oracle.h"

#include <algorithm>
#include <numeric>
#include <sstream>
#include <stdexcept>

// CGAL's headers are not written for -Wconversion/-Wshadow; they are third-party code.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wconversion"
#pragma GCC diagnostic ignored "-Wsign-conversion"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wpedantic"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Fraction_traits.h>
#include <CGAL/Polygon_2.h>
#include <CGAL/Polygon_set_2.h>
#include <CGAL/Polygon_with_holes_2.h>
#pragma GCC diagnostic pop

namespace tilevis::oracle {
namespace {

using Kernel = CGAL::Exact_predicates_exact_constructions_kernel;
__extension__ typedef __int128 Int128;  // GCC/Clang builtin; -Wpedantic wants the marker
using FT = Kernel::FT;
using Point = Kernel::Point_2;
using Polygon = CGAL::Polygon_2<Kernel>;
using PolygonSet = CGAL::Polygon_set_2<Kernel>;

// Coordinates reach CGAL through double, which holds every integer up to 2^53 exactly.
constexpr int64_t kMaxCoord = int64_t{1} << 53;

FT exact_coord(int64_t v) {
  if (v > kMaxCoord || v < -kMaxCoord)
    throw std::invalid_argument("oracle: coordinate " + std::to_string(v) + " outside ±2^53");
  return FT(static_cast<double>(v));
}

// Twice the signed area in y-down window units, exact: coordinate differences stay below
// 2^54, so each product stays below 2^108 and the difference fits Int128.
Int128 orient(const Triangle& t) {
  const Int128 ax = t.x[1] - t.x[0], ay = t.y[1] - t.y[0];
  const Int128 bx = t.x[2] - t.x[0], by = t.y[2] - t.y[0];
  return ax * by - ay * bx;
}

// CGAL's Boolean operations want simple, counter-clockwise boundaries.
Polygon ccw_polygon(const Triangle& t, Int128 o) {
  Polygon p;
  for (int k = 0; k < 3; ++k) p.push_back(Point(exact_coord(t.x[k]), exact_coord(t.y[k])));
  if (o < 0) p.reverse_orientation();
  return p;
}

FT area(const PolygonSet& set) {
  std::vector<CGAL::Polygon_with_holes_2<Kernel>> parts;
  set.polygons_with_holes(std::back_inserter(parts));
  FT sum = 0;
  for (const auto& pwh : parts) {
    sum += pwh.outer_boundary().area();
    // Holes are clockwise: their signed areas are negative.
    for (auto h = pwh.holes_begin(); h != pwh.holes_end(); ++h) sum += h->area();
  }
  return sum;
}

Area to_area(const FT& value) {
  using ET = decltype(CGAL::exact(value));
  using Traits = CGAL::Fraction_traits<std::decay_t<ET>>;
  typename Traits::Numerator_type num;
  typename Traits::Denominator_type den;
  const auto exact = CGAL::exact(value);
  typename Traits::Decompose()(exact, num, den);
  std::ostringstream n, d;
  n << num;
  d << den;
  return {n.str(), d.str(), CGAL::to_double(exact)};
}

bool bbox_interiors_overlap(const Triangle& a, const Triangle& b) {
  auto [ax0, ax1] = std::minmax({a.x[0], a.x[1], a.x[2]});
  auto [ay0, ay1] = std::minmax({a.y[0], a.y[1], a.y[2]});
  auto [bx0, bx1] = std::minmax({b.x[0], b.x[1], b.x[2]});
  auto [by0, by1] = std::minmax({b.y[0], b.y[1], b.y[2]});
  return ax0 < bx1 && bx0 < ax1 && ay0 < by1 && by0 < ay1;
}

}  // namespace

std::vector<Area> visible_areas(const std::vector<Triangle>& tris, int64_t clip_x0, int64_t clip_y0,
                                int64_t clip_x1, int64_t clip_y1) {
  if (!(clip_x0 < clip_x1 && clip_y0 < clip_y1))
    throw std::invalid_argument("oracle: empty viewport rectangle");
  const size_t n = tris.size();
  std::vector<Int128> orientation(n);
  std::vector<Polygon> polygons(n);
  for (size_t i = 0; i < n; ++i) {
    if (tris[i].z_min > tris[i].z_max)
      throw std::invalid_argument("oracle: triangle " + std::to_string(tris[i].id) + " has z_min > z_max");
    orientation[i] = orient(tris[i]);
    if (orientation[i] != 0) polygons[i] = ccw_polygon(tris[i], orientation[i]);
  }

  // The depth-order precondition, checked exactly: overlapping interiors (a regularised
  // intersection of positive area) with intersecting depth ranges would make "nearer"
  // undefined somewhere, so the answer would depend on what the oracle guessed.
  for (size_t i = 0; i < n; ++i) {
    if (orientation[i] == 0) continue;
    for (size_t j = i + 1; j < n; ++j) {
      if (orientation[j] == 0) continue;
      const Triangle &a = tris[i], &b = tris[j];
      if (a.z_max < b.z_min || b.z_max < a.z_min) continue;
      if (!bbox_interiors_overlap(a, b)) continue;
      PolygonSet common(polygons[i]);
      common.intersection(polygons[j]);
      if (!common.is_empty())
        throw std::invalid_argument("oracle: triangles " + std::to_string(a.id) + " and " + std::to_string(b.id) +
                                    " overlap with intersecting depth ranges");
    }
  }

  // Front to back by z_min. For two overlapping triangles the ranges are disjoint, so the
  // one with the smaller z_min is entirely nearer; a triangle sorted earlier that is not
  // nearer does not overlap, and subtracting it removes no area. So the union of the
  // triangles already swept is, area-wise, exactly the union of those nearer.
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return tris[a].z_min < tris[b].z_min; });

  Polygon viewport;
  viewport.push_back(Point(exact_coord(clip_x0), exact_coord(clip_y0)));
  viewport.push_back(Point(exact_coord(clip_x1), exact_coord(clip_y0)));
  viewport.push_back(Point(exact_coord(clip_x1), exact_coord(clip_y1)));
  viewport.push_back(Point(exact_coord(clip_x0), exact_coord(clip_y1)));
  // Rectangle corners listed x0y0, x1y0, x1y1, x0y1 run counter-clockwise in (x, y).

  std::vector<Area> result(n, Area{"0", "1", 0.0});
  PolygonSet covered;  // union of the triangles swept so far, inside the viewport
  for (size_t i : order) {
    if (orientation[i] == 0) continue;  // zero area: nothing to see, nothing hidden
    PolygonSet inside(viewport);
    inside.intersection(polygons[i]);
    if (inside.is_empty()) continue;
    PolygonSet visible(inside);
    visible.difference(covered);
    result[i] = to_area(area(visible));
    covered.join(inside);
  }
  return result;
}

}  // namespace tilevis::oracle
