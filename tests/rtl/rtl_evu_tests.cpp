// Fidelity rtl's cycle reference (model/units/early_visibility_unit/rtl_evu.h, rtl_ref/evu) on
// every 16th tile job of the bunny and the interpenetrating scene (1080p, 32x32 tiles; the jobs
// rtl.jobs.dump writes): per tile, the clocks it returns against the testbenches' figures for the
// same jobs (the CSVs rtl.{tile_sequencer,clip,occlude}.jobs write) and against the RTL's clock
// formulas computed here from the public functions; a job whose golden counters were changed
// must throw; make_evu_job must rebuild the dumped jobs from the scene's trace.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "drivers.h"
#include "scoreboard.h"
#include "tilevis/trace.h"
#include "units/early_visibility_unit/rtl_evu.h"
#include "visibility/evu_jobs.h"
#include "visibility/setup.h"
#include "visibility/tile_resolver.h"

using namespace tilevis;

namespace {

constexpr uint64_t kStride = 16;  // as the testbenches' CI sample (--job-stride 16)
const char* const kScenes[] = {"bunny", "interpenetrating"};

std::string jobs_path(const std::string& scene) { return std::string(TILEVIS_RTL_JOBS) + "/" + scene + "/evu_jobs.txt"; }

std::vector<vis::EvuJob> sample(const std::string& scene) {
  std::vector<vis::EvuJob> jobs;
  uint64_t seen = 0;
  vis::read_evu_jobs(jobs_path(scene), [&](const vis::EvuJob& j) {
    if (seen++ % kStride == 0) jobs.push_back(j);
  });
  return jobs;
}

// A testbench CSV's column, per (scene, tile).
std::map<std::pair<std::string, uint32_t>, uint64_t> csv_column(const std::string& file, const std::string& column) {
  std::ifstream in(std::string(TILEVIS_RTL_CSV) + "/" + file);
  if (!in) throw std::runtime_error(file + ": missing (the rtl.*.jobs tests write it)");
  std::string line;
  std::getline(in, line);
  std::vector<std::string> head;
  {
    std::istringstream s(line);
    for (std::string c; std::getline(s, c, ',');) head.push_back(c);
  }
  const auto find = [&](const std::string& c) {
    const auto it = std::find(head.begin(), head.end(), c);
    if (it == head.end()) throw std::runtime_error(file + ": no column " + c);
    return size_t(it - head.begin());
  };
  const size_t src = find("source"), tile = find("tile"), col = find(column);
  std::map<std::pair<std::string, uint32_t>, uint64_t> m;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::istringstream s(line);
    for (std::string c; std::getline(s, c, ',');) f.push_back(c);
    const std::string& path = f.at(src);
    const size_t slash = path.rfind('/'), prev = path.rfind('/', slash - 1);
    m[{path.substr(prev + 1, slash - prev - 1), uint32_t(std::stoul(f.at(tile)))}] = std::stoull(f.at(col));
  }
  return m;
}

// The sequencer's clocks per triangle, pass by pass: rows = max(1, ceil(edges / L)) when it
// meets every edge of the pass, min(floor(p / L) + 2, rows) when test 6 stops it after p pairs
// (stage A's row read ahead is dropped), but floor(p / L) + 1 for the pass's last triangle
// (`done` comes with its stopping row: nothing waits for the dropped one).
std::vector<uint64_t> reject_formula(const std::vector<uint32_t>& zmax, const std::vector<uint32_t>& zmin) {
  const uint32_t L = rtl::kSeqLanes;
  std::vector<uint64_t> c(zmax.size(), 0);
  for (size_t t0 = 0; t0 < zmax.size(); t0 += rtl::kSeqTriCap)
    for (size_t e0 = 0; e0 == 0 || e0 < zmin.size(); e0 += rtl::kSeqEdgeCap) {
      const size_t en = std::min<size_t>(rtl::kSeqEdgeCap, zmin.size() - e0);
      const uint64_t rows = std::max<uint64_t>(1, (en + L - 1) / L);
      const size_t t1 = std::min(zmax.size(), t0 + rtl::kSeqTriCap);
      for (size_t t = t0; t < t1; ++t) {
        uint64_t p = 0;
        while (p < en && zmin[e0 + p] <= zmax[t]) ++p;
        c[t] += p < en ? std::min<uint64_t>(p / L + (t + 1 == t1 ? 1 : 2), rows) : rows;
      }
      if (zmin.empty()) break;
    }
  return c;
}

class RtlEvuTest : public ::testing::TestWithParam<const char*> {};

// The sequencer's per-triangle clocks across passes (lists past both capacities), on random
// lists with many equal depths: the formula, and the walk is their sum + 2 a pass.
TEST(RtlEvu, SequencerClocksPerTriangleAcrossPasses) {
  std::mt19937_64 rng(21);
  rtl::TileSequencerDriver seq;
  uint64_t multi_pass = 0;
  for (int k = 0; k < 64; ++k) {
    const bool big = k % 8 == 0;
    const uint32_t nt = 1 + uint32_t(rng() % (big ? 2 * rtl::kSeqTriCap + 3 : 40));
    const uint32_t ne = uint32_t(rng() % (big ? 2 * rtl::kSeqEdgeCap + 3 : 4 * rtl::kSeqLanes + 3));
    const uint32_t range = 1 + uint32_t(rng() % 64);
    std::vector<uint32_t> zmax, zmin;
    for (uint32_t t = 0; t < nt; ++t) zmax.push_back(uint32_t(rng() % range));
    for (uint32_t e = 0; e < ne; ++e) zmin.push_back(uint32_t(rng() % range));
    std::sort(zmin.begin(), zmin.end());
    const rtl::TileSequencerDriver::Result r = seq.run(zmax, zmin);
    SCOPED_TRACE("job " + std::to_string(k) + ": " + std::to_string(nt) + " triangles, " + std::to_string(ne) +
                 " edges");
    EXPECT_EQ(r.tri_clocks, reject_formula(zmax, zmin));
    uint64_t sum = 0;
    for (uint64_t c : r.tri_clocks) sum += c;
    EXPECT_EQ(r.walk_clocks, sum + 2 * r.passes);
    multi_pass += r.passes > 1;
  }
  EXPECT_GT(multi_pass, 0u);
}

TEST(RtlEvu, AvailableAndRefusesOtherParameters) {
  EXPECT_TRUE(sim::rtl_evu_available());
  EXPECT_THROW(sim::make_rtl_evu(4, 512, 256), std::runtime_error);
  EXPECT_THROW(sim::make_rtl_evu(8, 1024, 256), std::runtime_error);
  EXPECT_THROW(sim::make_rtl_evu(8, 512, 128), std::runtime_error);
  EXPECT_NO_THROW(sim::make_rtl_evu(8, 512, 256));
}

TEST_P(RtlEvuTest, ClocksMatchTestbenchesAndFormulas) {
  const std::string scene = GetParam();
  const std::vector<vis::EvuJob> jobs = sample(scene);
  ASSERT_GT(jobs.size(), 10u);
  const auto walk = csv_column("reject.csv", "rtl_walk_cycles");
  const auto clip = csv_column("clip.csv", "rtl_clocks");
  const auto occlude = csv_column("occlude.csv", "rtl_clocks");
  auto evu = sim::make_rtl_evu(8, 512, 256);
  uint64_t stopped = 0, splits = 0, crossing = 0, pieces_tested = 0;
  for (const vis::EvuJob& j : jobs) {
    SCOPED_TRACE(scene + " tile " + std::to_string(j.tile));
    const sim::RtlTileClocks c = evu->run(j);
    ASSERT_EQ(c.tris.size(), j.triangles.size());

    // Reject: per triangle the formula; per tile the testbench's walk (2 clocks a pass beyond
    // the triangles' rows), and the latency 2 a pass + PairReject 3 + DepthTest 3.
    std::vector<uint32_t> zmax, zmin;
    for (const auto& t : j.triangles) zmax.push_back(std::max({t.v[0].z, t.v[1].z, t.v[2].z}));
    for (size_t k = 0; k < j.edges.size(); k += 2) zmin.push_back(std::min(j.edges[k].z, j.edges[k + 1].z));
    std::stable_sort(zmin.begin(), zmin.end());
    const std::vector<uint64_t> want_reject = reject_formula(zmax, zmin);
    uint64_t reject = 0;
    for (size_t t = 0; t < c.tris.size(); ++t) {
      EXPECT_EQ(c.tris[t].id, j.triangles[t].id);
      EXPECT_EQ(c.tris[t].reject, want_reject[t]) << "triangle " << t;
      reject += c.tris[t].reject;
      stopped += !zmin.empty() && zmin.back() > zmax[t];
    }
    const uint64_t passes = ((zmax.size() + rtl::kSeqTriCap - 1) / rtl::kSeqTriCap) *
                            std::max<uint64_t>(1, (zmin.size() + rtl::kSeqEdgeCap - 1) / rtl::kSeqEdgeCap);
    EXPECT_EQ(c.passes, passes);
    EXPECT_EQ(reject + 2 * c.passes, walk.at({scene, j.tile}));
    EXPECT_EQ(c.reject_latency, 2 * c.passes + 6);

    // Clip: each split of the public functions' replay, in order: 2n + 2 for a parent of n
    // edges that the line crosses, n + 2 otherwise; per tile the testbench's clocks.
    std::vector<uint32_t> want_splits;
    const rtl::ReplayedJob r = rtl::replay_job(j, [&](const geom::ConvexPolygon& piece, const vis::svgpu::Edge& e) {
      const bool crosses = rtl::split_status(vis::svgpu::split(piece, e)) == 0;
      want_splits.push_back(uint32_t(crosses ? 2 * piece.size() + 2 : piece.size() + 2));
      crossing += crosses;
    });
    std::vector<uint32_t> got_splits;
    int64_t n_pieces = 0, tests = 0;
    uint64_t clip_clocks = 0, occlude_clocks = 0;
    for (size_t t = 0; t < c.tris.size(); ++t) {
      EXPECT_EQ(int64_t(c.tris[t].splits.size()), r.triangles[t].clips) << "triangle " << t;
      EXPECT_EQ(c.tris[t].pieces.size(), r.triangles[t].pieces.size()) << "triangle " << t;
      got_splits.insert(got_splits.end(), c.tris[t].splits.begin(), c.tris[t].splits.end());
      for (uint32_t s : c.tris[t].splits) clip_clocks += s;
      // Occlude: 2 clocks for the interior point, then with k > 0 tests k + 1 more (one
      // occluder a clock; the last verdict the clock after its occluder's).
      for (uint32_t p : c.tris[t].pieces) {
        EXPECT_TRUE(p == 2 || p >= 4) << p;
        tests += p > 2 ? p - 3 : 0;
        pieces_tested += p > 2;
        occlude_clocks += p;
        ++n_pieces;
      }
    }
    EXPECT_EQ(got_splits, want_splits);
    splits += got_splits.size();
    EXPECT_EQ(clip_clocks, clip.at({scene, j.tile}));
    EXPECT_EQ(n_pieces, j.golden.pieces);
    EXPECT_EQ(tests, j.golden.occlusion_tests);
    EXPECT_EQ(occlude_clocks, occlude.at({scene, j.tile}));
  }
  // The sample exercises what the clocks depend on.
  EXPECT_GT(stopped, 0u);
  EXPECT_GT(splits, 0u);
  EXPECT_EQ(crossing, splits);  // a split the resolver performs always crosses (survives)
  EXPECT_GT(pieces_tested, 0u);
  std::printf("%s: %zu tile jobs, %llu triangles stopped by test 6, %llu splits, %llu pieces tested\n", scene.c_str(),
              jobs.size(), (unsigned long long)stopped, (unsigned long long)splits,
              (unsigned long long)pieces_tested);
}

// A job whose golden counters are not its RTL's outcome is refused.
TEST_P(RtlEvuTest, CorruptedJobThrows) {
  const std::vector<vis::EvuJob> jobs = sample(GetParam());
  // A job with work in every unit.
  const auto it = std::find_if(jobs.begin(), jobs.end(), [](const vis::EvuJob& j) {
    return j.golden.clip_polygons > 0 && j.golden.occlusion_tests > 0 && j.golden.visible_pieces > 0;
  });
  ASSERT_NE(it, jobs.end());
  auto evu = sim::make_rtl_evu(8, 512, 256);
  EXPECT_NO_THROW(evu->run(*it));
  int64_t vis::TileCounters::*const fields[] = {&vis::TileCounters::triangles,       &vis::TileCounters::edges,
                                                &vis::TileCounters::pair_tests,      &vis::TileCounters::candidate_pairs,
                                                &vis::TileCounters::clip_polygons,   &vis::TileCounters::pieces,
                                                &vis::TileCounters::visible_pieces,  &vis::TileCounters::occlusion_tests};
  for (auto f : fields) {
    vis::EvuJob bad = *it;
    bad.golden.*f += 1;
    EXPECT_THROW(evu->run(bad), std::runtime_error);
  }
  // Geometry that is not golden's tile: a triangle that test 6 stops, moved to the farthest
  // 24-bit depth, meets every edge (more pair tests than golden's).
  bool moved_one = false;
  for (const vis::EvuJob& j : jobs) {
    uint32_t zmin_max = 0;
    for (size_t k = 0; k < j.edges.size(); k += 2)
      zmin_max = std::max(zmin_max, std::min(j.edges[k].z, j.edges[k + 1].z));
    for (size_t t = 0; t < j.triangles.size() && !moved_one; ++t) {
      const auto& v = j.triangles[t].v;
      if (std::max({v[0].z, v[1].z, v[2].z}) >= zmin_max) continue;
      vis::EvuJob moved = j;
      for (auto& w : moved.triangles[t].v) w.z = (1u << 24) - 1;
      EXPECT_THROW(evu->run(moved), std::runtime_error);
      moved_one = true;
    }
    if (moved_one) break;
  }
  EXPECT_TRUE(moved_one);
  // The library runs on after a refusal.
  EXPECT_NO_THROW(evu->run(*it));
}

// make_evu_job (through EvuJobSource) on the scene's frame gives the dumped jobs.
TEST_P(RtlEvuTest, MakeEvuJobRebuildsTheDump) {
  const std::string scene = GetParam();
  const std::vector<vis::EvuJob> jobs = sample(scene);
  vis::EvuJobsHeader h;
  h = vis::read_evu_jobs(jobs_path(scene), [](const vis::EvuJob&) {});
  const trace::Trace tr = trace::read(std::string(TILEVIS_RTL_JOBS) + "/" + scene + "/" + scene + ".tvt");
  const vis::Setup s = vis::primitive_setup(tr.frames.at(h.frame), {});
  const geom::TileGrid grid = geom::TileGrid::make(s.width, s.height, h.tile_w, h.tile_h, s.subpixel_bits);
  vis::TileFrame f(s, grid);
  f.bin();
  vis::EvuJobSource source(f);
  for (const vis::EvuJob& want : jobs) {
    const vis::EvuJob got = source.job(want.tile);
    EXPECT_EQ(got.rect.x0, want.rect.x0);
    EXPECT_EQ(got.rect.y1, want.rect.y1);
    ASSERT_EQ(got.triangles.size(), want.triangles.size());
    for (size_t t = 0; t < got.triangles.size(); ++t) {
      EXPECT_EQ(got.triangles[t].id, want.triangles[t].id);
      EXPECT_EQ(got.triangles[t].opaque, want.triangles[t].opaque);
      for (int k = 0; k < 3; ++k) EXPECT_EQ(got.triangles[t].v[k], want.triangles[t].v[k]);
    }
    EXPECT_EQ(got.edges, want.edges);
    for (const auto& [name, field] : vis::TileCounters::kFields) {
      if (std::string(name) == "samples_covered" || std::string(name) == "fragments_generated") continue;  // not dumped
      EXPECT_EQ(got.golden.*field, want.golden.*field) << name << " tile " << want.tile;
    }
    // Without counters: the same lists, golden left zero but its sizes.
    const vis::EvuJob bare = vis::make_evu_job(f, want.tile);
    EXPECT_EQ(bare.edges, want.edges);
    EXPECT_EQ(bare.golden.pair_tests, 0);
    EXPECT_EQ(bare.golden.triangles, int64_t(want.triangles.size()));
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, RtlEvuTest, ::testing::ValuesIn(kScenes));

}  // namespace
