// Clip against geom::split (svgpu::split), bit for bit: both children's lines and vertex
// representations in canonical order, for constrained-random polygons and clip lines
// (--random N --seed S) and for every split the analytic resolver performs in the dumped tile
// jobs (--jobs FILE), whose count must equal golden's clip_polygons and pieces.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "drivers.h"
#include "scoreboard.h"
#include "visibility/evu_jobs.h"

using namespace tilevis;
using namespace tilevis::rtl;

namespace {

// Parents by size: 3-7 edges (a triangle in its tile), 8-16, 17-32, 33 and more.
int size_bucket(size_t n) { return n <= 7 ? 0 : n <= 16 ? 1 : n <= 32 ? 2 : 3; }

struct Coverage {
  uint64_t splits = 0, status[3] = {}, vertex_on_line = 0, collinear = 0, max_vertices = 0;
  uint64_t crosses_at_vertex = 0, crosses_at_vertex0 = 0;  // the line crosses, through a vertex (vertex 0)
  uint64_t by_size[4] = {}, crosses_by_size[4] = {};
  uint64_t clocks = 0, edges_in = 0;
  std::string report() const {
    char b[768];
    std::snprintf(b, sizeof b,
                  "%llu splits (crosses %llu, inside %llu, outside %llu); a vertex on the line %llu (crossing %llu, "
                  "at vertex 0 %llu), the line along an edge %llu; parents of 3-7 edges %llu (crossed %llu), 8-16 %llu "
                  "(%llu), 17-32 %llu (%llu), "
                  "33+ %llu (%llu); largest parent %llu edges; %llu clocks for %llu parent edges",
                  (unsigned long long)splits, (unsigned long long)status[0], (unsigned long long)status[1],
                  (unsigned long long)status[2], (unsigned long long)vertex_on_line,
                  (unsigned long long)crosses_at_vertex, (unsigned long long)crosses_at_vertex0,
                  (unsigned long long)collinear, (unsigned long long)by_size[0], (unsigned long long)crosses_by_size[0],
                  (unsigned long long)by_size[1], (unsigned long long)crosses_by_size[1],
                  (unsigned long long)by_size[2], (unsigned long long)crosses_by_size[2],
                  (unsigned long long)by_size[3], (unsigned long long)crosses_by_size[3],
                  (unsigned long long)max_vertices, (unsigned long long)clocks, (unsigned long long)edges_in);
    return b;
  }
};

// A piece grown by cutting off one corner at a time (the kept child has one edge more), up to
// `target` edges or `tries` attempts: the line through two lattice points near vertex i on its
// two edges (rounding may cut more or miss; only a child larger than the piece is kept).
geom::ConvexPolygon grow(geom::ConvexPolygon poly, size_t target, int tries, std::mt19937_64& rng) {
  auto at = [](const geom::ImplicitPoint& p) {
    return std::pair{double(p.x) / double(p.w), double(p.y) / double(p.w)};
  };
  for (int k = 0; k < tries && poly.size() < target; ++k) {
    const size_t n = poly.size(), i = rng() % n;
    const auto v = at(poly.vertex(i)), u = at(poly.vertex((i + n - 1) % n)), w = at(poly.vertex((i + 1) % n));
    const double s = 0.05 + 0.45 * double(rng() % 1000) / 1000.0, t = 0.05 + 0.45 * double(rng() % 1000) / 1000.0;
    const geom::Point p{int32_t(std::lround(v.first + s * (u.first - v.first))),
                        int32_t(std::lround(v.second + s * (u.second - v.second)))};
    const geom::Point q{int32_t(std::lround(v.first + t * (w.first - v.first))),
                        int32_t(std::lround(v.second + t * (w.second - v.second)))};
    if (p == q) continue;
    const geom::SplitResult sr = geom::split(poly, geom::Line::through(p, q));
    const geom::ConvexPolygon& big = sr.inside.size() >= sr.outside.size() ? sr.inside : sr.outside;
    if (big.size() > poly.size()) poly = big;
  }
  return poly;
}

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
    cov.crosses_at_vertex += on && want_status == 0;
    cov.crosses_at_vertex0 += want_status == 0 && geom::side(e.line, poly.vertex(0)) == 0;
    cov.collinear += col;
    cov.max_vertices = std::max<uint64_t>(cov.max_vertices, poly.size());
    ++cov.by_size[size_bucket(poly.size())];
    cov.crosses_by_size[size_bucket(poly.size())] += want_status == 0;
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
  const TbOptions opt = parse_tb_options(argc, argv, kTbCsv);
  const uint64_t random = opt.random, seed = opt.seed, job_stride = opt.job_stride;
  const std::vector<std::string>& jobs = opt.jobs;
  const std::string& csv = opt.csv;
  uint64_t bad = 0;
  if (random) {
    Bench b;
    Coverage cov;
    PairSource src(seed);
    std::mt19937_64 rng(seed ^ 0x9e3779b97f4a7c15ull);
    for (uint64_t k = 0; k < random; ++k) {
      PairVector v = src.next();
      // Grow the piece now and then by more splits, keeping a random side.
      const int extra = int(rng() % 4);
      for (int s = 0; s < extra; ++s) {
        const PairVector w = src.next();
        geom::SplitResult sr = geom::split(v.poly, w.e.line);
        const geom::ConvexPolygon& keep = (rng() & 1) ? sr.inside : sr.outside;
        if (!keep.empty()) v.poly = keep;
      }
      // One vector in four: a piece far larger than a triangle in its tile (up to 64 edges; the
      // slivers scene's 1080p tile jobs split parents of up to 54), cut by a line through two
      // lattice points of its bounding box half the time.
      if (rng() % 4 == 0) {
        const size_t target = 8 + rng() % 57;
        v.poly = grow(v.poly, target, int(3 * target), rng);
        if (rng() & 1) {
          double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30;
          for (size_t i = 0; i < v.poly.size(); ++i) {
            const double x = double(v.poly.vertex(i).x) / double(v.poly.vertex(i).w);
            const double y = double(v.poly.vertex(i).y) / double(v.poly.vertex(i).w);
            x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
          }
          auto in = [&](double a, double b) {
            return int32_t(std::lround(a + (b - a) * double(rng() % 1001) / 1000.0));
          };
          const geom::Point p{in(x0, x1), in(y0, y1)}, q{in(x0, x1), in(y0, y1)};
          if (!(p == q)) v.e = vis::svgpu::Edge::from({p.x, p.y, 0}, {q.x, q.y, 0});
        }
      }
      // Clip lines through the piece's own vertices where they are lattice points (ties): through
      // two of them, or half the time through one and the lattice point nearest the vertices'
      // mean, which crosses the piece through that vertex (vertex 0 is the lane's held one).
      if (rng() % 4 == 0) {
        std::vector<geom::Point> lattice;
        double mx = 0, my = 0;
        for (size_t i = 0; i < v.poly.size(); ++i) {
          const geom::ImplicitPoint& p = v.poly.vertex(i);
          if (p.x % p.w == 0 && p.y % p.w == 0) lattice.push_back({int32_t(p.x / p.w), int32_t(p.y / p.w)});
          mx += double(p.x) / double(p.w) / double(v.poly.size());
          my += double(p.y) / double(v.poly.size()) / double(p.w);
        }
        if (!lattice.empty()) {
          const geom::Point p = lattice[(rng() & 1) ? 0 : rng() % lattice.size()];
          const geom::Point q = (rng() & 1) ? geom::Point{int32_t(std::lround(mx)), int32_t(std::lround(my))}
                                            : lattice[rng() % lattice.size()];
          if (!(p == q)) v.e = vis::svgpu::Edge::from({p.x, p.y, 0}, {q.x, q.y, 0});
        }
      }
      bad += !b.split(v.poly, v.e, cov);
    }
    std::printf("Clip random (seed %llu): %s; mismatches %llu\n", (unsigned long long)seed, cov.report().c_str(),
                (unsigned long long)b.mismatches());
  }
  // Per tile job: the RTL's clocks at one lane beside the clip stage's cost before calibration
  // (838c783: per triangle ceil(candidates + clips) x ii 4, or 1 without any, plus a latency
  // of 12), for reports/rtl's before-calibration table; the calibrated cost is compared with
  // the RTL on whole frames by rtl_ref/tools/calibrated_error.py.
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
