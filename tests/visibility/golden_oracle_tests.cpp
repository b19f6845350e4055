// The golden pipeline's per-triangle visible area equals the exact one from CGAL's
// Boolean set operations, and its id buffer equals the z-buffer truth, on random
// non-penetrating scenes (DESIGN.md "Validation chain").
#include <cmath>

#include <gtest/gtest.h>

#include "random_scenes.h"
#include "visibility/golden.h"
#include "visibility/setup.h"
#include "visibility/truth.h"

using namespace tilevis;

namespace {

struct Case {
  const char* name;
  oracle::SceneOptions options;
  uint32_t tile_w, tile_h;
};

oracle::SceneOptions opts(uint32_t triangles, uint32_t draws, double huge, double sliver, double tilted, double back,
                          double degenerate, bool meshes) {
  oracle::SceneOptions o;
  o.triangles = triangles;
  o.draws = draws;
  o.huge_fraction = huge;
  o.sliver_fraction = sliver;
  o.tilted_fraction = tilted;
  o.back_fraction = back;
  o.degenerate_fraction = degenerate;
  o.meshes = meshes;
  return o;
}

class GoldenVsCgal : public ::testing::TestWithParam<Case> {};

TEST_P(GoldenVsCgal, VisibleAreasAreExactAndIdsMatchTheTruth) {
  const Case& c = GetParam();
  uint64_t triangles_checked = 0, occluded = 0;
  for (uint64_t seed = 1; seed <= 60; ++seed) {
    oracle::SceneOptions o = c.options;
    o.seed = seed;
    const oracle::RandomScene scene = oracle::random_scene(o);
    const vis::Setup s = vis::primitive_setup(scene.frame, {});
    vis::GoldenConfig gc;
    gc.tile_w = c.tile_w;
    gc.tile_h = c.tile_h;
    const vis::GoldenResult g = vis::golden_visibility(s, gc);
    const auto exact = oracle::visible_areas(scene.triangles, 0, 0, oracle::kSceneSize * oracle::kSubpixel,
                                             oracle::kSceneSize * oracle::kSubpixel);
    std::vector<bool> front(g.visible_area.size(), false);
    for (size_t i = 0; i < scene.triangles.size(); ++i) {
      const auto id = size_t(scene.triangles[i].id);
      front[id] = true;
      // Oracle areas are in sub-pixel units²; golden's in pixels².
      const double want = exact[i].value / double(oracle::kSubpixel * oracle::kSubpixel);
      const double got = g.visible_area[id];
      const double tol = 1e-9 * std::max(want, 1e-300);
      ASSERT_NEAR(got, want, tol) << "seed " << seed << " triangle " << id << " exact " << exact[i].num << "/"
                                  << exact[i].den;
      ++triangles_checked;
      occluded += exact[i].num == "0";
    }
    for (size_t id = 0; id < front.size(); ++id) {
      if (!front[id]) {
        EXPECT_EQ(g.visible_area[id], 0.0) << "back-facing or degenerate triangle " << id;
      }
    }
    const vis::TruthResult t = vis::zbuffer_truth(s, {});
    for (size_t k = 0; k < t.ids.size(); ++k) ASSERT_EQ(g.ids[k], t.ids[k]) << "seed " << seed << " sample " << k;
  }
  EXPECT_GT(triangles_checked, 100u);
  EXPECT_GT(occluded, 0u);  // the scenes really hide something
}

INSTANTIATE_TEST_SUITE_P(
    Scenes, GoldenVsCgal,
    ::testing::Values(Case{"loose", opts(12, 1, 0.1, 0.1, 0.3, 0.0, 0.0, false), 32, 32},
                      Case{"dense_small_tiles", opts(40, 3, 0.1, 0.2, 0.4, 0.2, 0.1, false), 4, 4},
                      Case{"huge_and_slivers", opts(20, 2, 0.4, 0.4, 0.5, 0.0, 0.0, false), 16, 16},
                      Case{"meshes", opts(48, 2, 0.2, 0.1, 0.0, 0.2, 0.0, true), 32, 32},
                      Case{"meshes_odd_tiles", opts(48, 4, 0.2, 0.1, 0.0, 0.0, 0.0, true), 7, 13},
                      Case{"one_tile", opts(30, 1, 0.2, 0.2, 0.3, 0.1, 0.1, false), 256, 256}),
    [](const ::testing::TestParamInfo<Case>& i) { return std::string(i.param.name); });

}  // namespace
