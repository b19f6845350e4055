// The per-tile visibility interface (tile_resolver.h): the registry of modes, the per_pixel
// mode against the z-buffer truth (two producers of the one z-buffer rule), per-triangle
// records that sum to their tile, tiles resolved in any order, and TileCounters' columns.
#include <algorithm>
#include <cstdlib>
#include <numeric>
#include <stdexcept>

#include <gtest/gtest.h>

#include "scene_frames.h"
#include "visibility/golden.h"
#include "visibility/setup.h"
#include "visibility/tile_resolver.h"
#include "visibility/truth.h"

using namespace tilevis;

namespace {

// Boxes through each other over a floor, a blended card in front: every mode has work.
const char* kMixed = R"({
  "viewport": [200, 150],
  "camera": {"eye": [1.8, 1.4, 3.0], "target": [0, 0, 0], "fov_y_deg": 50, "near": 0.1, "far": 20},
  "objects": [
    {"name": "floor", "primitive": {"type": "plane", "size": [6, 6], "subdivisions": 2}, "transform": {"translate": [0, -0.5, 0]}},
    {"name": "box_a", "primitive": {"type": "box", "size": [1, 1, 1]}, "transform": {"rotate_deg": [0, 20, 0]}},
    {"name": "box_b", "primitive": {"type": "box", "size": [1.2, 0.6, 0.6]}, "transform": {"translate": [0.4, 0.1, 0.2], "rotate_deg": [15, 60, 5]}},
    {"name": "card", "primitive": {"type": "quads", "count": 1, "size": [0.5, 0.4], "origin": [-0.6, 0.2, 1]}, "flags": ["blended"]}
  ]})";

vis::GoldenConfig config(const std::string& mode, uint32_t tile) {
  vis::GoldenConfig c;
  c.mode = mode;
  c.tile_w = c.tile_h = tile;
  return c;
}

}  // namespace

TEST(TileResolver, RegistryNamesEveryMode) {
  const auto& modes = vis::tile_resolver_modes();
  for (const char* m : {"analytic", "hybrid", "per_pixel"})
    EXPECT_NE(std::find(modes.begin(), modes.end(), m), modes.end()) << m;
  for (const std::string& m : modes) EXPECT_NE(vis::make_tile_resolver(m, {}), nullptr) << m;
  try {
    vis::make_tile_resolver("z_prepass", {});
    FAIL() << "an unknown mode was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("z_prepass"), std::string::npos) << what;
    for (const std::string& m : modes) EXPECT_NE(what.find(m), std::string::npos) << what;
  }
}

// per_pixel is the truth's z-buffer run tile by tile: the same ids, covered and generated
// samples, and visible areas equal to covered samples over samples per pixel.
TEST(TileResolver, PerPixelIsTheTruthTileByTile) {
  for (uint32_t samples : {1u, 4u}) {
    const trace::Frame f = testsupport::frame_of("mixed", kMixed, samples);
    const vis::Setup s = vis::primitive_setup(f, {});
    const vis::TruthResult truth = vis::zbuffer_truth(s, {});
    for (uint32_t tile : {4u, 16u, 64u, 256u}) {
      const vis::GoldenResult r = vis::golden_visibility(s, config("per_pixel", tile));
      SCOPED_TRACE(std::to_string(samples) + " samples, tile " + std::to_string(tile));
      EXPECT_EQ(r.ids, truth.ids);
      EXPECT_EQ(r.samples_covered, truth.samples_covered);
      EXPECT_EQ(r.fragments_generated, truth.fragments_generated);
      EXPECT_EQ(r.pair_tests + r.pieces_total + r.occlusion_tests, 0u);
      EXPECT_EQ(r.longest_walk.steps + r.longest_walk.work, 0u);  // nothing clipped
      for (size_t id = 0; id < truth.covered.size(); ++id)
        ASSERT_DOUBLE_EQ(r.visible_area[id], double(truth.covered[id]) / samples) << "triangle " << id;
    }
  }
}

// Every mode's per-triangle records sum to its tile's row, and tiles may be resolved in any
// order (the model's units ask for them as they flow): results equal the row-major run's.
TEST(TileResolver, RecordsSumToTheTileInAnyTileOrder) {
  const trace::Frame f = testsupport::frame_of("mixed", kMixed, 4);
  const vis::Setup s = vis::primitive_setup(f, {});
  for (const std::string& mode : vis::tile_resolver_modes()) {
    SCOPED_TRACE(mode);
    const vis::GoldenConfig cfg = config(mode, 16);
    const vis::GoldenResult reference = vis::golden_visibility(s, cfg);
    vis::GoldenResult r;
    vis::GoldenTiler tiler(s, cfg, r);
    tiler.bin();
    std::vector<uint32_t> order(tiler.tile_count());
    std::iota(order.begin(), order.end(), 0u);
    std::reverse(order.begin(), order.end());
    for (uint32_t tile : order) {
      std::vector<vis::TileTriangleWork> records;
      tiler.process_tile(tile, &records);
      ASSERT_EQ(records.size(), tiler.frame().tile_triangles(tile).size());
      vis::TileCounters sum;
      for (const auto& rec : records) {
        EXPECT_EQ(rec.counters.triangles + rec.counters.edges, 0);
        sum += rec.counters;
      }
      vis::TileCounters row = vis::TileCounters::read(r.tiles.rows[tile]);
      row.triangles = row.edges = 0;
      ASSERT_EQ(sum, row) << "tile " << tile;
    }
    vis::sum_golden_totals(r);
    EXPECT_EQ(r.ids, reference.ids);
    EXPECT_EQ(r.tiles.rows, reference.tiles.rows);
    EXPECT_EQ(r.visible_area.size(), reference.visible_area.size());
    for (size_t id = 0; id < r.visible_area.size(); ++id)  // summed in another order: equal to rounding
      EXPECT_NEAR(r.visible_area[id], reference.visible_area[id], 1e-9 * (1.0 + reference.visible_area[id]));
  }
}

// Tiles resolved ahead on other threads give golden's result bit for bit, visible areas and
// kept pieces included (they wait per tile and are summed in the consumer's order), in every
// mode, whatever order the consumer takes the tiles in. (The bunny: many triangles are split
// into several pieces in one tile, whose areas' order shows in their sum.)
TEST(TileResolver, AheadOnThreadsIsTheSameBits) {
  const trace::Frame f = testsupport::shipped("bunny", 240, 135, 4);
  const vis::Setup s = vis::primitive_setup(f, {});
  const char* old = std::getenv("TILEVIS_THREADS");
  const std::string saved = old ? old : "";
  auto golden_with = [&](const char* threads, const vis::GoldenConfig& cfg) {
    setenv("TILEVIS_THREADS", threads, 1);
    return vis::golden_visibility(s, cfg);
  };
  for (const std::string& mode : vis::tile_resolver_modes()) {
    SCOPED_TRACE(mode);
    vis::GoldenConfig cfg = config(mode, 8);
    cfg.options.keep_pieces = true;
    const vis::GoldenResult one = golden_with("1", cfg);
    const vis::GoldenResult four = golden_with("4", cfg);
    EXPECT_EQ(four.ids, one.ids);
    EXPECT_EQ(four.tiles.rows, one.tiles.rows);
    EXPECT_EQ(four.visible_area, one.visible_area);  // bit for bit
    ASSERT_EQ(four.pieces.size(), one.pieces.size());
    for (size_t i = 0; i < one.pieces.size(); ++i) {
      EXPECT_EQ(four.pieces[i].id, one.pieces[i].id) << i;
      EXPECT_EQ(four.pieces[i].xy, one.pieces[i].xy) << i;
    }
    EXPECT_EQ(four.visible_triangles, one.visible_triangles);
    EXPECT_EQ(four.shader_invocations, one.shader_invocations);
    EXPECT_EQ(four.max_tile_pieces, one.max_tile_pieces);
    // The longest clip walk: the same item (the first in tile order among equals) on any threads.
    EXPECT_EQ(four.longest_walk.steps, one.longest_walk.steps);
    EXPECT_EQ(four.longest_walk.work, one.longest_walk.work);
    EXPECT_EQ(four.longest_walk.chain_splits, one.longest_walk.chain_splits);
    EXPECT_EQ(four.longest_walk.splits, one.longest_walk.splits);
    EXPECT_EQ(four.longest_walk.tile, one.longest_walk.tile);
    EXPECT_EQ(four.longest_walk.setup_index, one.longest_walk.setup_index);
    if (mode != "per_pixel") {
      // At least a step per 32 of its candidates, every walk's steps at least the chain's, its
      // pieces within the frame's most, and its candidates within its tile's row.
      const auto& w = one.longest_walk;
      EXPECT_GE(w.steps, (w.candidates + 31) / 32);
      EXPECT_GE(w.work, w.steps);
      EXPECT_GE(w.work, w.pieces);
      // Every piece but the first was cut off by a split; the chain's splits are among them.
      EXPECT_GE(w.splits, w.pieces - 1);
      EXPECT_LE(w.chain_splits, w.splits);
      EXPECT_LE(w.chain_splits, w.steps);
      EXPECT_LE(w.splits, w.work);
      EXPECT_LE(w.pieces, one.max_tile_pieces);
      EXPECT_GT(w.pieces, 1u) << "the bunny's longest walk splits";
      const auto& cols = vis::TileCounters::columns();
      const size_t cand = size_t(std::find(cols.begin(), cols.end(), "candidate_pairs") - cols.begin());
      ASSERT_LT(cand, cols.size());
      EXPECT_LE(int64_t(w.candidates), one.tiles.rows[w.tile][cand]);
    }
    EXPECT_EQ(four.fallback_tiles, one.fallback_tiles);
    EXPECT_EQ(four.detection_tests, one.detection_tests);

    // The model's way: per-triangle records, tiles queued in one order and taken in another.
    auto records_with = [&](const char* threads, std::vector<double>& areas) {
      setenv("TILEVIS_THREADS", threads, 1);
      vis::GoldenResult r;
      vis::GoldenTiler tiler(s, cfg, r);
      tiler.bin();
      std::vector<uint32_t> queued(tiler.tile_count()), taken;
      std::iota(queued.begin(), queued.end(), 0u);
      tiler.resolve_ahead(queued, true);
      for (uint32_t t = 0; t < tiler.tile_count(); t += 2) taken.push_back(t);  // evens, then odds backwards
      for (uint32_t t = tiler.tile_count() - 1 - tiler.tile_count() % 2; t < tiler.tile_count(); t -= 2) taken.push_back(t);
      std::vector<std::pair<uint32_t, vis::TileCounters>> out;
      for (uint32_t t : taken) {
        std::vector<vis::TileTriangleWork> records;
        tiler.process_tile(t, &records);
        for (const auto& rec : records) out.emplace_back(rec.triangle, rec.counters);
      }
      areas = r.visible_area;
      return out;
    };
    std::vector<double> areas_one, areas_four;
    const auto records_one = records_with("1", areas_one);
    const auto records_four = records_with("4", areas_four);
    EXPECT_EQ(records_four.size(), records_one.size());
    EXPECT_TRUE(records_four == records_one);
    EXPECT_EQ(areas_four, areas_one);
  }
  if (old) setenv("TILEVIS_THREADS", saved.c_str(), 1);
  else unsetenv("TILEVIS_THREADS");
}

TEST(TileCounters, ColumnsFollowTheFieldsAndRowsRoundTrip) {
  const auto& cols = vis::TileCounters::columns();
  ASSERT_EQ(cols.size(), vis::TileCounters::kCount);
  EXPECT_EQ(cols.front(), "triangles");
  EXPECT_EQ(cols.back(), "fragments_generated");
  vis::TileCounters c;
  for (size_t i = 0; i < vis::TileCounters::kCount; ++i) c.*vis::TileCounters::kFields[i].second = int64_t(i * i + 1);
  EXPECT_EQ(c.pieces, 26);  // "pieces" is column 5
  int64_t row[vis::TileCounters::kCount];
  c.write(row);
  EXPECT_EQ(row[5], c.pieces);
  EXPECT_EQ(vis::TileCounters::read(row), c);
  const vis::TileCounters twice = c + c;
  EXPECT_EQ(twice.occlusion_tests, 2 * c.occlusion_tests);
  EXPECT_EQ(twice - c, c);
  EXPECT_THROW(vis::TileCounters::read(std::vector<int64_t>(3)), std::invalid_argument);
}

// TileFrame::pair_tests, from the binning alone, is the analytic resolver's pair_tests for
// every tile (the sampled render's regressor: model/units/tile_scheduler/tile_sampler.h).
TEST(TileResolver, PairTestsFollowFromTheBinning) {
  const trace::Frame f = testsupport::frame_of("mixed", kMixed, 1);
  const vis::Setup s = vis::primitive_setup(f, {});
  for (uint32_t tile_size : {8u, 16u, 32u}) {
    SCOPED_TRACE("tile " + std::to_string(tile_size));
    vis::GoldenResult r;
    vis::GoldenTiler tiler(s, config("analytic", tile_size), r);
    tiler.bin();
    uint64_t pairs = 0;
    for (uint32_t tile = 0; tile < tiler.tile_count(); ++tile) {
      tiler.process_tile(tile, nullptr);
      const vis::TileCounters row = vis::TileCounters::read(r.tiles.rows[tile]);
      EXPECT_EQ(uint64_t(row.pair_tests), tiler.frame().pair_tests(tile)) << "tile " << tile;
      pairs += tiler.frame().pair_tests(tile);
    }
    EXPECT_GT(pairs, 0u);
  }
}
