// TileSequencer against the analytic resolver's pair order: for every tile job (--jobs FILE)
// and for constrained-random lists (--random N --seed S), the issued (triangle, edge) pairs
// must be exactly the resolver's, triangle by triangle, and the pass must end. Measures the
// clocks of each job (list loads + walks, passes by the overflow rule) beside the SystemC
// EVU reject stage's cost for the same job (--csv FILE: one row per job).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "drivers.h"
#include "visibility/evu_jobs.h"
#include "visibility/svgpu.h"

using namespace tilevis;
using namespace tilevis::rtl;

namespace {

constexpr uint32_t kLanes = kSeqLanes, kTriCap = kSeqTriCap, kEdgeCap = kSeqEdgeCap;
// The reject stage's cost before calibration (838c783), for reports/rtl's before-calibration
// table: reject {lanes 8, ii 1, latency 6}, pass_overhead_cycles 32. The calibrated cost is
// compared with the RTL on whole frames by rtl_ref/tools/calibrated_error.py.
constexpr uint64_t kModelRejectLatency = 6, kModelPassOverhead = 32;

// A job as the sequencer sees it: triangles' z_max, edges' z_min sorted ascending (stable).
struct SeqJob {
  uint32_t tile = 0;
  std::vector<uint32_t> tri_zmax, edge_zmin;
};

struct Result {
  uint64_t jobs = 0, passes = 0, pairs = 0, mismatches = 0, cycles = 0, load_cycles = 0, stopped = 0;
  uint64_t model_cycles = 0;
};

// The resolver's pairs (analytic_resolver.cpp: edges by z_min, stable; per triangle until the
// first edge with z_min > z_max) and each triangle's pair count.
std::vector<std::pair<uint32_t, uint32_t>> model_pairs(const SeqJob& j, std::vector<uint64_t>& per_tri) {
  std::vector<std::pair<uint32_t, uint32_t>> p;
  per_tri.assign(j.tri_zmax.size(), 0);
  for (uint32_t t = 0; t < j.tri_zmax.size(); ++t)
    for (uint32_t e = 0; e < j.edge_zmin.size(); ++e) {
      if (j.edge_zmin[e] > j.tri_zmax[t]) break;
      p.emplace_back(t, e);
      ++per_tri[t];
    }
  return p;
}

// The SystemC EVU reject stage's cycles for the job at `lanes` lanes, ii 1 (EvuReject::cost).
uint64_t model_reject_cycles(const std::vector<uint64_t>& per_tri, uint32_t nt, uint32_t ne, uint64_t lanes) {
  uint64_t c = 0;
  for (uint64_t p : per_tri) c += p ? (p + lanes - 1) / lanes : 1;
  const uint64_t tp = (nt + 511) / 512, ep = (ne + 255) / 256;  // evu.*_list_entries defaults
  const uint64_t passes = std::max<uint64_t>(1, std::max(tp, ep));
  return c + (passes - 1) * kModelPassOverhead + kModelRejectLatency;
}

}  // namespace

namespace {
int bench(int argc, char** argv) {
  const TbOptions opt = parse_tb_options(argc, argv, kTbCsv);
  const uint64_t random = opt.random, seed = opt.seed, job_stride = opt.job_stride;
  const std::vector<std::string>& jobs = opt.jobs;
  const std::string& csv = opt.csv;
  std::ofstream out;
  if (!csv.empty()) {
    out.open(csv);
    out << "source,tile,triangles,edges,pair_tests,passes,rtl_load_cycles,rtl_walk_cycles,rtl_cycles,model_reject_"
           "cycles\n";
  }
  uint64_t bad = 0;
  auto check = [&](TileSequencerDriver& b, const SeqJob& j, Result& r, const std::string& source) {
    std::vector<uint64_t> per_tri;
    auto want = model_pairs(j, per_tri);
    TileSequencerDriver::Result run = b.run(j.tri_zmax, j.edge_zmin);
    std::vector<std::pair<uint32_t, uint32_t>>& got = run.issued;
    const uint64_t passes = run.passes, load = run.load_clocks, clocks = run.load_clocks + run.walk_clocks;
    r.stopped += run.stopped;
    ++r.jobs;
    r.passes += passes;
    r.pairs += want.size();
    r.cycles += clocks;
    r.load_cycles += load;
    const uint64_t model =
        model_reject_cycles(per_tri, uint32_t(j.tri_zmax.size()), uint32_t(j.edge_zmin.size()), kLanes);
    r.model_cycles += model;
    // One pass issues in the resolver's order; passes interleave triangles by edge chunk.
    if (passes > 1) {
      std::sort(got.begin(), got.end());
      std::sort(want.begin(), want.end());
    }
    if (got != want) {
      if (r.mismatches < 10)
        std::printf("MISMATCH %s tile %u: %zu pairs issued, model %zu\n", source.c_str(), j.tile, got.size(),
                    want.size());
      ++r.mismatches;
    }
    if (out.is_open())
      out << source << ',' << j.tile << ',' << j.tri_zmax.size() << ',' << j.edge_zmin.size() << ',' << want.size()
          << ',' << passes << ',' << load << ',' << clocks - load << ',' << clocks << ',' << model << '\n';
  };
  auto print = [&](const Result& r, const std::string& what) {
    std::printf(
        "TileSequencer x%u (lists %u/%u) %s: %llu jobs, %llu passes, %llu pairs, %llu triangles stopped by "
        "test 6; %llu clocks (%llu loading); model reject stage %llu cycles; mismatches %llu\n",
        kLanes, kTriCap, kEdgeCap, what.c_str(), (unsigned long long)r.jobs, (unsigned long long)r.passes,
        (unsigned long long)r.pairs, (unsigned long long)r.stopped, (unsigned long long)r.cycles,
        (unsigned long long)r.load_cycles, (unsigned long long)r.model_cycles, (unsigned long long)r.mismatches);
    bad += r.mismatches;
  };
  if (random) {
    TileSequencerDriver b;
    Result r;
    std::mt19937_64 rng(seed);
    for (uint64_t k = 0; k < random; ++k) {
      SeqJob j;
      j.tile = uint32_t(k);
      // Small lists (rows of lanes, partial rows), and every 256th job past both capacities
      // (passes); depths with many equal values.
      const uint32_t nt = 1 + uint32_t(rng() % (k % 256 == 0 ? 2 * kTriCap + 3 : 24));
      const uint32_t ne = uint32_t(rng() % (k % 256 == 0 ? 2 * kEdgeCap + 3 : 3 * kLanes + 2));
      const uint32_t range = 1 + uint32_t(rng() % 64);
      for (uint32_t t = 0; t < nt; ++t) j.tri_zmax.push_back(uint32_t(rng() % range));
      for (uint32_t e = 0; e < ne; ++e) j.edge_zmin.push_back(uint32_t(rng() % range));
      std::sort(j.edge_zmin.begin(), j.edge_zmin.end());
      check(b, j, r, "random");
    }
    print(r, "random (seed " + std::to_string(seed) + ")");
  }
  for (const std::string& f : jobs) {
    TileSequencerDriver b;
    Result r;
    uint64_t seen = 0, golden_mismatch = 0;
    vis::read_evu_jobs(f, [&](const vis::EvuJob& job) {
      if (seen++ % job_stride != 0) return;
      SeqJob j;
      j.tile = job.tile;
      for (const auto& t : job.triangles) j.tri_zmax.push_back(std::max({t.v[0].z, t.v[1].z, t.v[2].z}));
      for (size_t k = 0; k < job.edges.size(); k += 2)
        j.edge_zmin.push_back(std::min(job.edges[k].z, job.edges[k + 1].z));
      std::stable_sort(j.edge_zmin.begin(), j.edge_zmin.end());
      std::vector<uint64_t> per_tri;
      if (int64_t(model_pairs(j, per_tri).size()) != job.golden.pair_tests) ++golden_mismatch;
      check(b, j, r, f);
    });
    print(r, f);
    std::printf("  tile jobs whose pair count differs from golden's pair_tests: %llu\n",
                (unsigned long long)golden_mismatch);
    bad += golden_mismatch;
  }
  return bad ? 1 : 0;
}
}  // namespace

int main(int argc, char** argv) { return tilevis::rtl::run_bench(bench, argc, argv); }
