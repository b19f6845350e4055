// cuda_ref on the GPU (device 0) against the golden pipeline and its own host emulation.
// Every test skips, saying why, where no CUDA device is usable (CI, build machines).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <future>

#include "compare.h"
#include "scenes.h"
#include "sort_check.h"

using namespace tilevis;
namespace ct = tilevis::cudatest;

namespace {

// GTEST_SKIP returns from the test itself, so this is a macro, not a function.
#define REQUIRE_GPU()                                                                   \
  do {                                                                                  \
    std::string why;                                                                    \
    if (!cuda::cuda_available(&why)) GTEST_SKIP() << "no CUDA device (" << why << "): GPU test not run"; \
  } while (0)

class ExactGpu : public ::testing::TestWithParam<std::tuple<std::string, uint32_t, uint32_t>> {};

TEST_P(ExactGpu, BitIdenticalToGolden) {
  REQUIRE_GPU();
  const auto& [name, tile, samples] = GetParam();
  const trace::Frame f = ct::scene(name, samples);
  auto cfg = ct::config(cuda::Device::gpu, cuda::Precision::exact, tile, tile);
  cfg.runs = 3;
  const auto r = cuda::run_cuda(f, cfg);
  const auto d = ct::diff(ct::golden_of(f, tile, tile), r);
  ct::expect_bit_identical(d);
  EXPECT_EQ(r.stage_ms.size(), 8u);  // seven on the main chain, the unclipped pieces beside clip
  EXPECT_EQ(r.stream_stage_ms.size(), 8u);
  EXPECT_GT(r.stream_total_ms, 0.0);
  EXPECT_GT(r.total_ms, 0.0);
  EXPECT_GT(r.peak_device_bytes, 0u);
  EXPECT_FALSE(r.device_name.empty());
  EXPECT_TRUE(r.device_sized);  // the results above are the device-sized graph's run
  EXPECT_GT(r.device_graph_nodes, 0u);
  // Both graphs launch this library's kernels programmatically (the default; the results above
  // are those of the device-sized graph with these edges).
  if (!std::getenv("TILEVIS_CUDA_PDL")) {
    EXPECT_EQ(r.graph_pdl, "exit");
    EXPECT_GT(r.graph_programmatic_edges, 0u);
    EXPECT_GT(r.device_graph_programmatic_edges, 0u);
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, ExactGpu,
                         ::testing::Combine(::testing::ValuesIn(ct::scene_names()), ::testing::Values(16u, 32u, 64u),
                                            ::testing::Values(1u, 4u)));
// Near the eye every tile size gives golden's answer, from the smallest tile to the largest.
INSTANTIATE_TEST_SUITE_P(NearEyeTiles, ExactGpu,
                         ::testing::Combine(::testing::Values("near_eye", "near_eye_pair"),
                                            ::testing::Values(4u, 8u, 128u, 256u), ::testing::Values(1u)));

TEST(Gpu, FinerOcclusionBinsStayBitIdentical) {
  REQUIRE_GPU();
  for (const auto& name : ct::scene_names()) {
    const trace::Frame f = ct::scene(name);
    auto cfg = ct::config(cuda::Device::gpu, cuda::Precision::exact, 32, 32);
    cfg.occlusion_bin_w = cfg.occlusion_bin_h = 8;
    cfg.runs = 2;
    const auto d = ct::diff(ct::golden_of(f, 32, 32), cuda::run_cuda(f, cfg));
    EXPECT_EQ(d.id_mismatches, 0u) << name;
    EXPECT_EQ(d.tile_cell_mismatches, 0u) << name << ": " << d.first_tile_mismatch;
    EXPECT_EQ(d.area_bit_mismatches, 0u) << name;
  }
}

TEST(Gpu, SameAsHostEmulation) {
  // exact: the device and the host emulation of its kernels agree bit for bit. (float is not
  // compared: the device contracts float multiply-adds into FMA, the host does not.)
  REQUIRE_GPU();
  for (const auto& name : {"cubes", "ground", "mixed"}) {
    const trace::Frame f = ct::scene(name, 4);
    const auto gpu = cuda::run_cuda(f, ct::config(cuda::Device::gpu, cuda::Precision::exact, 32, 32));
    const auto cpu = cuda::run_cuda(f, ct::config(cuda::Device::cpu, cuda::Precision::exact, 32, 32));
    EXPECT_EQ(gpu.ids, cpu.ids) << name;
    EXPECT_EQ(gpu.tiles, cpu.tiles) << name;
    EXPECT_EQ(gpu.visible_area, cpu.visible_area) << name;
  }
}

// Exec::sort_pairs, every path it takes by size (sort_check.h).
TEST(Gpu, SortPairsIsStableByTheKeysLowBits) {
  REQUIRE_GPU();
  ct::check_sort_pairs(true);
}

TEST(Gpu, DeterministicAcrossRuns) {
  REQUIRE_GPU();
  const trace::Frame f = ct::scene("stack");
  const auto a = cuda::run_cuda(f, ct::config(cuda::Device::gpu, cuda::Precision::exact, 16, 16));
  const auto b = cuda::run_cuda(f, ct::config(cuda::Device::gpu, cuda::Precision::exact, 16, 16));
  EXPECT_EQ(a.ids, b.ids);
  EXPECT_EQ(a.tiles, b.tiles);
  EXPECT_EQ(a.visible_area, b.visible_area);
}

TEST(Gpu, GrowAndRetryFromTinyPools) {
  REQUIRE_GPU();
  const trace::Frame f = ct::scene("cubes");
  auto cfg = ct::config(cuda::Device::gpu, cuda::Precision::exact, 64, 64);
  cfg.initial_pool = 4;
  const auto r = cuda::run_cuda(f, cfg);
  EXPECT_GT(r.retries, 0u);
  const auto d = ct::diff(ct::golden_of(f, 64, 64), r);
  EXPECT_EQ(d.id_mismatches, 0u);
  EXPECT_EQ(d.tile_cell_mismatches, 0u) << d.first_tile_mismatch;
}

TEST(Gpu, FloatAgreementIsMeasured) {
  REQUIRE_GPU();
  const trace::Frame f = ct::scene("cubes");
  const auto exact = cuda::run_cuda(f, ct::config(cuda::Device::gpu, cuda::Precision::exact, 32, 32));
  const auto fl = cuda::run_cuda(f, ct::config(cuda::Device::gpu, cuda::Precision::floating, 32, 32));
  uint64_t compared = 0, mismatched = 0;
  for (size_t i = 0; i < exact.ids.size(); ++i) {
    if (exact.ids[i] < 0 && fl.ids[i] < 0) continue;
    ++compared;
    mismatched += exact.ids[i] != fl.ids[i];
  }
  ASSERT_GT(compared, 0u);
  EXPECT_GT(1.0 - double(mismatched) / double(compared), 0.99);
}

// The z-buffers on the GPU: the tiled one equals the truth's ids on every test scene at 1 and 4
// samples; the naive one (float depth, no near clipping) draws and agrees on most samples.
class ZBufferGpu : public ::testing::TestWithParam<std::tuple<std::string, uint32_t>> {};

TEST_P(ZBufferGpu, TiledEqualsTruth) {
  REQUIRE_GPU();
  const auto& [name, samples] = GetParam();
  const trace::Frame f = ct::scene(name, samples);
  auto cfg = ct::config(cuda::Device::gpu, cuda::Precision::exact, 32, 32);
  cfg.runs = 3;
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
  EXPECT_GT(z.total_ms, 0.0);
  const auto n = cuda::run_cuda_zbuffer(f, cfg, cuda::ZBufferKind::naive);
  ASSERT_EQ(n.ids.size(), truth.size());
  uint64_t same = 0;
  for (size_t k = 0; k < truth.size(); ++k) same += truth[k] >= 0 && truth[k] == n.ids[k] ? 1 : 0;
  EXPECT_GT(n.total_ms, 0.0);
  // Float depth z-fights where the truth has exact ties (coplanar: 88 % agree); a wrong
  // orientation or id mapping would agree on almost nothing.
  if (n.skipped == 0) {
    EXPECT_GT(double(same), 0.5 * double(covered)) << "naive z-buffer agrees on " << same << " of " << covered;
  }
}

// From tiny pools and list segments of 8 records: grow and retry, and long tile lists split over
// helper warps that merge per sample by CAS (the merge order must not matter).
TEST_P(ZBufferGpu, TiledFromTinyPoolsEqualsTruth) {
  REQUIRE_GPU();
  const auto& [name, samples] = GetParam();
  const trace::Frame f = ct::scene(name, samples);
  auto cfg = ct::config(cuda::Device::gpu, cuda::Precision::exact, 32, 32);
  cfg.runs = 3;
  cfg.initial_pool = 4;
  const auto z = cuda::run_cuda_zbuffer(f, cfg, cuda::ZBufferKind::tiled);
  EXPECT_GT(z.retries, 0u);
  EXPECT_EQ(z.ids, ct::truth_ids_of(f));
}

INSTANTIATE_TEST_SUITE_P(Scenes, ZBufferGpu,
                         ::testing::Combine(::testing::ValuesIn(ct::scene_names()), ::testing::Values(1u, 4u)));

// Hybrid on the GPU: golden --mode hybrid bit for bit (ids, areas, every per-tile counter, the
// verdict columns), the detector's thread per tile and the per-pixel tiles' blocks included;
// then the same run in float: the verdicts are exact, so they and the per-pixel tiles agree.
// With `small`, over small lists and a pair budget (compare.h small_lists): culling skips the
// items of the tiles over them, and the per-pixel kernels draw those tiles.
static void check_hybrid_gpu(const std::string& name, uint32_t tile, uint32_t samples, bool small) {
  const trace::Frame f = ct::scene(name, samples);
  auto cfg = ct::config(cuda::Device::gpu, cuda::Precision::exact, tile, tile);
  cfg.hybrid = true;
  cfg.runs = 2;
  if (small) ct::small_lists(cfg);
  const auto r = cuda::run_cuda(f, cfg);
  ct::expect_bit_identical(ct::diff(ct::golden_of(f, tile, tile, "hybrid", &cfg), r));
  cfg.precision = cuda::Precision::floating;
  const auto rf = cuda::run_cuda(f, cfg);
  EXPECT_EQ(rf.per_pixel_cause, r.per_pixel_cause);
  EXPECT_EQ(rf.detection_tests, r.detection_tests);
}

class HybridGpu : public ::testing::TestWithParam<std::tuple<std::string, uint32_t, uint32_t>> {};

TEST_P(HybridGpu, BitIdenticalToGoldenHybrid) {
  REQUIRE_GPU();
  const auto& [name, tile, samples] = GetParam();
  check_hybrid_gpu(name, tile, samples, false);
}

TEST_P(HybridGpu, BitIdenticalToGoldenHybridOverSmallLists) {
  REQUIRE_GPU();
  const auto& [name, tile, samples] = GetParam();
  check_hybrid_gpu(name, tile, samples, true);
}

INSTANTIATE_TEST_SUITE_P(Scenes, HybridGpu,
                         ::testing::Combine(::testing::ValuesIn(ct::scene_names()), ::testing::Values(8u, 32u),
                                            ::testing::Values(1u, 4u)));


// The built-in scenes (traces/scenes/*.json as traces: gpu_run.sh sets TILEVIS_GPU_TRACES to
// the folder prepare_gpu_run.sh's traces were unpacked into), failure scenes included, at 32x32:
// exact hybrid against golden --mode hybrid, every total, ids, areas (bitwise), every per-tile
// counter and verdict column and the fallback totals; float analytic never reports a negative
// area or an anomaly.
TEST(GpuBuiltInScenes, HybridEqualsGoldenHybridAndFloatKeepsSigns) {
  REQUIRE_GPU();
  const char* dir = std::getenv("TILEVIS_GPU_TRACES");
  if (!dir || !*dir) GTEST_SKIP() << "TILEVIS_GPU_TRACES not set (gpu_run.sh sets it to the built-in scenes' traces)";
  std::vector<std::filesystem::path> traces;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() == ".tvt") traces.push_back(e.path());
  std::sort(traces.begin(), traces.end());
  ASSERT_GE(traces.size(), 15u) << "expected every traces/scenes/*.json as a trace in " << dir;
  std::vector<trace::Frame> frames;
  for (const auto& t : traces) frames.push_back(std::move(trace::read(t.string()).frames.at(0)));
  // Golden (CPU) for every scene at once, then the GPU runs one at a time.
  std::vector<std::future<vis::GoldenResult>> golden;
  for (const auto& f : frames)
    golden.push_back(std::async(std::launch::async, [&f] { return ct::golden_of(f, 32, 32, "hybrid"); }));
  for (size_t k = 0; k < frames.size(); ++k) {
    const std::string name = traces[k].stem().string();
    SCOPED_TRACE(name);
    auto cfg = ct::config(cuda::Device::gpu, cuda::Precision::floating, 32, 32);
    cfg.runs = 1;
    const auto fl = cuda::run_cuda(frames[k], cfg);
    EXPECT_EQ(fl.float_anomalies, 0u);
    EXPECT_EQ(fl.float_negative_areas, 0u);
    uint64_t negative = 0;
    for (double a : fl.visible_area) negative += a < 0 ? 1 : 0;
    EXPECT_EQ(negative, 0u);
    // The tiled z-buffer = the truth, from tiny pools and segments of 8 (helpers merging by CAS).
    auto zc = ct::config(cuda::Device::gpu, cuda::Precision::exact, 32, 32);
    zc.runs = 1;
    zc.initial_pool = 4;
    const auto z = cuda::run_cuda_zbuffer(frames[k], zc, cuda::ZBufferKind::tiled);
    const std::vector<int32_t> truth = ct::truth_ids_of(frames[k]);
    ASSERT_EQ(z.ids.size(), truth.size());
    uint64_t z_differ = 0;
    for (size_t i = 0; i < truth.size(); ++i) z_differ += truth[i] != z.ids[i] ? 1 : 0;
    EXPECT_EQ(z_differ, 0u);
    cfg.precision = cuda::Precision::exact;
    cfg.hybrid = true;
    const auto r = cuda::run_cuda(frames[k], cfg);
    const vis::GoldenResult g = golden[k].get();
    const auto d = ct::diff(g, r);
    ct::expect_bit_identical(d);
    std::printf("%-18s hybrid: %llu samples, %llu id / %llu tile-cell / %llu area mismatches, totals %s; "
                "%llu per-pixel tiles; float: %llu exact-region areas, %llu negative, %llu anomalies\n",
                name.c_str(), (unsigned long long)d.samples_compared, (unsigned long long)d.id_mismatches,
                (unsigned long long)d.tile_cell_mismatches, (unsigned long long)d.area_bit_mismatches,
                d.totals_equal ? "equal" : d.totals.c_str(), (unsigned long long)g.fallback_tiles,
                (unsigned long long)fl.float_exact_areas, (unsigned long long)fl.float_negative_areas,
                (unsigned long long)fl.float_anomalies);
  }
}

// A sequence of frames through one pipeline (run_cuda_frames, the orbit's timing) gives each
// frame the ids a run of that frame alone gives.
TEST(Gpu, FrameSequenceGivesEachFramesIds) {
  REQUIRE_GPU();
  const std::vector<std::string> names = {"cubes", "mixed", "cubes"};
  std::vector<trace::Frame> frames;
  for (const auto& n : names) frames.push_back(ct::scene(n));
  for (auto prec : {cuda::Precision::exact, cuda::Precision::floating}) {
    auto cfg = ct::config(cuda::Device::gpu, prec, 32, 32);
    cfg.runs = 2;
    const auto seq = cuda::run_cuda_frames(frames, cfg, 2);
    ASSERT_EQ(seq.size(), frames.size());
    for (size_t k = 0; k < frames.size(); ++k) {
      EXPECT_EQ(seq[k].ids_hash, cuda::ids_hash(cuda::run_cuda(frames[k], cfg).ids)) << names[k];
      EXPECT_GT(seq[k].new_frame_ms, 0.0);
      EXPECT_GT(seq[k].graph_ms, 0.0);
      EXPECT_GT(seq[k].first_ms, 0.0);
    }
  }
}

// The device-sized graph of a sequence (DevGraph: recorded once, no frame's sizes in it) meets a
// frame past the bounds it was recorded for: the launch overflows, the frame runs again with host
// reads and the graph is recorded again; every frame gets the ids a run of it alone gives, and
// in the later laps every frame runs through the one graph without a retry.
TEST(Gpu, DeviceSizedGraphPastItsBoundsRunsAgain) {
  REQUIRE_GPU();
  const std::vector<trace::Frame> frames = ct::small_big_sequence();
  for (auto prec : {cuda::Precision::exact, cuda::Precision::floating}) {
    auto cfg = ct::config(cuda::Device::gpu, prec, 32, 32);
    cfg.runs = 2;
    const auto seq = cuda::run_cuda_frames(frames, cfg, 2);
    ASSERT_EQ(seq.size(), frames.size());
    EXPECT_GE(seq[1].first_retries, 1u);  // big after small's graph: past its bounds
    EXPECT_EQ(seq[2].first_retries, 0u);
    EXPECT_EQ(seq[3].first_retries, 0u);
    for (size_t k = 0; k < frames.size(); ++k) {
      EXPECT_EQ(seq[k].retries, 0u) << k;  // the laps: one graph for all four frames
      EXPECT_EQ(seq[k].ids_hash, cuda::ids_hash(cuda::run_cuda(frames[k], cfg).ids)) << k;
    }
  }
}

}  // namespace
