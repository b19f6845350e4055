// Primitive setup, golden SVGPU pipeline and z-buffer truth on small scenes: golden
// agrees with the truth sample for sample, runs are deterministic, clipping conserves
// area, and the per-pixel modes count what they must.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>
#include <thread>

#include <sched.h>


#include <gtest/gtest.h>

#include "geom/predicates.h"
#include "scene_frames.h"
#include "visibility/golden.h"
#include "visibility/parallel.h"
#include "visibility/setup.h"
#include "visibility/truth.h"

using namespace tilevis;

namespace {

using testsupport::frame_of;
using testsupport::shipped;

struct Agreement {
  uint64_t compared = 0, mismatched = 0;
};

Agreement agree(const std::vector<int32_t>& a, const std::vector<int32_t>& b) {
  Agreement r;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i] < 0 && b[i] < 0) continue;
    ++r.compared;
    r.mismatched += a[i] != b[i];
  }
  return r;
}

const char* kCubes = R"({
  "viewport": [320, 240],
  "camera": {"eye": [1.6, 1.2, 3.0], "target": [0, 0, 0], "fov_y_deg": 50, "near": 0.1, "far": 20},
  "objects": [
    {"name": "floor", "primitive": {"type": "plane", "size": [6, 6], "subdivisions": 3}, "transform": {"translate": [0, -0.6, 0]}},
    {"name": "box", "primitive": {"type": "box", "size": [1, 1, 1]}, "transform": {"rotate_deg": [10, 30, 0]}},
    {"name": "ball", "primitive": {"type": "sphere", "radius": 0.45, "segments": 24, "rings": 12},
     "transform": {"translate": [-0.9, -0.1, 0.8]}},
    {"name": "cards", "primitive": {"type": "quads", "count": 4, "size": [0.5, 0.7], "origin": [1.6, 0, 1.5], "step": [-0.1, 0.05, -0.25]}}
  ]})";

}  // namespace

TEST(Setup, CubeSilhouetteIsItsOutline) {
  // A cube seen from a generic direction shows three faces; its outline is a hexagon of
  // six edges, each between a front and a back face.
  auto f = frame_of("cube", R"({"viewport": [200, 200], "camera": {"eye": [2, 1.5, 2.5]},
      "objects": [{"primitive": {"type": "box"}}]})");
  auto s = vis::primitive_setup(f, {});
  EXPECT_EQ(s.stats.triangles_in, 12u);
  EXPECT_EQ(s.stats.front_facing, 6u);
  EXPECT_EQ(s.stats.back_facing, 6u);
  EXPECT_EQ(s.silhouettes.size(), 6u);
}

TEST(Setup, DrawsJoinedInOrderEqualEachDrawSetUpAlone) {
  // Draws are set up on threads and joined in draw order: the frame's setup is each draw's
  // own, ids and draw indices shifted, in order, whatever the schedule.
  auto f = frame_of("cubes", kCubes);
  ASSERT_GE(f.draws.size(), 4u);
  const auto whole = vis::primitive_setup(f, {});
  size_t tri = 0, sil = 0;
  uint32_t first_id = 0;
  for (uint32_t d = 0; d < f.draws.size(); ++d) {
    trace::Frame one = f;
    one.draws = {f.draws[d]};
    const auto alone = vis::primitive_setup(one, {});
    for (const auto& t : alone.triangles) {
      ASSERT_LT(tri, whole.triangles.size());
      const auto& w = whole.triangles[tri++];
      EXPECT_EQ(w.id, t.id + first_id);
      EXPECT_EQ(w.draw, d);
      EXPECT_EQ(w.front, t.front);
      for (int k = 0; k < 3; ++k) EXPECT_TRUE(w.v[k] == t.v[k]);
    }
    for (const auto& e : alone.silhouettes) {
      ASSERT_LT(sil, whole.silhouettes.size());
      const auto& w = whole.silhouettes[sil++];
      EXPECT_TRUE(w.a == e.a && w.b == e.b);
      EXPECT_EQ(w.draw, d);
    }
    for (uint32_t i = 0; i < f.draws[d].triangle_count(); ++i) EXPECT_EQ(whole.triangle_draw[first_id + i], d);
    first_id += uint32_t(f.draws[d].triangle_count());
  }
  EXPECT_EQ(tri, whole.triangles.size());
  EXPECT_EQ(sil, whole.silhouettes.size());
  EXPECT_EQ(whole.triangle_draw.size(), f.triangle_count());
}

TEST(ForEachIndex, VisitsEveryIndexOnceAndRethrowsTheLowestFailure) {
  struct Scratch {
    int uses = 0;
  };
  std::vector<std::atomic<int>> seen(1000);
  vis::for_each_index<Scratch>(seen.size(), [&](size_t i, Scratch& s) {
    ++s.uses;
    ++seen[i];
  });
  for (const auto& v : seen) EXPECT_EQ(v.load(), 1);
  try {
    vis::for_each_index<Scratch>(100, [](size_t i, Scratch&) {
      if (i == 70 || i == 30 || i == 90) throw std::runtime_error(std::to_string(i));
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "30");
  }
  vis::for_each_index<Scratch>(0, [](size_t, Scratch&) { FAIL(); });
}

TEST(ForEachIndex, TilevisThreadsSetsTheCount) {
  const char* old = std::getenv("TILEVIS_THREADS");
  const std::string saved = old ? old : "";
  const char* old_slurm = std::getenv("SLURM_CPUS_ON_NODE");
  const std::string saved_slurm = old_slurm ? old_slurm : "";
  unsetenv("SLURM_CPUS_ON_NODE");
  setenv("TILEVIS_THREADS", "1", 1);
  EXPECT_EQ(vis::host_threads(), 1u);
  setenv("TILEVIS_THREADS", "3", 1);
  EXPECT_EQ(vis::host_threads(), 3u);
  setenv("TILEVIS_THREADS", "zero", 1);  // not a count: the CPUs this process may use
  EXPECT_GE(vis::host_threads(), 1u);
  EXPECT_LE(vis::host_threads(), std::max(1u, std::thread::hardware_concurrency()));
  // Bound to one CPU (as taskset or a Slurm task of one CPU would), one thread.
  cpu_set_t all, one;
  ASSERT_EQ(sched_getaffinity(0, sizeof all, &all), 0);
  CPU_ZERO(&one);
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &all)) {
      CPU_SET(c, &one);
      break;
    }
  ASSERT_EQ(sched_setaffinity(0, sizeof one, &one), 0);
  EXPECT_EQ(vis::host_threads(), 1u);
  ASSERT_EQ(sched_setaffinity(0, sizeof all, &all), 0);
  EXPECT_EQ(vis::host_threads(), unsigned(CPU_COUNT(&all)));
  // A Slurm job of one CPU whose task is not bound (its mask is the whole node): one thread.
  setenv("SLURM_CPUS_ON_NODE", "1", 1);
  EXPECT_EQ(vis::host_threads(), 1u);
  setenv("SLURM_CPUS_ON_NODE", "4096", 1);  // more than the mask holds: the mask
  EXPECT_EQ(vis::host_threads(), unsigned(CPU_COUNT(&all)));
  setenv("SLURM_CPUS_ON_NODE", "two", 1);  // not a count: ignored
  EXPECT_EQ(vis::host_threads(), unsigned(CPU_COUNT(&all)));
  setenv("TILEVIS_THREADS", "3", 1);  // the user's count wins
  setenv("SLURM_CPUS_ON_NODE", "1", 1);
  EXPECT_EQ(vis::host_threads(), 3u);
  if (old_slurm) setenv("SLURM_CPUS_ON_NODE", saved_slurm.c_str(), 1);
  else unsetenv("SLURM_CPUS_ON_NODE");
  // One thread: every index on the calling thread, in order.
  setenv("TILEVIS_THREADS", "1", 1);
  std::vector<size_t> order;
  vis::for_each_index<int>(5, [&](size_t i, int&) { order.push_back(i); });
  EXPECT_EQ(order, (std::vector<size_t>{0, 1, 2, 3, 4}));
  if (old) setenv("TILEVIS_THREADS", saved.c_str(), 1);
  else unsetenv("TILEVIS_THREADS");
}

// Ahead: results handed over whatever order the consumer asks in, keys not queued left to the
// caller, a thread's exception rethrown at its key, and never more than `window` results
// computed and waiting.
TEST(Ahead, HandsOverInAnyOrderWithinItsWindow) {
  constexpr unsigned kThreads = 3;
  constexpr size_t kWindow = 4;
  std::atomic<int> waiting{0}, most{0};
  std::atomic<bool> wrong_worker{false};
  std::vector<std::atomic<bool>> by_thread(61);
  vis::Ahead<int64_t> ahead(kThreads, kWindow, [&](uint32_t key, int64_t& r, unsigned worker) {
    if (worker > kThreads) wrong_worker = true;
    if (key == 13) throw std::runtime_error("thirteen");
    r = int64_t(key) * key;
    if (worker < kThreads) {
      by_thread[key] = true;
      const int now = ++waiting;
      for (int m = most.load(); now > m && !most.compare_exchange_weak(m, now);) {}
    }
  });
  std::vector<uint32_t> keys(60);
  std::iota(keys.begin(), keys.end(), 0u);
  ahead.submit(keys);
  ahead.submit({5, 60});  // 5 is queued already; 60 is new
  std::this_thread::sleep_for(std::chrono::milliseconds(50));  // the threads fill the window
  std::vector<uint32_t> order = {59, 1, 0, 60, 30, 2};
  for (uint32_t k = 3; k < 59; ++k)
    if (k != 30) order.push_back(k);
  for (uint32_t k : order) {
    int64_t r = -1;
    if (k == 13) {
      EXPECT_THROW(ahead.take(k, r), std::runtime_error);
      continue;
    }
    ASSERT_TRUE(ahead.take(k, r)) << k;
    EXPECT_EQ(r, int64_t(k) * k);
    if (by_thread[k]) --waiting;  // a thread's result no longer waits
  }
  int64_t r = -1;
  EXPECT_FALSE(ahead.take(7, r));    // taken already
  EXPECT_FALSE(ahead.take(1000, r));  // never queued
  EXPECT_EQ(r, -1);
  EXPECT_FALSE(wrong_worker);
  // The count here lags take() by one: a thread may start the next result between take()
  // freeing its slot and the decrement above. Without the window it would reach about 60.
  EXPECT_LE(most.load(), int(kWindow) + 1);
  EXPECT_GE(most.load(), 1);
}

TEST(Setup, NearPlaneClipsIntoAFanWithOneId) {
  // A ground plane reaching behind the camera crosses the near plane.
  auto f = frame_of("ground", R"({"viewport": [320, 200], "camera": {"eye": [0, 1, 2], "target": [0, 0, 0], "near": 0.1},
      "objects": [{"primitive": {"type": "plane", "size": [100, 100]}}]})");
  auto s = vis::primitive_setup(f, {});
  EXPECT_EQ(s.stats.triangles_in, 2u);
  EXPECT_EQ(s.stats.clipped, 2u);
  EXPECT_GT(s.triangles.size(), 2u);
  for (const auto& t : s.triangles) {
    EXPECT_LE(t.id, 1u);
    EXPECT_TRUE(t.clipped);
    for (const auto& v : t.v) EXPECT_LT(std::abs(v.x), 1 << 23);
  }
}

TEST(Setup, SoupWeldsByPosition) {
  // The same cube as triangle soup: welded by position it has the same silhouette.
  auto indexed = frame_of("cube_i", R"({"viewport": [200, 200], "camera": {"eye": [2, 1.5, 2.5]},
      "objects": [{"primitive": {"type": "box"}}]})");
  auto soup = indexed;
  auto& d = soup.draws[0];
  std::vector<trace::Vec4> v;
  for (uint32_t i : d.indices) v.push_back(d.vertices[i]);
  d.vertices = v;
  std::iota(d.indices.begin(), d.indices.end(), 0u);
  auto unwelded = vis::primitive_setup(soup, {});
  EXPECT_EQ(unwelded.silhouettes.size(), 18u);  // no flag: every front edge is a boundary
  d.flags |= trace::kTriangleSoup;
  EXPECT_EQ(vis::primitive_setup(soup, {}).silhouettes.size(), 6u);
}

// An edge hides inside the visible surface only where two front faces share it from
// opposite sides. A duplicated face shares all three of its edges with its copy from the same
// side: they bound both copies, so they are silhouettes (and hybrid then equals the truth).
TEST(Setup, EdgesSharedFromTheSameSideAreSilhouettes) {
  auto f = frame_of("grid_dup", R"({"viewport": [200, 200], "camera": {"eye": [0.3, 3, 1], "target": [0, 0, 0]},
      "objects": [{"primitive": {"type": "plane", "size": [2, 2], "subdivisions": 4}}]})");
  const size_t outline = vis::primitive_setup(f, {}).silhouettes.size();
  ASSERT_EQ(outline, 16u);  // the grid's border
  auto& d = f.draws[0];
  const auto s0 = vis::primitive_setup(f, {});
  // Duplicate a front-facing triangle whose edges are all interior to the grid.
  size_t dup = SIZE_MAX;
  for (size_t t = 0; t < s0.triangles.size() && dup == SIZE_MAX; ++t) {
    if (!s0.triangles[t].front) continue;
    bool interior = true;
    for (const auto& e : s0.silhouettes)
      for (int k = 0; k < 3; ++k) {
        const auto &a = s0.triangles[t].v[k], &b = s0.triangles[t].v[(k + 1) % 3];
        interior = interior && !((e.a == a && e.b == b) || (e.a == b && e.b == a));
      }
    if (interior) dup = t;
  }
  ASSERT_NE(dup, SIZE_MAX);
  // A smaller copy of it, nearer the eye, added twice: the two copies share every edge.
  const uint32_t id = s0.triangles[dup].id, base = uint32_t(d.vertices.size());
  trace::Vec4 c{0, 0, 0, 0};
  for (int k = 0; k < 3; ++k) {
    const trace::Vec4& v = d.vertices[d.indices[3 * id + uint32_t(k)]];
    c = {c.x + v.x / 3, c.y + v.y / 3, c.z + v.z / 3, c.w + v.w / 3};
  }
  for (int k = 0; k < 3; ++k) {
    const trace::Vec4& v = d.vertices[d.indices[3 * id + uint32_t(k)]];
    d.vertices.push_back({(v.x + c.x) / 2, (v.y + c.y) / 2, (v.z + c.z) / 2 - 0.05f * (v.w + c.w) / 2, (v.w + c.w) / 2});
  }
  for (int copy = 0; copy < 2; ++copy) d.indices.insert(d.indices.end(), {base, base + 1, base + 2});
  const auto s1 = vis::primitive_setup(f, {});
  // Their three edges, each shared by two faces on the same side, are silhouettes.
  EXPECT_EQ(s1.silhouettes.size(), outline + 3);
  // Golden equals the truth (the copy ties with the original, the earlier wins).
  vis::GoldenConfig cfg;
  EXPECT_EQ(vis::golden_visibility(s1, cfg).ids, vis::zbuffer_truth(s1, {}).ids);
}

class GoldenVsTruth : public ::testing::TestWithParam<std::tuple<uint32_t, uint32_t>> {};

TEST_P(GoldenVsTruth, SmallSceneAgreesSampleForSample) {
  auto [tile, samples] = GetParam();
  // Non-penetrating by construction: the one assumption the method makes (SVGPU §3).
  auto f = frame_of("cubes", kCubes);
  f.samples = trace::standard_samples(samples);
  auto s = vis::primitive_setup(f, {});
  vis::GoldenConfig gc;
  gc.tile_w = gc.tile_h = tile;
  auto g = vis::golden_visibility(s, gc);
  vis::TruthConfig tc;
  tc.tile_w = tc.tile_h = tile;
  auto t = vis::zbuffer_truth(s, tc);
  auto a = agree(g.ids, t.ids);
  EXPECT_GT(a.compared, 320u * 240u * samples / 2);
  EXPECT_EQ(a.mismatched, 0u);
  EXPECT_EQ(g.samples_covered, t.samples_covered);
  EXPECT_EQ(g.fragments_generated, t.fragments_generated);
  EXPECT_GT(g.clip_polygons, 0u);  // the scene makes the pipeline clip
}

INSTANTIATE_TEST_SUITE_P(Tiles, GoldenVsTruth,
                         ::testing::Combine(::testing::Values(4u, 16u, 32u, 64u), ::testing::Values(1u, 4u)));

TEST(Golden, NonSquareTilesAgreeToo) {
  auto f = frame_of("cubes", kCubes);
  auto s = vis::primitive_setup(f, {});
  vis::GoldenConfig gc;
  gc.tile_w = 48;
  gc.tile_h = 8;
  auto g = vis::golden_visibility(s, gc);
  auto t = vis::zbuffer_truth(s, {});
  EXPECT_EQ(agree(g.ids, t.ids).mismatched, 0u);
  EXPECT_EQ(g.tiles.tiles_x, 7u);
  EXPECT_EQ(g.tiles.tiles_y, 30u);
}

TEST(Golden, DeterministicAcrossRuns) {
  auto f = frame_of("cubes", kCubes);
  auto s1 = vis::primitive_setup(f, {});
  auto s2 = vis::primitive_setup(f, {});
  auto a = vis::golden_visibility(s1, {});
  auto b = vis::golden_visibility(s2, {});
  EXPECT_EQ(a.ids, b.ids);
  EXPECT_EQ(a.visible_area, b.visible_area);
  EXPECT_EQ(a.tiles.rows, b.tiles.rows);
}

// SVGPU §4.1's finer occlusion bins only shorten each piece's scan of occluders: every
// result and counter equals that of one bin per tile, for bins that divide the tile and
// bins that do not.
TEST(Golden, FinerOcclusionBinsChangeNothingButTheScan) {
  for (const auto& f : {frame_of("cubes", kCubes), shipped("bunny", 480, 270, 1)}) {
    auto s = vis::primitive_setup(f, {});
    vis::GoldenConfig base;
    base.tile_w = base.tile_h = 32;
    base.options.occlusion_bin_w = base.options.occlusion_bin_h = 0;  // one bin per tile
    const auto ref = vis::golden_visibility(s, base);
    ASSERT_GT(ref.occlusion_tests, 0u);
    for (auto [bw, bh] : {std::pair{1u, 1u}, {4u, 4u}, {5u, 7u}, {8u, 32u}, {31u, 31u}, {32u, 32u}}) {
      vis::GoldenConfig gc = base;
      gc.options.occlusion_bin_w = bw;
      gc.options.occlusion_bin_h = bh;
      const auto g = vis::golden_visibility(s, gc);
      EXPECT_EQ(g.ids, ref.ids) << bw << "x" << bh;
      EXPECT_EQ(g.visible_area, ref.visible_area) << bw << "x" << bh;
      EXPECT_EQ(g.tiles.rows, ref.tiles.rows) << bw << "x" << bh;
    }
  }
}

TEST(Golden, VisibleAreaOfAnUnoccludedTriangleIsItsArea) {
  // One quad facing the camera, orthographic-like: both triangles fully visible, their
  // visible areas sum to the quad's snapped area whatever the tiling.
  auto f = frame_of("quad", R"({"viewport": [256, 256], "camera": {"eye": [0, 0, 3]},
      "objects": [{"primitive": {"type": "quads", "count": 1, "size": [1.3, 0.9]}}]})");
  auto s = vis::primitive_setup(f, {});
  ASSERT_EQ(s.triangles.size(), 2u);
  double exact = 0;
  for (const auto& t : s.triangles)
    exact += std::fabs(double(geom::orient2d(t.v[0].xy(), t.v[1].xy(), t.v[2].xy()))) / 2 / 65536.0;
  for (uint32_t tile : {4u, 7u, 32u, 256u}) {
    vis::GoldenConfig gc;
    gc.tile_w = gc.tile_h = tile;
    auto g = vis::golden_visibility(s, gc);
    double sum = g.visible_area[0] + g.visible_area[1];
    EXPECT_NEAR(sum, exact, exact * 1e-12) << "tile " << tile;
    EXPECT_EQ(g.visible_pieces, g.pieces_total);
  }
}

TEST(Truth, EarlyZCountsFollowSubmissionOrder) {
  // Five cards one behind another. Back to front, early-Z shades every fragment; front to
  // back only the nearest card's. As separate draws, sorting draws front to back helps.
  const char* back_to_front = R"({"viewport": [200, 200], "camera": {"eye": [0, 0, 3]},
      "objects": [{"name": "c", "primitive": {"type": "quads", "count": 1, "size": 1},
                   "instances": [{"translate": [0, 0, -2]}, {"translate": [0, 0, -1.5]}, {"translate": [0, 0, -1]},
                                 {"translate": [0, 0, -0.5]}, {"translate": [0, 0, 0]}]}]})";
  auto s = vis::primitive_setup(frame_of("btf", back_to_front), {});
  auto t = vis::zbuffer_truth(s, {});
  EXPECT_EQ(t.modes.none, t.fragments_generated);
  EXPECT_EQ(t.modes.early_z, t.fragments_generated);  // each card is nearer than the last
  EXPECT_EQ(t.modes.prepass, t.samples_covered);
  EXPECT_EQ(t.modes.hsr, t.samples_covered);
  EXPECT_EQ(t.modes.early_z_sorted, t.samples_covered);  // nearest draw first: the rest fail
  EXPECT_LT(t.samples_covered, t.fragments_generated / 2);
}

TEST(Truth, QuantizedDepthShowsZFighting) {
  // Two overlapping cards 0.002 apart at distance 10: exact depth separates them; 12-bit depth
  // cannot, so the earlier-drawn (farther) card wins some samples.
  auto s = vis::primitive_setup(frame_of("fight", R"({"viewport": [200, 200],
      "camera": {"eye": [0, 0, 10], "near": 0.5, "far": 100},
      "objects": [{"name": "far", "primitive": {"type": "quads", "count": 1, "size": 2}, "transform": {"translate": [0, 0, -0.002]}},
                  {"name": "near", "primitive": {"type": "quads", "count": 1, "size": 2}, "transform": {"rotate_deg": [0, 0, 1]}}]})"),
                                  {});
  auto exact = vis::zbuffer_truth(s, {});
  vis::TruthConfig q;
  q.quantized_depth_bits = 12;
  auto coarse = vis::zbuffer_truth(s, q);
  auto count_far = [](const std::vector<int32_t>& ids) {
    return std::count_if(ids.begin(), ids.end(), [](int32_t id) { return id == 0 || id == 1; });
  };
  EXPECT_EQ(count_far(exact.ids), 0);   // the near card hides the far one wherever they overlap... 
  EXPECT_GT(count_far(coarse.ids), 0);  // ...until depth is too coarse to tell them apart
}

TEST(GoldenVsTruthShipped, BunnyAtQuarterResolution) {
  auto f = shipped("bunny", 480, 270, 1);
  auto s = vis::primitive_setup(f, {});
  auto g = vis::golden_visibility(s, {});
  auto t = vis::zbuffer_truth(s, {});
  auto a = agree(g.ids, t.ids);
  EXPECT_GT(a.compared, 10000u);
  EXPECT_EQ(a.mismatched, 0u);
}

// MSAA: visibility per sample, shading once per pixel and triangle. On large triangles 4
// samples cost hardly more shader invocations than 1 (only pixels on edges between triangles
// add one); every producer of a mode counts the same invocations.
TEST(Msaa, ShadesOncePerPixelAndTriangle) {
  const auto one = vis::primitive_setup(frame_of("cubes1", kCubes, 1), {});
  const auto four = vis::primitive_setup(frame_of("cubes4", kCubes, 4), {});
  const vis::GoldenResult g1 = vis::golden_visibility(one, {}), g4 = vis::golden_visibility(four, {});
  const vis::TruthResult t1 = vis::zbuffer_truth(one, {}), t4 = vis::zbuffer_truth(four, {});
  EXPECT_EQ(g1.shader_invocations, g1.samples_covered);  // one sample per pixel: the same thing
  EXPECT_EQ(g1.shader_invocations, t1.modes.hsr);
  EXPECT_EQ(g4.shader_invocations, t4.modes.hsr);          // analytic and per-pixel HSR agree
  EXPECT_LT(g4.shader_invocations, g4.samples_covered);    // far fewer invocations than samples
  EXPECT_GE(g4.shader_invocations, g1.shader_invocations * 95 / 100);
  EXPECT_LE(g4.shader_invocations, g1.shader_invocations * 11 / 10);
  EXPECT_LE(t4.modes.hsr, t4.modes.early_z);
  EXPECT_LE(t4.modes.early_z, t4.modes.none);
  EXPECT_LT(t4.modes.none, t4.fragments_generated);
  // Per-pixel tiles count the same invocations as the truth, translucent fragments included.
  vis::GoldenConfig pp;
  pp.mode = "per_pixel";
  EXPECT_EQ(vis::golden_visibility(four, pp).shader_invocations, t4.modes.hsr);
  auto glass = frame_of("cubes_glass", kCubes, 4);
  glass.draws.back().flags |= trace::kBlended;  // the cards
  const auto sg = vis::primitive_setup(glass, {});
  const vis::TruthResult tg = vis::zbuffer_truth(sg, {});
  EXPECT_GT(tg.modes.hsr, vis::golden_visibility(sg, pp).samples_covered / 4);  // the cards are shaded
  EXPECT_EQ(vis::golden_visibility(sg, pp).shader_invocations, tg.modes.hsr);
}

// Sample-rate shading (trace::kSampleRateShading, a draw whose shader reads the sample):
// that draw's triangles run once per sample they shade, the others once per pixel, in
// every producer and mode.
TEST(Msaa, SampleRateDrawsShadeEverySample) {
  auto all = frame_of("cubes4_sample_rate", kCubes, 4);
  for (trace::Draw& d : all.draws) d.flags |= trace::kSampleRateShading;
  const auto sa = vis::primitive_setup(all, {});
  const vis::GoldenResult ga = vis::golden_visibility(sa, {});
  const vis::TruthResult ta = vis::zbuffer_truth(sa, {});
  EXPECT_EQ(ga.shader_invocations, ga.samples_covered);  // every visible sample is an invocation
  EXPECT_EQ(ta.modes.hsr, ta.samples_covered);
  EXPECT_EQ(ta.modes.none, ta.fragments_generated);
  vis::GoldenConfig pp;
  pp.mode = "per_pixel";
  EXPECT_EQ(vis::golden_visibility(sa, pp).shader_invocations, ta.modes.hsr);

  // Only the last draw at sample rate: between the pixel rate and the all-sample count.
  auto one = frame_of("cubes4_last_sample_rate", kCubes, 4);
  one.draws.back().flags |= trace::kSampleRateShading;
  const auto so = vis::primitive_setup(one, {});
  const vis::GoldenResult go = vis::golden_visibility(so, {});
  const vis::GoldenResult gp = vis::golden_visibility(vis::primitive_setup(frame_of("cubes4", kCubes, 4), {}), {});
  EXPECT_GT(go.shader_invocations, gp.shader_invocations);
  EXPECT_LT(go.shader_invocations, ga.shader_invocations);
  EXPECT_EQ(go.shader_invocations, vis::zbuffer_truth(so, {}).modes.hsr);
  EXPECT_EQ(vis::golden_visibility(so, pp).shader_invocations, vis::zbuffer_truth(so, {}).modes.hsr);
}
