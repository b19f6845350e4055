// Clip against geom::split (svgpu::split), bit for bit: both children's lines and vertex
// representations in canonical order, for constrained-random polygons and clip lines
// (--random N --seed S) and for every split the analytic resolver performs in the dumped tile
// jobs (--jobs FILE), whose count must equal golden's clip_polygons and pieces.
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
#include "scoreboard.h"
#include "visibility/evu_jobs.h"

using namespace tilevis;
using namespace tilevis::rtl;

namespace {

constexpr int kMaxV = int(kClipMaxV);

struct Coverage {
  uint64_t splits = 0, status[3] = {}, vertex_on_line = 0, collinear = 0, max_vertices = 0, too_big = 0;
  uint64_t clocks = 0, edges_in = 0;
  std::string report() const {
    char b[512];
    std::snprintf(b, sizeof b,
                  "%llu splits (crosses %llu, inside %llu, outside %llu); a vertex on the line %llu, the line along "
                  "an edge %llu; most edges %llu; over MAXV (C++ only) %llu; %llu clocks for %llu parent edges",
                  (unsigned long long)splits, (unsigned long long)status[0], (unsigned long long)status[1],
                  (unsigned long long)status[2], (unsigned long long)vertex_on_line, (unsigned long long)collinear,
                  (unsigned long long)max_vertices, (unsigned long long)too_big, (unsigned long long)clocks,
                  (unsigned long long)edges_in);
    return b;
  }
};

class Bench {
 public:
  // One split through the RTL; compares with geom::split. Returns false on a mismatch.
  bool split(const geom::ConvexPolygon& poly, const vis::svgpu::Edge& e, Coverage& cov) {
    ++cov.splits;
    const geom::SplitResult want = vis::svgpu::split(poly, e);
    const int want_status = split_status(want);
    bool on = false, col = false;
    for (size_t i = 0; i < poly.size(); ++i) {
      const bool z0 = geom::side(e.line, poly.vertex(i)) == 0;
      const bool z1 = geom::side(e.line, poly.vertex((i + 1) % poly.size())) == 0;
      on |= z0;
      col |= z0 && z1;
    }
    cov.vertex_on_line += on;
    cov.collinear += col;
    cov.max_vertices = std::max<uint64_t>(cov.max_vertices, poly.size());
    if (poly.size() > size_t(kMaxV)) {
      ++cov.too_big;
      ++cov.status[want_status];
      return true;
    }
    const ClipDriver::Split got = m_clip.split(poly, e);
    const uint64_t clocks = got.clocks;
    cov.clocks += clocks;
    cov.edges_in += poly.size();
    ++cov.status[want_status];
    const bool ok = split_matches(got, want);
    if (!ok && m_mismatches++ < 10)
      std::printf("MISMATCH split of a %zu-gon: rtl status %d (%zu + %zu edges), model %d (%zu + %zu)\n", poly.size(),
                  got.status, got.inside.size(), got.outside.size(), want_status, want.inside.size(),
                  want.outside.size());
    return ok;
  }
  uint64_t mismatches() const { return m_mismatches; }

 private:
  ClipDriver m_clip;
  uint64_t m_mismatches = 0;
};

}  // namespace

namespace {
int bench(int argc, char** argv) {
  uint64_t random = 0, seed = 1, job_stride = 1;
  std::vector<std::string> jobs;
  std::string csv;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto val = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--random")
      random = std::stoull(val());
    else if (a == "--seed")
      seed = std::stoull(val());
    else if (a == "--jobs")
      jobs.push_back(val());
    else if (a == "--csv")
      csv = val();
    else if (a == "--job-stride")
      job_stride = std::max<uint64_t>(1, std::stoull(val()));
    else {
      std::fprintf(stderr, "usage: %s [--random N --seed S] [--jobs FILE [--job-stride K]] [--csv FILE]\n", argv[0]);
      return 2;
    }
  }
  uint64_t bad = 0;
  if (random) {
    Bench b;
    Coverage cov;
    PairSource src(seed);
    std::mt19937_64 rng(seed ^ 0x9e3779b97f4a7c15ull);
    for (uint64_t k = 0; k < random; ++k) {
      PairVector v = src.next();
      // Grow the piece now and then by more splits (up to MAXV edges), keeping a random side.
      const int extra = int(rng() % 4);
      for (int s = 0; s < extra; ++s) {
        const PairVector w = src.next();
        geom::SplitResult sr = geom::split(v.poly, w.e.line);
        const geom::ConvexPolygon& keep = (rng() & 1) ? sr.inside : sr.outside;
        if (!keep.empty() && keep.size() <= size_t(kMaxV)) v.poly = keep;
      }
      // Clip lines through the piece's own vertices where they are snapped points (ties).
      if (rng() % 4 == 0) {
        std::vector<geom::Point> snapped;
        for (size_t i = 0; i < v.poly.size(); ++i)
          if (v.poly.vertex(i).w == 1) snapped.push_back({int32_t(v.poly.vertex(i).x), int32_t(v.poly.vertex(i).y)});
        if (snapped.size() >= 2) {
          const auto p = snapped[rng() % snapped.size()], q = snapped[rng() % snapped.size()];
          if (!(p == q)) v.e = vis::svgpu::Edge::from({p.x, p.y, 0}, {q.x, q.y, 0});
        }
      }
      bad += !b.split(v.poly, v.e, cov);
    }
    std::printf("Clip random (seed %llu): %s; mismatches %llu\n", (unsigned long long)seed, cov.report().c_str(),
                (unsigned long long)b.mismatches());
  }
  // Per tile job: the RTL's clocks at one lane beside the SystemC EVU clip stage's cycles for
  // the same work at one lane (EvuClip::cost: per triangle ceil(candidates + clips) x ii, or 1
  // without any, plus the latency once; model defaults ii 4, latency 12).
  std::ofstream out;
  if (!csv.empty()) {
    out.open(csv);
    out << "source,tile,triangles,candidates,clips,parent_edges,rtl_clocks,model_cycles\n";
  }
  for (const std::string& f : jobs) {
    Bench b;
    Coverage cov;
    uint64_t seen = 0, checked = 0, counter_mismatch = 0;
    vis::read_evu_jobs(f, [&](const vis::EvuJob& j) {
      if (seen++ % job_stride != 0) return;
      ++checked;
      const uint64_t clocks0 = cov.clocks, edges0 = cov.edges_in;
      const ReplayedJob r = replay_job(
          j, [&](const geom::ConvexPolygon& piece, const vis::svgpu::Edge& e) { bad += !b.split(piece, e, cov); });
      uint64_t model = 12, cand = 0;
      for (const auto& t : r.triangles) {
        const uint64_t ops = t.candidates.size() + uint64_t(t.clips);
        model += ops ? ops * 4 : 1;
        cand += t.candidates.size();
      }
      if (out.is_open())
        out << f << ',' << j.tile << ',' << r.triangles.size() << ',' << cand << ',' << r.clips << ','
            << cov.edges_in - edges0 << ',' << cov.clocks - clocks0 << ',' << model << '\n';
      const int64_t clips = r.clips;
      int64_t pieces = 0;
      for (const auto& t : r.triangles) pieces += int64_t(t.pieces.size());
      if (clips != j.golden.clip_polygons || pieces != j.golden.pieces) {
        if (counter_mismatch < 10)
          std::printf("COUNTER MISMATCH tile %u: clips %lld/%lld pieces %lld/%lld (tb/golden)\n", j.tile,
                      (long long)clips, (long long)j.golden.clip_polygons, (long long)pieces,
                      (long long)j.golden.pieces);
        ++counter_mismatch;
      }
    });
    std::printf("Clip jobs %s: %llu of %llu tile jobs; %s; mismatches %llu, tile counter mismatches %llu\n", f.c_str(),
                (unsigned long long)checked, (unsigned long long)seen, cov.report().c_str(),
                (unsigned long long)b.mismatches(), (unsigned long long)counter_mismatch);
    bad += counter_mismatch;
  }
  return bad ? 1 : 0;
}
}  // namespace

int main(int argc, char** argv) { return tilevis::rtl::run_bench(bench, argc, argv); }
