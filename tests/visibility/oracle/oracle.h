// Exact visible-area oracle for the golden visibility pipeline (DESIGN.md "Validation
// chain": golden ⇄ CGAL exact booleans on small scenes). Independent of model/geom: it
// answers with CGAL's exact rational Boolean set operations, so a shared bug in TileVis's
// own predicates or clipper cannot make both sides agree. No CGAL type crosses this
// header, so test files compile without CGAL's heavy templates.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace tilevis::oracle {

// Window coordinates in integer sub-pixel units (y down) and the triangle's depth range
// (smaller z = nearer). Either vertex orientation is accepted. `id` only names the
// triangle in error messages.
struct Triangle {
  int64_t x[3], y[3];
  uint32_t z_min, z_max;
  int32_t id;
};

// An exact non-negative rational in lowest terms (den > 0, "0"/"1" for zero), and
// CGAL::to_double of it (correct to about an ulp: compare exactly through num/den).
struct Area {
  std::string num, den;
  double value;
};

// Per input triangle (same order): area((T ∩ viewport) \ ∪{projections of triangles
// nearer than T}) in (sub-pixel units)². The viewport is the closed rectangle
// [x0,x1]×[y0,y1]. Zero-area triangles get area 0 and never occlude.
// Preconditions, checked (std::invalid_argument): x0 < x1, y0 < y1, z_min <= z_max,
// |coordinates| <= 2^53, and every two non-degenerate triangles whose projections overlap
// with positive area have disjoint depth ranges (the scene is depth-ordered, no ties).
// Meant for small scenes (up to a few hundred triangles): one exact intersection and one
// difference per triangle against the growing union of nearer ones.
std::vector<Area> visible_areas(const std::vector<Triangle>& tris, int64_t clip_x0, int64_t clip_y0,
                                int64_t clip_x1, int64_t clip_y1);

}  // namespace tilevis::oracle
