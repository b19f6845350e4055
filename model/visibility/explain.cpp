#include "visibility/explain.h"

#include <algorithm>
#include <unordered_map>

#include "geom/clip.h"
#include "geom/depth.h"
#include "geom/polygon.h"

namespace tilevis::vis {
namespace {

// Setup triangles of one original id (a near-clipped triangle is a fan of several).
struct Owner {
  std::vector<const SetupTriangle*> parts;
};

const SetupTriangle* part_covering(const Owner& o, geom::Point s) {
  for (const SetupTriangle* t : o.parts)
    if (geom::TriangleEdges::from(t->v[0].xy(), t->v[1].xy(), t->v[2].xy()).covers(s)) return t;
  return nullptr;
}

geom::Triangle tri(const SetupTriangle* t) { return geom::Triangle{{t->v[0], t->v[1], t->v[2]}}; }

// Do the two triangles interpenetrate, i.e. does their depth order change sign over the
// overlap of their projections? Checked exactly at the overlap polygon's vertices (the
// depth difference is affine, so its extremes are there).
bool interpenetrate(const SetupTriangle* p, const SetupTriangle* q) {
  geom::ConvexPolygon overlap = geom::ConvexPolygon::from_triangle(tri(p));
  geom::ConvexPolygon other = geom::ConvexPolygon::from_triangle(tri(q));
  for (const auto& e : other.edges()) overlap = geom::clip(overlap, e.line);
  if (overlap.empty()) return false;
  const auto dp = geom::DepthPlane::from(tri(p)), dq = geom::DepthPlane::from(tri(q));
  bool nearer = false, farther = false;
  for (const auto& e : overlap.edges()) {
    int o = geom::depth_order(dp, dq, e.start);
    nearer = nearer || o < 0;
    farther = farther || o > 0;
  }
  return nearer && farther;
}

// Does some front-facing triangle interpenetrate t (anywhere)?
bool pierced(const Setup& s, const SetupTriangle* t) {
  for (const auto& u : s.triangles)
    if (u.front && u.id != t->id && interpenetrate(t, &u)) return true;
  return false;
}

}  // namespace

MismatchReport explain_mismatches(const Setup& s, const std::vector<int32_t>& a, const std::vector<int32_t>& b) {
  MismatchReport r;
  std::unordered_map<uint32_t, Owner> owners;
  for (const auto& t : s.triangles)
    if (t.front) owners[t.id].parts.push_back(&t);
  const size_t n = s.samples.size();
  for (size_t k = 0; k < a.size() && k < b.size(); ++k) {
    if (a[k] == b[k]) continue;
    ++r.mismatched;
    const size_t pixel = k / n;
    const geom::Point p{int32_t(((pixel % s.width) << s.subpixel_bits) + s.samples[k % n].x),
                        int32_t(((pixel / s.width) << s.subpixel_bits) + s.samples[k % n].y)};
    std::string kind;
    if (a[k] < 0 || b[k] < 0) {
      // One shows background: the other's triangle covers the sample, so a piece of it was
      // judged hidden there; penetration by another triangle is what makes that possible.
      const SetupTriangle* t = part_covering(owners[uint32_t(std::max(a[k], b[k]))], p);
      kind = t && pierced(s, t) ? "background on one side: the covering triangle is pierced by another"
                                : "unexplained: background on one side, no interpenetration";
    } else {
      const SetupTriangle* ta = part_covering(owners[uint32_t(a[k])], p);
      const SetupTriangle* tb = part_covering(owners[uint32_t(b[k])], p);
      if (!ta || !tb) {
        kind = "an id does not cover its sample";
      } else {
        const int o = geom::depth_order(geom::DepthPlane::from(tri(ta)), geom::DepthPlane::from(tri(tb)), p);
        if (o == 0)
          kind = "equal depth at the sample (tie)";
        else if (interpenetrate(ta, tb))
          kind = "the two triangles interpenetrate";
        else if (pierced(s, ta) || pierced(s, tb))
          kind = "a third triangle interpenetrates one of the two";
        else
          kind = "unexplained (no interpenetration, no tie): a pipeline error";
      }
    }
    if (++r.kinds[kind] <= 3)
      r.examples.push_back("sample " + std::to_string(k) + " (" + std::to_string(pixel % s.width) + ", " +
                           std::to_string(pixel / s.width) + "): " + std::to_string(a[k]) + " vs " +
                           std::to_string(b[k]) + ": " + kind);
  }
  return r;
}

}  // namespace tilevis::vis
