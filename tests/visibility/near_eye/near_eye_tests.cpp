// Near the eye (w ~ 0): primitive setup against an independent exact clipper, golden against
// the z-buffer truth at every tile size, and no valid trace aborting a frame.
#include <map>

#include <gtest/gtest.h>

#include "exact_clipper.h"
#include "near_eye_scenes.h"
#include "visibility/golden.h"
#include "visibility/setup.h"
#include "visibility/truth.h"

using namespace tilevis;

namespace {

// The setup triangles of each trace triangle put back together as the clipped polygon
// (a fan around its first vertex), and whether they are front-facing.
struct SetupPolygon {
  std::vector<geom::Vertex> polygon;
  bool front = false;
  bool any_piece = false;
};

std::map<uint32_t, SetupPolygon> setup_polygons(const vis::Setup& s) {
  std::map<uint32_t, SetupPolygon> out;
  for (const vis::SetupTriangle& t : s.triangles) {
    SetupPolygon& p = out[t.id];
    if (p.polygon.empty()) p.polygon = {t.v[0], t.v[1], t.v[2]};
    else p.polygon.push_back(t.v[2]);
    p.front = p.front || t.front;
  }
  return out;
}

// Every trace triangle: the same snapped polygon as the exact clipper, and front-facing
// exactly when the exact det[x y w] is positive (unless every piece snapped to nothing).
void expect_setup_exact(const trace::Frame& f, const std::string& what) {
  const vis::Setup s = vis::primitive_setup(f, {});
  const auto got = setup_polygons(s);
  for (const near_eye::ExactTriangle& e : near_eye::exact_clip(f)) {
    const auto it = got.find(e.id);
    const bool culled = e.facing == 0 || e.polygon.empty();
    if (culled) {
      EXPECT_TRUE(it == got.end()) << what << ": triangle " << e.id << " should be culled";
      continue;
    }
    ASSERT_TRUE(it != got.end()) << what << ": triangle " << e.id << " lost by setup";
    ASSERT_EQ(it->second.polygon.size(), e.polygon.size()) << what << ": triangle " << e.id;
    for (size_t k = 0; k < e.polygon.size(); ++k)
      EXPECT_EQ(it->second.polygon[k], e.polygon[k]) << what << ": triangle " << e.id << " vertex " << k;
    if (it->second.front) {
      EXPECT_GT(e.facing, 0) << what << ": triangle " << e.id;
    }
    if (e.facing < 0) {
      EXPECT_FALSE(it->second.front) << what << ": triangle " << e.id;
    }
  }
}

void expect_golden_equals_truth(const trace::Frame& f, const std::string& what) {
  const vis::Setup s = vis::primitive_setup(f, {});
  const vis::TruthResult truth = vis::zbuffer_truth(s, {});
  uint64_t near_samples = 0;
  for (int32_t id : truth.ids) near_samples += id >= 0 && uint32_t(id) < s.triangle_draw.size() && s.triangle_draw[size_t(id)] == 0;
  EXPECT_GT(near_samples, 0u) << what << ": the near-eye triangles must be visible somewhere";
  for (uint32_t tile : {4u, 8u, 16u, 32u, 64u, 128u, 256u}) {
    vis::GoldenConfig cfg;
    cfg.tile_w = cfg.tile_h = tile;
    const vis::GoldenResult g = vis::golden_visibility(s, cfg);
    uint64_t mismatched = 0;
    for (size_t k = 0; k < g.ids.size(); ++k) mismatched += g.ids[k] != truth.ids[k];
    EXPECT_EQ(mismatched, 0u) << what << " at " << tile << "x" << tile << " tiles";
  }
}

TEST(NearEye, TwoTrianglesAtOneDepthOverTheFarPlane) {
  const trace::Frame f = near_eye::two_triangles(480, 270, 0.0f, 0.0f);
  expect_setup_exact(f, "coplanar pair");
  expect_golden_equals_truth(f, "coplanar pair");
}

TEST(NearEye, TwoTrianglesAtTwoDepthsOverTheFarPlane) {
  const trace::Frame f = near_eye::two_triangles(480, 270, 0.5f, -0.25f);
  expect_setup_exact(f, "pair at two depths");
  expect_golden_equals_truth(f, "pair at two depths");
}

TEST(NearEye, RandomNearEyeScenes) {
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    const trace::Frame f = near_eye::random_near_eye(seed, 60, 320, 180);
    expect_setup_exact(f, "random scene " + std::to_string(seed));
    expect_golden_equals_truth(f, "random scene " + std::to_string(seed));
  }
}

// A vertex at |w| down to 2^-126, or the eye itself, never aborts a frame; setup agrees
// with the exact clipper on what it keeps and on facing.
TEST(NearEye, NearZeroWNeverAbortsAFrame) {
  uint64_t kept = 0, edge_on = 0;
  for (uint64_t seed = 0; seed < 600; ++seed) {
    const trace::Frame f = near_eye::near_zero_w(seed, 160, 90);
    vis::Setup s;
    ASSERT_NO_THROW(s = vis::primitive_setup(f, {})) << "seed " << seed;
    ASSERT_NO_THROW(vis::zbuffer_truth(s, {})) << "seed " << seed;
    kept += !s.triangles.empty();
    edge_on += s.stats.edge_on;
    expect_setup_exact(f, "near-zero w, seed " + std::to_string(seed));
  }
  EXPECT_GT(kept, 100u);   // the cases are not all trivially culled
  EXPECT_GE(edge_on, 12u);  // every 50th seed puts a vertex at the eye
}

}  // namespace
