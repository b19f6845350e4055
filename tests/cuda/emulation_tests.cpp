// cuda_ref's kernels' logic, run on the host one element at a time (Device::cpu), against the
// golden pipeline: bit-identical ids, per-tile counters and visible areas in `exact`; the
// `float` precision's agreement measured. No GPU needed: this is what CI and machines without
// a device check before GPU time is spent.
#include <gtest/gtest.h>

#include "compare.h"
#include "scenes.h"
#include "sort_check.h"
#if TILEVIS_HAVE_SCENE
#include <filesystem>
#include "tilevis/scene.h"
#endif

using namespace tilevis;
namespace ct = tilevis::cudatest;

namespace {

struct Case {
  std::string scene;
  uint32_t tile_w, tile_h, samples;
};

std::string name_of(const ::testing::TestParamInfo<Case>& i) {
  return i.param.scene + "_" + std::to_string(i.param.tile_w) + "x" + std::to_string(i.param.tile_h) + "_s" +
         std::to_string(i.param.samples);
}

std::vector<Case> cases() {
  std::vector<Case> v;
  for (const auto& s : ct::scene_names())
    for (uint32_t t : {16u, 32u, 64u}) v.push_back({s, t, t, 1});
  for (const auto& s : {"cubes", "mixed", "coplanar"}) v.push_back({s, 32, 32, 4});
  v.push_back({"cubes", 48, 8, 1});
  v.push_back({"ground", 7, 13, 2});
  // Near the eye every tile size must give golden's answer (issue: hostile input).
  for (const auto& s : {"near_eye", "near_eye_pair"})
    for (uint32_t t : {4u, 8u, 128u, 256u}) v.push_back({s, t, t, 1});
  return v;
}

class ExactEmulation : public ::testing::TestWithParam<Case> {};

TEST_P(ExactEmulation, BitIdenticalToGolden) {
  const Case& c = GetParam();
  const trace::Frame f = ct::scene(c.scene, c.samples);
  const auto g = ct::golden_of(f, c.tile_w, c.tile_h);
  const auto r = cuda::run_cuda(f, ct::config(cuda::Device::cpu, cuda::Precision::exact, c.tile_w, c.tile_h));
  const auto d = ct::diff(g, r);
  ct::expect_bit_identical(d);
}

INSTANTIATE_TEST_SUITE_P(Scenes, ExactEmulation, ::testing::ValuesIn(cases()), name_of);

// Finer occlusion bins (SVGPU §4.1) change which occluders a piece scans, never the result:
// still bit-identical to golden (with or without its own bins), bins dividing the tile or not.
TEST(Emulation, FinerOcclusionBinsStayBitIdentical) {
  for (const auto& s : {"cubes", "mixed", "stack"}) {
    const trace::Frame f = ct::scene(s);
    const auto g = ct::golden_of(f, 32, 32);
    ASSERT_GT(g.occlusion_tests, 0u) << s;
    for (auto [bw, bh] : {std::pair{8u, 8u}, {5u, 7u}, {1u, 32u}}) {
      auto cfg = ct::config(cuda::Device::cpu, cuda::Precision::exact, 32, 32);
      cfg.occlusion_bin_w = bw;
      cfg.occlusion_bin_h = bh;
      cfg.shuffle_cpu = true;
      const auto d = ct::diff(g, cuda::run_cuda(f, cfg));
      EXPECT_EQ(d.id_mismatches, 0u) << s << " " << bw << "x" << bh;
      EXPECT_EQ(d.tile_cell_mismatches, 0u) << s << " " << bw << "x" << bh << ": " << d.first_tile_mismatch;
      EXPECT_EQ(d.area_bit_mismatches, 0u) << s << " " << bw << "x" << bh;
    }
  }
}

TEST(Emulation, ScenesExerciseThePipeline) {
  // The scenes are only worth comparing if they clip, split, occlude and tie.
  const auto cubes = ct::golden_of(ct::scene("cubes"), 32, 32);
  EXPECT_GT(cubes.clip_polygons, 20u);
  EXPECT_GT(cubes.occlusion_tests, 100u);
  const auto ground = vis::primitive_setup(ct::scene("ground"), {});
  EXPECT_GT(ground.stats.clipped, 0u);
  const auto stack = ct::golden_of(ct::scene("stack"), 32, 32);
  EXPECT_GT(stack.pair_tests, 10000u);
  const auto mixed = vis::primitive_setup(ct::scene("mixed"), {});
  EXPECT_LT(mixed.silhouettes.size(), 60u);  // the soup sphere is welded: an outline, not every edge
}

TEST(Emulation, OrderIndependent) {
  // Elements visited in a scrambled order (as a GPU may run them) give the same result.
  for (const auto& s : {"cubes", "stack", "mixed"}) {
    const trace::Frame f = ct::scene(s, 4);
    auto cfg = ct::config(cuda::Device::cpu, cuda::Precision::exact, 32, 32);
    const auto a = cuda::run_cuda(f, cfg);
    cfg.shuffle_cpu = true;
    const auto b = cuda::run_cuda(f, cfg);
    EXPECT_EQ(a.ids, b.ids) << s;
    EXPECT_EQ(a.tiles, b.tiles) << s;
    EXPECT_EQ(a.visible_area, b.visible_area) << s;
  }
}

TEST(Emulation, GrowAndRetryFromTinyPools) {
  // Every overflow-checked pool starts at 4 elements: device counters report the overflow,
  // the host grows the pools and runs again, and the result is still exact.
  const trace::Frame f = ct::scene("cubes");
  auto cfg = ct::config(cuda::Device::cpu, cuda::Precision::exact, 64, 64);
  cfg.initial_pool = 4;
  const auto r = cuda::run_cuda(f, cfg);
  EXPECT_GT(r.retries, 0u);
  const auto d = ct::diff(ct::golden_of(f, 64, 64), r);
  EXPECT_EQ(d.id_mismatches, 0u);
  EXPECT_EQ(d.tile_cell_mismatches, 0u) << d.first_tile_mismatch;
}

TEST(Emulation, FloatAgreementIsMeasured) {
  for (const auto& s : ct::scene_names()) {
    const trace::Frame f = ct::scene(s);
    const auto exact = cuda::run_cuda(f, ct::config(cuda::Device::cpu, cuda::Precision::exact, 32, 32));
    const auto fl = cuda::run_cuda(f, ct::config(cuda::Device::cpu, cuda::Precision::floating, 32, 32));
    uint64_t compared = 0, mismatched = 0;
    for (size_t i = 0; i < exact.ids.size(); ++i) {
      if (exact.ids[i] < 0 && fl.ids[i] < 0) continue;
      ++compared;
      mismatched += exact.ids[i] != fl.ids[i];
    }
    ASSERT_GT(compared, 0u) << s;
    // float32 is not exact, but on these small scenes it must be close.
    EXPECT_GT(1.0 - double(mismatched) / double(compared), 0.99) << s;
    EXPECT_EQ(fl.triangles_front, exact.triangles_front) << s;  // setup is shared
  }
}

// Frames in sequence through one pipeline (run_cuda_frames): each frame's ids are those of a
// run of it alone.
TEST(Emulation, FrameSequenceGivesEachFramesIds) {
  const std::vector<std::string> names = {"cubes", "mixed", "cubes"};
  std::vector<trace::Frame> frames;
  for (const auto& n : names) frames.push_back(ct::scene(n));
  for (auto prec : {cuda::Precision::exact, cuda::Precision::floating}) {
    const auto cfg = ct::config(cuda::Device::cpu, prec, 32, 32);
    const auto seq = cuda::run_cuda_frames(frames, cfg, 1);
    ASSERT_EQ(seq.size(), frames.size());
    for (size_t k = 0; k < frames.size(); ++k)
      EXPECT_EQ(seq[k].ids_hash, cuda::ids_hash(cuda::run_cuda(frames[k], cfg).ids)) << names[k];
  }
}

// A device-sized run (sizes kept on the device, within bounds learned from earlier frames) of a
// frame past those bounds (ct::small_big_sequence): the run overflows, runs again with host reads
// (a retry), and every frame still gets the ids a run of it alone gives.
TEST(Emulation, DeviceSizedRunPastItsBoundsRunsAgain) {
  const std::vector<trace::Frame> frames = ct::small_big_sequence();
  for (auto prec : {cuda::Precision::exact, cuda::Precision::floating}) {
    const auto cfg = ct::config(cuda::Device::cpu, prec, 32, 32);
    const auto seq = cuda::run_cuda_frames(frames, cfg, 1);
    ASSERT_EQ(seq.size(), frames.size());
    EXPECT_GE(seq[1].first_retries, 1u);  // big after small: past the bounds, run again
    EXPECT_EQ(seq[2].first_retries, 0u);  // small within the bounds big left
    EXPECT_EQ(seq[3].first_retries, 0u);
    for (size_t k = 0; k < frames.size(); ++k) {
      const auto alone = cuda::run_cuda(frames[k], cfg);
      EXPECT_TRUE(alone.device_sized);
      EXPECT_EQ(seq[k].ids_hash, cuda::ids_hash(alone.ids)) << k;
    }
  }
}

// Exec::sort_pairs's host path (and the padding of a device count), by the GPU test's check.
TEST(Emulation, SortPairsIsStableByTheKeysLowBits) { ct::check_sort_pairs(false); }

TEST(Emulation, RejectsBadConfig) {
  const trace::Frame f = ct::scene("cubes");
  auto cfg = ct::config(cuda::Device::cpu, cuda::Precision::exact, 0, 32);
  EXPECT_THROW(cuda::run_cuda(f, cfg), std::runtime_error);
  cfg = ct::config(cuda::Device::cpu, cuda::Precision::exact, 32, 32);
  cfg.depth_bits = 40;
  EXPECT_THROW(cuda::run_cuda(f, cfg), std::runtime_error);
}

// Hybrid (golden --mode hybrid) in host emulation: ids, areas (bitwise), every per-tile counter
// and the verdict columns (per_pixel, cause, detection_screens, detection_tests) equal golden's,
// with and without a pair budget, at 1 and 4 samples.
class HybridEmulation : public ::testing::TestWithParam<std::tuple<std::string, uint32_t, uint32_t>> {};

TEST_P(HybridEmulation, BitIdenticalToGoldenHybrid) {
  const auto& [name, tile, samples] = GetParam();
  const trace::Frame f = ct::scene(name, samples);
  const auto g = ct::golden_of(f, tile, tile, "hybrid");
  auto cfg = ct::config(cuda::Device::cpu, cuda::Precision::exact, tile, tile);
  cfg.hybrid = true;
  cfg.shuffle_cpu = true;
  const auto r = cuda::run_cuda(f, cfg);
  const auto d = ct::diff(g, r);
  ct::expect_bit_identical(d);
}

// The same over small lists and a pair budget: the tiles over them go per pixel, and culling
// skips their items (no candidate, no piece), so only golden's per-pixel answer is left there.
TEST_P(HybridEmulation, BitIdenticalToGoldenHybridOverSmallLists) {
  const auto& [name, tile, samples] = GetParam();
  const trace::Frame f = ct::scene(name, samples);
  auto cfg = ct::config(cuda::Device::cpu, cuda::Precision::exact, tile, tile);
  cfg.hybrid = true;
  cfg.shuffle_cpu = true;
  ct::small_lists(cfg);
  const auto g = ct::golden_of(f, tile, tile, "hybrid", &cfg);
  const auto r = cuda::run_cuda(f, cfg);
  ct::expect_bit_identical(ct::diff(g, r));
}

INSTANTIATE_TEST_SUITE_P(Scenes, HybridEmulation,
                         ::testing::Combine(::testing::ValuesIn(ct::scene_names()), ::testing::Values(8u, 32u),
                                            ::testing::Values(1u, 4u)));

// The tiled z-buffer (cuda_ref.h ZBufferKind::tiled), its kernels' logic on the host in a
// scrambled bin order: the z-buffer truth's ids, sample for sample, at 1 and 4 samples (bins of
// 16x16 and 8x8 pixels), near the eye too. The naive one only runs: its ids are measured.
class ZBufferEmulation : public ::testing::TestWithParam<std::tuple<std::string, uint32_t>> {};

TEST_P(ZBufferEmulation, TiledEqualsTruth) {
  const auto& [name, samples] = GetParam();
  const trace::Frame f = ct::scene(name, samples);
  auto cfg = ct::config(cuda::Device::cpu, cuda::Precision::exact, 32, 32);
  cfg.shuffle_cpu = true;
  const auto z = cuda::run_cuda_zbuffer(f, cfg, cuda::ZBufferKind::tiled);
  const std::vector<int32_t> truth = ct::truth_ids_of(f);
  ASSERT_EQ(z.ids.size(), truth.size());
  uint64_t covered = 0, differ = 0;
  for (size_t k = 0; k < truth.size(); ++k) {
    covered += truth[k] >= 0 ? 1 : 0;
    differ += truth[k] != z.ids[k] ? 1 : 0;
  }
  EXPECT_GT(covered, 0u);
  EXPECT_EQ(differ, 0u);
  EXPECT_GT(z.bin_entries, 0u);
  const auto n = cuda::run_cuda_zbuffer(f, cfg, cuda::ZBufferKind::naive);
  ASSERT_EQ(n.ids.size(), truth.size());
  EXPECT_GT(n.triangles_drawn, 0u);
}

// The same from tiny pools and list segments of 8 records: frames run again as the counters
// overflow, and long tile lists are split over helper items merged per sample.
TEST_P(ZBufferEmulation, TiledFromTinyPoolsEqualsTruth) {
  const auto& [name, samples] = GetParam();
  const trace::Frame f = ct::scene(name, samples);
  auto cfg = ct::config(cuda::Device::cpu, cuda::Precision::exact, 32, 32);
  cfg.shuffle_cpu = true;
  cfg.initial_pool = 4;
  const auto z = cuda::run_cuda_zbuffer(f, cfg, cuda::ZBufferKind::tiled);
  EXPECT_GT(z.retries, 0u);
  EXPECT_EQ(z.ids, ct::truth_ids_of(f));
}

INSTANTIATE_TEST_SUITE_P(Scenes, ZBufferEmulation,
                         ::testing::Combine(::testing::Values("cubes", "mixed", "coplanar", "near_eye", "near_eye_pair"),
                                            ::testing::Values(1u, 4u)));

#if TILEVIS_HAVE_SCENE
// A shipped scene's first frame at 320x240, 1 sample.
static trace::Frame shipped_small(const std::string& name) {
  tilevis::scene::BuildOptions o;
  o.width = 320;
  o.height = 240;
  o.samples = 1;
  return tilevis::scene::build_trace(std::filesystem::path(TILEVIS_SOURCE_DIR) / "traces/scenes" / (name + ".json"), o)
      .frames.at(0);
}

// Hybrid on shipped failure scenes (interpenetration, decals, slivers, broken meshes) at a small
// viewport: the detector's crossing verdicts, their work counts and the per-pixel tiles equal
// golden's; some tiles do go per pixel for interpenetration.
TEST(Emulation, HybridOnShippedFailureScenes) {
  for (const char* name : {"interpenetrating", "decals", "slivers", "broken_mesh"}) {
    const trace::Frame f = shipped_small(name);
    for (uint32_t tile : {8u, 32u}) {
      const auto g = ct::golden_of(f, tile, tile, "hybrid");
      auto cfg = ct::config(cuda::Device::cpu, cuda::Precision::exact, tile, tile);
      cfg.hybrid = true;
      const auto r = cuda::run_cuda(f, cfg);
      const auto d = ct::diff(g, r);
      EXPECT_EQ(d.id_mismatches, 0u) << name << " " << tile;
      EXPECT_EQ(d.tile_cell_mismatches, 0u) << name << " " << tile << ": " << d.first_tile_mismatch;
      EXPECT_EQ(d.area_bit_mismatches, 0u) << name << " " << tile;
      EXPECT_TRUE(d.totals_equal) << name << " " << tile << ": " << d.totals;
      if (std::string(name) == "interpenetrating") {
        EXPECT_GT(g.fallback_interpenetration, 0u) << tile;
      }
    }
    // Over lists of 24 triangles and 8 edges, busy tiles go per pixel for the budget.
    auto cfg = ct::config(cuda::Device::cpu, cuda::Precision::exact, 32, 32);
    cfg.hybrid = true;
    cfg.list_triangles = 24;
    cfg.list_edges = 8;
    const auto g = ct::golden_of(f, 32, 32, "hybrid", &cfg);
    const auto d = ct::diff(g, cuda::run_cuda(f, cfg));
    EXPECT_GT(g.fallback_budget, 0u) << name;
    EXPECT_EQ(d.id_mismatches, 0u) << name << " (lists 24, 8)";
    EXPECT_EQ(d.tile_cell_mismatches, 0u) << name << " (lists 24, 8): " << d.first_tile_mismatch;
    EXPECT_EQ(d.area_bit_mismatches, 0u) << name << " (lists 24, 8)";
    EXPECT_TRUE(d.totals_equal) << name << " (lists 24, 8): " << d.totals;
  }
}

// Float on the shipped failure scenes: no visible piece has a negative area (a float area is
// used only where its sign is proven, else the exact area of the region the piece's lines bound).
TEST(Emulation, FloatAreasNeverNegativeOnShippedFailureScenes) {
  for (const char* name : {"slivers", "broken_mesh", "decals", "interpenetrating"}) {
    const trace::Frame f = shipped_small(name);
    const auto r = cuda::run_cuda(f, ct::config(cuda::Device::cpu, cuda::Precision::floating, 32, 32));
    EXPECT_EQ(r.float_negative_areas, 0u) << name;
    EXPECT_EQ(r.float_anomalies, 0u) << name;
    for (double a : r.visible_area) ASSERT_GE(a, 0.0) << name;
  }
}

// The tiled z-buffer on shipped scenes at a small viewport: huge triangles through the near
// plane and across the screen (slivers, teapot_stadium: coarse bins), deep stacks (stack: long
// tile lists split over helpers), coplanar decals; from default and from tiny pools.
TEST(Emulation, ZBufferTiledOnShippedScenes) {
  for (const char* name : {"slivers", "teapot_stadium", "stack", "decals", "broken_mesh"}) {
    const trace::Frame f = shipped_small(name);
    const std::vector<int32_t> truth = ct::truth_ids_of(f);
    for (uint32_t pool : {0u, 4u}) {
      auto cfg = ct::config(cuda::Device::cpu, cuda::Precision::exact, 32, 32);
      cfg.shuffle_cpu = true;
      cfg.initial_pool = pool;
      const auto z = cuda::run_cuda_zbuffer(f, cfg, cuda::ZBufferKind::tiled);
      ASSERT_EQ(z.ids.size(), truth.size());
      uint64_t differ = 0;
      for (size_t k = 0; k < truth.size(); ++k) differ += truth[k] != z.ids[k] ? 1 : 0;
      EXPECT_EQ(differ, 0u) << name << " pool " << pool;
    }
  }
}

// A shipped mesh scene (the Stanford bunny) at a small viewport, built by the scene generator.
TEST(Emulation, ShippedBunnyAgrees) {
  tilevis::scene::BuildOptions o;
  o.width = 400;
  o.height = 300;
  o.samples = 1;
  const trace::Frame f =
      tilevis::scene::build_trace(std::filesystem::path(TILEVIS_SOURCE_DIR) / "traces/scenes/bunny.json", o).frames.at(0);
  for (uint32_t tile : {16u, 64u}) {
    const auto r = cuda::run_cuda(f, ct::config(cuda::Device::cpu, cuda::Precision::exact, tile, tile));
    const auto d = ct::diff(ct::golden_of(f, tile, tile), r);
    EXPECT_EQ(d.id_mismatches, 0u) << tile;
    EXPECT_EQ(d.tile_cell_mismatches, 0u) << d.first_tile_mismatch;
    EXPECT_EQ(d.area_bit_mismatches, 0u) << tile;
  }
}
#endif

}  // namespace
