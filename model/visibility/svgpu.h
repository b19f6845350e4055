// SVGPU's per-tile decisions as public functions (Ellis, Hunt & Hart, HPG 2016, §3.2-3.3), on
// snapped integer geometry and exact predicates: the culling tests of a silhouette edge against
// a triangle, the split of a piece, the occlusion test of a piece's interior point, and the
// hybrid mode's test for where the method can be wrong. The golden pipeline is built from
// them; the SystemC model inherits them through it; RTL scoreboards and the CUDA emulation
// tests call them directly.
#pragma once

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "geom/clip.h"
#include "geom/depth.h"
#include "geom/polygon.h"
#include "geom/predicates.h"

namespace tilevis::vis::svgpu {

// A front-facing triangle as the tile stage sees it.
struct Triangle {
  geom::Triangle tri;
  geom::TriangleEdges edges;
  geom::DepthPlane plane;
  geom::Rect bbox;  // closed, sub-pixel units
  uint32_t z_min = 0, z_max = 0;
  static Triangle from(const geom::Vertex& a, const geom::Vertex& b, const geom::Vertex& c);
};

// A silhouette edge as the tile stage sees it.
struct Edge {
  geom::Vertex a, b;
  geom::Line line;
  uint32_t z_min = 0, z_max = 0;
  geom::Rect bbox;
  static Edge from(const geom::Vertex& a, const geom::Vertex& b);
};

// Test 6 (§3.2.1): the triangle's farthest depth is nearer than the edge's nearest, so the
// edge cannot split it (nor can any edge that is farther still).
inline bool edge_behind(uint32_t edge_z_min, const Triangle& t) { return edge_z_min > t.z_max; }
inline bool edge_behind(const Edge& e, const Triangle& t) { return edge_behind(e.z_min, t); }

// The bounding boxes at most touch: the segment cannot meet the triangle's interior (test 2's cheap form).
inline bool boxes_apart(const geom::Rect& e, const geom::Rect& t) {
  return e.x1 <= t.x0 || e.x0 >= t.x1 || e.y1 <= t.y0 || e.y0 >= t.y1;
}
inline bool boxes_apart(const Edge& e, const Triangle& t) { return boxes_apart(e.bbox, t.bbox); }

// Test 4: the silhouette edge is one of the triangle's own edges.
bool shares_edge(const Edge& e, const geom::Triangle& t);

// Tests 1-3 of an edge against a piece of triangle t: true when the pair survives, i.e. the
// piece must be split by the edge's line. 1: the piece lies on one side of the line; 2: the
// segment misses the piece's interior; 3: over the part of the segment inside the piece the
// edge is behind t's plane. An edge level with the plane at both ends of that part survives:
// it can bound a coplanar occluder whose tie (the earlier triangle in front) the piece's
// interior point then decides.
bool survives(const geom::ConvexPolygon& piece, const Triangle& t, const Edge& e);

// The clip step (§3.2.2): both sides of the piece, inside (the line's positive side) first.
inline geom::SplitResult split(const geom::ConvexPolygon& piece, const Edge& e) { return geom::split(piece, e.line); }

// Occlusion (§3.3) of a piece of t by an original opaque triangle u at the piece's interior
// point q: u contains q and is nearer there; at equal depth the earlier-submitted triangle
// (smaller id) stays in front, as under a less-than depth test.
bool occludes(const Triangle& u, uint32_t u_id, const Triangle& t, uint32_t t_id, const geom::RationalPoint& q);

// Hybrid: do the planes of t and u cross strictly inside their overlap within `region` (a
// convex polygon, e.g. t clipped to the tile)? Depth is affine over the overlap, so they cross
// exactly when z_u - z_t is positive at one of its vertices and negative at another. Where no
// pair of a tile's triangles crosses, silhouette splitting makes the analytic answer exact.
bool planes_cross(const geom::ConvexPolygon& region, const Triangle& t, const Triangle& u);

// planes_cross's cheap screen (integer compares): the depth ranges overlap strictly and the
// bounding boxes overlap with area. Where it fails, the planes cannot cross in the overlap.
inline bool may_cross(const Triangle& t, const Triangle& u) {
  return u.z_min < t.z_max && u.z_max > t.z_min && u.bbox.x1 > t.bbox.x0 && u.bbox.x0 < t.bbox.x1 &&
         u.bbox.y1 > t.bbox.y0 && u.bbox.y0 < t.bbox.y1;
}

// Do t and u (both front-facing) share an edge from opposite sides (t runs a -> b, u b -> a),
// as mesh neighbours do? Then they lie on opposite sides of it on screen: their overlap has no
// area and their planes cannot cross inside it (vertex compares only).
bool opposite_neighbours(const geom::Triangle& t, const geom::Triangle& u);

// The longest chain of dependent steps in clipping one triangle when every piece is walked by its
// own worker through the candidates after the one that cut it off, `width` candidates tested at
// once (cuda_ref's k_clip_long tree: a warp, 32): a step per `width` candidates that the piece
// survives none of, one per split, and a piece cut off starts when the step that cut it ends. With
// workers enough this bounds the item's time from below; the steps of all its walks (work) are
// the tree's loop trips. Feed it the clip's splits in the order §3.2.2 makes them (candidate by
// candidate, pieces in their order); pieces are numbered as the clip appends them, the root 0.
class WalkChain {
 public:
  explicit WalkChain(uint64_t width = 32) : m_width(width) {}
  void start() {
    m_walk.assign(1, Walk{});
    m_splits = 0;
  }
  // Piece `piece` is split by the candidate at position `ci`; `cut_off`: a new piece is appended.
  void split(size_t piece, uint64_t ci, bool cut_off) {
    Walk& w = m_walk[piece];
    w.steps += (ci - w.pos) / m_width + 1;
    w.pos = ci + 1;
    ++w.splits;
    ++m_splits;
    if (cut_off) m_walk.push_back({w.pos, w.steps, w.steps, w.splits});
  }
  // Over `candidates` candidates: the longest walk's end (steps), and every walk's own steps.
  uint64_t longest(uint64_t candidates) const { return longest_walk(candidates).second; }
  // How many of the longest chain's steps are splits (the first longest walk's): a split step
  // costs cuda_ref's warp many times one without a survivor (reports/cuda/clip_chord_h200.md).
  uint64_t longest_splits(uint64_t candidates) const {
    return m_walk.empty() ? 0 : m_walk[longest_walk(candidates).first].splits;
  }
  // Splits of all walks: the work's steps that split.
  uint64_t splits() const { return m_splits; }
  uint64_t work(uint64_t candidates) const {
    uint64_t sum = 0;
    for (const Walk& w : m_walk) sum += end(w, candidates) - w.start;
    return sum;
  }

 private:
  struct Walk {
    uint64_t pos = 0, steps = 0, start = 0;  // next candidate position, steps so far (from the item's start), first step
    uint64_t splits = 0;                     // splits on its chain so far (its parent's when it was cut off, then its own)
  };
  std::pair<size_t, uint64_t> longest_walk(uint64_t candidates) const {  // (the first longest walk, its end)
    std::pair<size_t, uint64_t> best{0, 0};
    for (size_t k = 0; k < m_walk.size(); ++k)
      if (const uint64_t e = end(m_walk[k], candidates); e > best.second) best = {k, e};
    return best;
  }
  uint64_t end(const Walk& w, uint64_t candidates) const {
    return w.steps + (w.pos < candidates ? (candidates - w.pos + m_width - 1) / m_width : 0);
  }
  uint64_t m_width;
  uint64_t m_splits = 0;
  std::vector<Walk> m_walk;
};

}  // namespace tilevis::vis::svgpu
