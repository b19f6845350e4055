// The public SVGPU functions (visibility/svgpu.h) on hand-made cases: each test of §3.2.1,
// the split, the occlusion test with its tie rule, and the hybrid's crossing test.
#include <gtest/gtest.h>

#include "visibility/svgpu.h"

using namespace tilevis;
using geom::Vertex;
namespace sv = vis::svgpu;

namespace {

constexpr int32_t P = 256;  // one pixel in sub-pixel units

Vertex v(int32_t x, int32_t y, uint32_t z) { return {x * P, y * P, z}; }

// Counter-clockwise in NDC = clockwise on screen (y down), as setup keeps front faces.
sv::Triangle front(Vertex a, Vertex b, Vertex c) { return sv::Triangle::from(a, c, b); }

geom::ConvexPolygon poly_of(const sv::Triangle& t) { return geom::ConvexPolygon::from_triangle(t.tri); }

const sv::Triangle kFar = front(v(0, 0, 1000), v(100, 0, 1000), v(0, 100, 1000));

}  // namespace

TEST(Svgpu, ANearEdgeAcrossTheTriangleSurvives) {
  const sv::Edge e = sv::Edge::from(v(10, -10, 10), v(10, 200, 10));
  EXPECT_FALSE(sv::edge_behind(e, kFar));
  EXPECT_FALSE(sv::boxes_apart(e, kFar));
  EXPECT_FALSE(sv::shares_edge(e, kFar.tri));
  EXPECT_TRUE(sv::survives(poly_of(kFar), kFar, e));
  const geom::SplitResult parts = sv::split(poly_of(kFar), e);
  EXPECT_FALSE(parts.inside.empty());
  EXPECT_FALSE(parts.outside.empty());
}

TEST(Svgpu, EachTestRejectsItsCase) {
  // Test 1: the line misses the triangle (it lies on one side).
  EXPECT_FALSE(sv::survives(poly_of(kFar), kFar, sv::Edge::from(v(200, -10, 10), v(200, 200, 10))));
  // Test 2: the line crosses, the segment stops short of the triangle.
  EXPECT_FALSE(sv::survives(poly_of(kFar), kFar, sv::Edge::from(v(10, -50, 10), v(10, -10, 10))));
  // Test 3: the edge is behind the triangle over their overlap.
  EXPECT_FALSE(sv::survives(poly_of(kFar), kFar, sv::Edge::from(v(10, -10, 5000), v(10, 200, 5000))));
  // Test 4: the triangle's own edge.
  EXPECT_TRUE(sv::shares_edge(sv::Edge::from(kFar.tri.v[0], kFar.tri.v[1]), kFar.tri));
  // Test 6: the edge's nearest depth is beyond the triangle's farthest.
  EXPECT_TRUE(sv::edge_behind(sv::Edge::from(v(10, -10, 2000), v(10, 200, 2000)), kFar));
}

TEST(Svgpu, AnEdgeLevelWithThePlaneSurvives) {
  // A coplanar occluder's edge lies in the plane: it must split, so the tie is judged per piece.
  EXPECT_TRUE(sv::survives(poly_of(kFar), kFar, sv::Edge::from(v(10, -10, 1000), v(10, 200, 1000))));
  // Level at one end only, behind elsewhere: nothing to split.
  EXPECT_FALSE(sv::survives(poly_of(kFar), kFar, sv::Edge::from(v(10, -10, 1000), v(10, 200, 3000))));
}

TEST(Svgpu, OcclusionAndItsTieRule) {
  const sv::Triangle near = front(v(0, 0, 10), v(100, 0, 10), v(0, 100, 10));
  const sv::Triangle same = kFar;
  const geom::RationalPoint inside = geom::interior_point(geom::ConvexPolygon::from_triangle(
      geom::Triangle{{v(5, 5, 0), v(6, 5, 0), v(5, 6, 0)}}));
  EXPECT_TRUE(sv::occludes(near, 7, kFar, 3, inside));   // nearer: hides, whatever the order
  EXPECT_FALSE(sv::occludes(kFar, 3, near, 7, inside));  // farther: never
  EXPECT_TRUE(sv::occludes(same, 2, kFar, 3, inside));   // equal depth: the earlier one stays in front
  EXPECT_FALSE(sv::occludes(same, 4, kFar, 3, inside));
  const geom::RationalPoint outside = geom::interior_point(geom::ConvexPolygon::from_triangle(
      geom::Triangle{{v(80, 80, 0), v(81, 80, 0), v(80, 81, 0)}}));
  EXPECT_FALSE(sv::occludes(near, 7, kFar, 3, outside));  // not under the occluder
}

TEST(Svgpu, PlanesCrossOnlyWhereTheyInterpenetrate) {
  // A tilted triangle through kFar's plane inside their overlap, one wholly in front, one touching.
  const sv::Triangle through = front(v(0, 0, 0), v(100, 0, 2000), v(0, 100, 0));
  const sv::Triangle in_front = front(v(0, 0, 10), v(100, 0, 900), v(0, 100, 10));
  const sv::Triangle touching = front(v(0, 0, 1000), v(100, 0, 0), v(0, 100, 0));
  const geom::ConvexPolygon region = poly_of(kFar);
  EXPECT_TRUE(sv::planes_cross(region, kFar, through));
  EXPECT_FALSE(sv::planes_cross(region, kFar, in_front));
  EXPECT_FALSE(sv::planes_cross(region, kFar, touching));
  // Crossing outside the region does not count: the left half keeps one order.
  const geom::ConvexPolygon left = geom::clip_to_rect(region, {0, 0, 20 * P, 100 * P});
  const sv::Triangle cross_right = front(v(0, 0, 500), v(100, 0, 1500), v(0, 100, 500));
  EXPECT_TRUE(sv::planes_cross(region, kFar, cross_right));
  EXPECT_FALSE(sv::planes_cross(left, kFar, cross_right));
}

// The clip's chain of dependent steps when each piece is walked on its own, 32 candidates a step
// (svgpu::WalkChain, cuda_ref's k_clip_long tree), on hand-made split sequences.
TEST(Svgpu, WalkChainCountsTheLongestWalk) {
  sv::WalkChain w;
  w.start();
  EXPECT_EQ(w.longest(0), 0u);      // no candidates: nothing to walk
  EXPECT_EQ(w.longest(1), 1u);      // one step tests up to 32
  EXPECT_EQ(w.longest(32), 1u);
  EXPECT_EQ(w.longest(100), 4u);    // 32 + 32 + 32 + 4
  // The root split at candidates 0, 1 and 2: three steps, then 97 candidates (4 steps): 7. The
  // piece cut off at 0 starts after step 1 at candidate 1: 1 + 4 = 5; at 2: 3 + 4 = 7.
  w.split(0, 0, true);
  w.split(0, 1, true);
  w.split(0, 2, true);
  EXPECT_EQ(w.longest(100), 7u);
  EXPECT_EQ(w.longest_splits(100), 3u);  // the root's chain: 3 splits and 4 steps without one
  EXPECT_EQ(w.splits(), 3u);
  EXPECT_EQ(w.work(100), 7u + 4u + 4u + 4u);  // the root's 7; pieces 1-3 walk 99, 98, 97 candidates
  // Piece 1 (cut off at 0, time 1, next candidate 1) splits at 40: one step without a survivor
  // (candidates 1-32), one for the split; then 59 candidates left (2 steps): 1 + 2 + 2 = 5. Its
  // own cut-off piece starts at time 3 at candidate 41: 3 + 2 = 5. The root's 7 stays longest.
  w.split(1, 40, true);
  EXPECT_EQ(w.longest(100), 7u);
  // A chain: piece 4 (cut off at 40) is split at 41, 42, ..., 99, each a step: 3 + 59 = 62.
  for (uint64_t ci = 41; ci < 100; ++ci) w.split(4, ci, ci % 2 == 0);
  EXPECT_EQ(w.longest(100), 62u);
  // Its 62 steps: the root's split at 0, piece 1's step without a survivor and its split at 40,
  // then piece 4's 59 splits.
  EXPECT_EQ(w.longest_splits(100), 61u);
  EXPECT_EQ(w.splits(), 3u + 1u + 59u);
  // Piece 1 walked 2 + 2 steps, piece 4 its 59 splits; pieces 5-33, cut off at the even
  // candidates 42-98, walk what follows them: 2 steps each from 42-66 (13), 1 from 68-98 (16).
  EXPECT_EQ(w.work(100), 7u + 4u + 4u + 4u + 59u + 13u * 2u + 16u);
  // Splits that cut nothing off (the outside part empty) still take their step.
  sv::WalkChain v(8);
  v.start();
  v.split(0, 20, false);  // steps: 2 rounds of 8 (0-15), then the split: 3; next candidate 21
  EXPECT_EQ(v.longest(21), 3u);
  EXPECT_EQ(v.longest_splits(21), 1u);
  EXPECT_EQ(v.longest(30), 5u);  // + candidates 21-28, 29: 2 steps
}
