// The host time of fidelity rtl's cycle reference: every job of each dump (tilevis golden
// --dump-evu-jobs) run through make_rtl_evu()'s units, reading excluded. Prints, per file, the
// jobs, the host seconds, seconds per job and the clocks the units returned.
//   ninja -C build-rtl bench_rtl_evu && build-rtl/rtl_ref/bench_rtl_evu build-rtl/rtl_ref/jobs/bunny/evu_jobs.txt
#include <chrono>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "units/early_visibility_unit/rtl_evu.h"

using namespace tilevis;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s EVU_JOBS.txt...\n", argv[0]);
    return 2;
  }
  try {
    for (int i = 1; i < argc; ++i) {
      std::vector<vis::EvuJob> jobs;
      vis::read_evu_jobs(argv[i], [&](const vis::EvuJob& j) { jobs.push_back(j); });
      const auto t0 = std::chrono::steady_clock::now();
      auto evu = sim::make_rtl_evu(8, 512, 256);
      uint64_t reject = 0, splits = 0, split_clocks = 0, pieces = 0, piece_clocks = 0, latency = 0;
      for (const auto& j : jobs) {
        const sim::RtlTileClocks c = evu->run(j);
        latency += c.reject_latency;
        for (const auto& t : c.tris) {
          reject += t.reject;
          splits += t.splits.size();
          for (uint32_t s : t.splits) split_clocks += s;
          pieces += t.pieces.size();
          for (uint32_t p : t.pieces) piece_clocks += p;
        }
      }
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::printf(
          "%s: %zu tile jobs in %.3f s host (%.3f ms a job); clocks: reject %llu + latency %llu, %llu splits %llu, "
          "%llu pieces %llu\n",
          argv[i], jobs.size(), s, jobs.empty() ? 0.0 : 1e3 * s / double(jobs.size()), (unsigned long long)reject,
          (unsigned long long)latency, (unsigned long long)splits, (unsigned long long)split_clocks,
          (unsigned long long)pieces, (unsigned long long)piece_clocks);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
