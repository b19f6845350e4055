// Occlude against svgpu::occludes at geom::interior_point, bit for bit: the interior point's
// representation and every occluder's verdict, for constrained-random pieces and occluders
// (--random N --seed S; N pieces, a few occluders each: ties on edges, shared vertices,
// coplanar and equal-depth pairs) and for every occlusion test the analytic resolver makes in
// the dumped tile jobs (--jobs FILE), whose counts must equal golden's occlusion_tests and
// visible_pieces.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <fstream>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "drivers.h"
#include "scoreboard.h"
#include "visibility/evu_jobs.h"

using namespace tilevis;
using namespace tilevis::rtl;

namespace {

struct Coverage {
  uint64_t pieces = 0, tests = 0, occluded = 0, depth_ties = 0, on_edge = 0, q_mismatch = 0, clocks = 0;
  std::string report() const {
    char b[400];
    std::snprintf(b, sizeof b,
                  "%llu pieces, %llu occluder tests (%llu occluded); equal depth at q %llu, q on an occluder's edge "
                  "%llu; %llu clocks",
                  (unsigned long long)pieces, (unsigned long long)tests, (unsigned long long)occluded,
                  (unsigned long long)depth_ties, (unsigned long long)on_edge, (unsigned long long)clocks);
    return b;
  }
};

using Occluder = OccludeDriver::Occluder;

class Bench {
 public:
  // The piece's occlusion tests against `occ` in order, up to and including the first that
  // occludes (as the resolver scans). Returns whether the piece is occluded.
  bool run(const geom::ConvexPolygon& piece, const vis::svgpu::Triangle& t, uint32_t t_id,
           const std::vector<Occluder>& occ, Coverage& cov) {
    ++cov.pieces;
    const OccludeDriver::Result r = m_occlude.run(piece, t, t_id, occ);
    if (!r.q_matches) {
      if (m_mismatches++ < 10) std::printf("MISMATCH interior point of a %zu-gon\n", piece.size());
      ++cov.q_mismatch;
    }
    if (r.verdict_mismatches) {
      if (m_mismatches < 10) std::printf("MISMATCH occlusion verdicts of a piece: %u\n", r.verdict_mismatches);
      m_mismatches += r.verdict_mismatches;
    }
    // Coverage of the tests streamed.
    const geom::RationalPoint q = geom::interior_point(piece);
    for (uint32_t k = 0; k < r.tests; ++k) {
      const auto& u = *occ[k].u;
      ++cov.tests;
      cov.occluded += vis::svgpu::occludes(u, occ[k].id, t, t_id, q);
      if (u.plane.valid() && geom::depth_order(u.plane, t.plane, q) == 0) ++cov.depth_ties;
      for (const auto& l : u.edges.edge) cov.on_edge += u.edges.valid && geom::side(l, q) == 0;
    }
    cov.clocks += r.clocks;
    return r.occluded;
  }
  uint64_t mismatches() const { return m_mismatches; }

 private:
  OccludeDriver m_occlude;
  uint64_t m_mismatches = 0;
};

}  // namespace

namespace {
int bench(int argc, char** argv) {
  const TbOptions opt = parse_tb_options(argc, argv, kTbCsv);
  const uint64_t random = opt.random, seed = opt.seed, job_stride = opt.job_stride;
  const std::vector<std::string>& jobs = opt.jobs;
  const std::string& csv = opt.csv;
  uint64_t bad = 0;
  if (random) {
    Bench b;
    Coverage cov;
    PairSource src(seed);
    std::mt19937_64 rng(seed * 7919 + 1);
    for (uint64_t k = 0; k < random; ++k) {
      const PairVector v = src.next();
      // Occluders: random triangles, t itself under other ids (coplanar, equal depth
      // everywhere: the id rule decides), triangles through a vertex or along an edge of t.
      std::vector<vis::svgpu::Triangle> us;
      std::vector<uint32_t> ids;
      const uint32_t t_id = uint32_t(rng() % 1000) + 1;
      const int n = 1 + int(rng() % 4);
      for (int i = 0; i < n; ++i) {
        switch (rng() % 4) {
          case 0:
            us.push_back(v.t);
            ids.push_back(uint32_t(rng() % 2001));
            break;
          case 1: {
            PairVector w = src.next();
            geom::Vertex a = v.t.tri.v[rng() % 3], b = v.t.tri.v[rng() % 3];
            us.push_back(vis::svgpu::Triangle::from(a, b, w.t.tri.v[0]));
            ids.push_back(uint32_t(rng()));
            break;
          }
          default:
            us.push_back(src.next().t);
            ids.push_back(uint32_t(rng()));
            break;
        }
      }
      std::vector<Occluder> occ;
      for (size_t i = 0; i < us.size(); ++i) occ.push_back({&us[i], ids[i]});
      b.run(v.poly, v.t, t_id, occ, cov);
    }
    std::printf("Occlude random (seed %llu): %s; mismatches %llu\n", (unsigned long long)seed, cov.report().c_str(),
                (unsigned long long)b.mismatches());
    bad += b.mismatches();
  }
  // Per tile job: the RTL's clocks at one lane beside the occlude stage's cost before
  // calibration (838c783: per triangle pieces + occlusion tests at ii 1, or 1 without any, plus
  // a latency of 10), for reports/rtl's before-calibration table; the calibrated cost is
  // compared with the RTL on whole frames by rtl_ref/tools/calibrated_error.py.
  std::ofstream out;
  if (!csv.empty()) {
    out.open(csv);
    out << "source,tile,triangles,pieces,occlusion_tests,rtl_clocks,model_cycles\n";
  }
  for (const std::string& f : jobs) {
    Bench b;
    Coverage cov;
    uint64_t seen = 0, checked = 0, counter_mismatch = 0;
    vis::read_evu_jobs(f, [&](const vis::EvuJob& j) {
      if (seen++ % job_stride != 0) return;
      ++checked;
      const ReplayedJob r = replay_job(j);
      const std::vector<uint32_t> occ_ix = occluder_order(r);
      int64_t tests = 0, visible = 0, pieces = 0;
      const uint64_t clocks0 = cov.clocks;
      uint64_t model = 10;
      for (const auto& rt : r.triangles) {
        const int64_t tests0 = tests;
        int64_t tri_pieces = 0;
        for (const auto& piece : rt.pieces) {
          if (piece.empty()) continue;
          std::vector<Occluder> occ;
          screened_occluders(r, occ_ix, rt, geom::interior_point(piece), occ);
          const uint64_t before = cov.tests;
          const bool hidden = b.run(piece, rt.t, rt.id, occ, cov);
          tests += int64_t(cov.tests - before);
          visible += !hidden;
          ++tri_pieces;
        }
        pieces += tri_pieces;
        const uint64_t ops = uint64_t(tri_pieces + tests - tests0);
        model += ops ? ops : 1;
      }
      if (out.is_open())
        out << f << ',' << j.tile << ',' << r.triangles.size() << ',' << pieces << ',' << tests << ','
            << cov.clocks - clocks0 << ',' << model << '\n';
      if (tests != j.golden.occlusion_tests || visible != j.golden.visible_pieces) {
        if (counter_mismatch < 10)
          std::printf("COUNTER MISMATCH tile %u: occlusion tests %lld/%lld visible %lld/%lld (tb/golden)\n", j.tile,
                      (long long)tests, (long long)j.golden.occlusion_tests, (long long)visible,
                      (long long)j.golden.visible_pieces);
        ++counter_mismatch;
      }
    });
    std::printf("Occlude jobs %s: %llu of %llu tile jobs; %s; mismatches %llu, tile counter mismatches %llu\n",
                f.c_str(), (unsigned long long)checked, (unsigned long long)seen, cov.report().c_str(),
                (unsigned long long)b.mismatches(), (unsigned long long)counter_mismatch);
    bad += b.mismatches() + counter_mismatch;
  }
  return bad ? 1 : 0;
}
}  // namespace

int main(int argc, char** argv) { return tilevis::rtl::run_bench(bench, argc, argv); }
