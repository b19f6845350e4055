// Hybrid visibility: tiles where the analytic answer can be wrong go per pixel, so the result
// equals the exact z-buffer truth on interpenetrating, non-opaque and overloaded content,
// while tiles where it cannot be wrong stay analytic (same ids, counters and exact areas).


#include <gtest/gtest.h>

#include "scene_frames.h"
#include "visibility/golden.h"
#include "visibility/setup.h"
#include "visibility/truth.h"

using namespace tilevis;

namespace {

using testsupport::frame_of;

uint64_t mismatches(const std::vector<int32_t>& a, const std::vector<int32_t>& b) {
  uint64_t n = 0;
  for (size_t i = 0; i < a.size(); ++i) n += a[i] != b[i];
  return n;
}

// Two boxes through each other and a sphere through the floor: planes cross inside overlaps.
const char* kInterpenetrating = R"({
  "viewport": [320, 240],
  "camera": {"eye": [1.8, 1.4, 3.0], "target": [0, 0, 0], "fov_y_deg": 50, "near": 0.1, "far": 20},
  "objects": [
    {"name": "floor", "primitive": {"type": "plane", "size": [6, 6], "subdivisions": 2}, "transform": {"translate": [0, -0.5, 0]}},
    {"name": "box_a", "primitive": {"type": "box", "size": [1, 1, 1]}, "transform": {"rotate_deg": [0, 20, 0]}},
    {"name": "box_b", "primitive": {"type": "box", "size": [1.2, 0.6, 0.6]}, "transform": {"translate": [0.4, 0.1, 0.2], "rotate_deg": [15, 60, 5]}},
    {"name": "ball", "primitive": {"type": "sphere", "radius": 0.5, "segments": 20, "rings": 10}, "transform": {"translate": [-1.0, -0.6, 0.6]}}
  ]})";

// An opaque box behind a blended card: non-opaque triangles never occlude.
const char* kBlended = R"({
  "viewport": [240, 180],
  "camera": {"eye": [0, 0, 3], "target": [0, 0, 0]},
  "objects": [
    {"name": "box", "primitive": {"type": "box", "size": [1, 1, 1]}, "transform": {"rotate_deg": [20, 30, 0]}},
    {"name": "glass", "primitive": {"type": "quads", "count": 1, "size": [0.4, 0.3], "origin": [-0.9, 0.6, 1]}, "flags": ["blended"]}
  ]})";

void expect_hybrid_is_truth(const trace::Frame& f, const std::string& what, uint64_t budget = 0) {
  const vis::Setup s = vis::primitive_setup(f, {});
  const vis::TruthResult truth = vis::zbuffer_truth(s, {});
  for (uint32_t tile : {8u, 32u, 128u}) {
    vis::GoldenConfig cfg;
    cfg.tile_w = cfg.tile_h = tile;
    cfg.mode = "hybrid";
    cfg.options.pair_budget = budget;
    const vis::GoldenResult h = vis::golden_visibility(s, cfg);
    EXPECT_EQ(mismatches(h.ids, truth.ids), 0u) << what << " at " << tile << "x" << tile << " tiles";
    EXPECT_GT(h.fallback_tiles, 0u) << what << ": nothing went per pixel";
    EXPECT_LT(h.fallback_tiles, h.tiles.rows.size()) << what << ": everything went per pixel";
  }
}

}  // namespace

TEST(Hybrid, EqualsTheTruthWhereMeshesInterpenetrate) {
  for (uint32_t samples : {1u, 4u}) {
    const trace::Frame f = frame_of("interpenetrating", kInterpenetrating, samples);
    const vis::Setup s = vis::primitive_setup(f, {});
    vis::GoldenConfig analytic;
    // The case is real: the analytic method alone loses samples here.
    EXPECT_GT(mismatches(vis::golden_visibility(s, analytic).ids, vis::zbuffer_truth(s, {}).ids), 0u);
    expect_hybrid_is_truth(f, "interpenetrating, " + std::to_string(samples) + " samples");
  }
}

TEST(Hybrid, NonOpaqueTilesGoPerPixel) {
  const trace::Frame f = frame_of("blended", kBlended);
  expect_hybrid_is_truth(f, "blended card");
  vis::GoldenConfig cfg;
  cfg.mode = "hybrid";
  const vis::GoldenResult h = vis::golden_visibility(vis::primitive_setup(f, {}), cfg);
  EXPECT_EQ(h.fallback_tiles, h.fallback_non_opaque);
  EXPECT_EQ(h.fallback_crossing_triangles, 0u);  // counted in interpenetration tiles only
}

// ids hold the nearest opaque surface in every mode: a visible blended piece is shaded (its
// samples count as covered) but owns no sample, so analytic equals the truth here too.
TEST(Hybrid, NonOpaquePiecesOwnNoSample) {
  const vis::Setup s = vis::primitive_setup(frame_of("blended", kBlended), {});
  const vis::GoldenResult a = vis::golden_visibility(s, {});
  const vis::TruthResult t = vis::zbuffer_truth(s, {});
  EXPECT_EQ(a.ids, t.ids);
  EXPECT_GT(a.samples_covered, t.samples_covered);  // the card's visible samples are shaded on top
}

// The measure behind tile granularity: in tiles that go per pixel for interpenetration, how
// many triangles cross another (both members of every crossing pair, nothing else).
TEST(Hybrid, CountsTheTrianglesThatCross) {
  const trace::Frame f = frame_of("interpenetrating", kInterpenetrating);
  vis::GoldenConfig cfg;
  cfg.mode = "hybrid";
  const vis::GoldenResult h = vis::golden_visibility(vis::primitive_setup(f, {}), cfg);
  ASSERT_GT(h.fallback_interpenetration, 0u);
  EXPECT_GE(h.fallback_crossing_triangles, 2 * h.fallback_interpenetration);  // a pair per such tile at least
  EXPECT_LT(h.fallback_crossing_triangles, h.fallback_triangles);
}

TEST(Hybrid, WorkOverTheBudgetGoesPerPixel) {
  const trace::Frame f = frame_of("interpenetrating", kInterpenetrating);
  vis::GoldenConfig cfg;
  cfg.tile_w = cfg.tile_h = 32;
  cfg.mode = "hybrid";
  cfg.options.pair_budget = 50;
  const vis::GoldenResult h = vis::golden_visibility(vis::primitive_setup(f, {}), cfg);
  EXPECT_GT(h.fallback_budget, 0u);
  expect_hybrid_is_truth(f, "budget 50", 50);
}

// Where no tile can be wrong, hybrid is analytic: the same ids, counters and exact areas.
TEST(Hybrid, IsAnalyticWhereNothingCanGoWrong) {
  const trace::Frame f = frame_of("cube", R"({"viewport": [200, 160], "camera": {"eye": [2, 1.5, 2.5]},
      "objects": [{"primitive": {"type": "box"}}, {"primitive": {"type": "sphere", "radius": 0.3},
                   "transform": {"translate": [0.2, 0.1, 1.3]}}]})");
  const vis::Setup s = vis::primitive_setup(f, {});
  vis::GoldenConfig cfg;
  const vis::GoldenResult a = vis::golden_visibility(s, cfg);
  cfg.mode = "hybrid";
  const vis::GoldenResult h = vis::golden_visibility(s, cfg);
  EXPECT_EQ(h.fallback_tiles, 0u);
  EXPECT_EQ(h.ids, a.ids);
  EXPECT_EQ(h.visible_area, a.visible_area);
  for (size_t t = 0; t < a.tiles.rows.size(); ++t)
    for (size_t c = 0; c < a.tiles.columns.size(); ++c) ASSERT_EQ(h.tiles.rows[t][c], a.tiles.rows[t][c]);
}

// The detector's bins change its work, never its verdict: the same tiles go per pixel with
// every bin size (the work differs: a pair spanning bins is screened in each, and a tile's
// search stops at its first crossing pair, found in another order).
TEST(Hybrid, DetectionBinsChangeWorkNotVerdict) {
  const vis::Setup s = vis::primitive_setup(frame_of("interpenetrating", kInterpenetrating), {});
  vis::GoldenConfig cfg;
  cfg.mode = "hybrid";
  cfg.options.detection_bin = 0;  // the whole tile
  const vis::GoldenResult whole = vis::golden_visibility(s, cfg);
  ASSERT_GT(whole.fallback_interpenetration, 0u);
  for (uint32_t bin : {1u, 4u, 8u, 16u}) {
    cfg.options.detection_bin = bin;
    const vis::GoldenResult r = vis::golden_visibility(s, cfg);
    EXPECT_EQ(r.ids, whole.ids) << bin;
    EXPECT_EQ(r.fallback_tiles, whole.fallback_tiles) << bin;
    EXPECT_EQ(r.fallback_crossing_triangles, whole.fallback_crossing_triangles) << bin;
    EXPECT_NE(r.detection_screens, whole.detection_screens) << bin;
  }
}
