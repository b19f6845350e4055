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
#include <string>
#include <vector>

#include "VOcclude.h"
#include "port_bits.h"
#include "scoreboard.h"
#include "verilated.h"
#include "visibility/evu_jobs.h"

using namespace tilevis;
using namespace tilevis::rtl;

namespace {

constexpr int kPX = 74, kPW = 51, kQX = 174, kQW = 151, kLA = 26, kLC = 49, kAW = 59, kGW = 84, kIDW = 32;

template <class T, int L>
bool equal_wide(const T& port, int width, const geom::WideInt<L>& v) {
  for (int i = 0; i < width; ++i)
    if (get_bit(port, i) != bool((v.limb[i / 64] >> (i % 64)) & 1)) return false;
  for (int i = width; i < 64 * L; ++i)  // the rest of v is the sign
    if (bool((v.limb[i / 64] >> (i % 64)) & 1) != get_bit(port, width - 1)) return false;
  return true;
}

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

struct Occluder {
  const vis::svgpu::Triangle* u;
  uint32_t id;
};

class Bench {
 public:
  Bench() : m_ctx(std::make_unique<VerilatedContext>()), m_dut(std::make_unique<VOcclude>(m_ctx.get())) {
    m_dut->rst = 1;
    tick();
    tick();
    m_dut->rst = 0;
  }
  // The piece's occlusion tests against `occ` in order, up to and including the first that
  // occludes (as the resolver scans). Returns whether the piece is occluded.
  bool run(const geom::ConvexPolygon& piece, const vis::svgpu::Triangle& t, uint32_t t_id,
           const std::vector<Occluder>& occ, Coverage& cov) {
    ++cov.pieces;
    const geom::RationalPoint q = geom::interior_point(piece);
    m_dut->p_valid = 1;
    for (int i = 0; i < 3; ++i) {
      put_field(m_dut->p_vx, i * kPX, kPX, piece.vertex(size_t(i)).x);
      put_field(m_dut->p_vy, i * kPX, kPX, piece.vertex(size_t(i)).y);
      put_field(m_dut->p_vw, i * kPW, kPW, piece.vertex(size_t(i)).w);
    }
    put_field(m_dut->t_alpha, 0, kAW, t.plane.alpha);
    put_field(m_dut->t_beta, 0, kAW, t.plane.beta);
    put_field(m_dut->t_gamma, 0, kGW, t.plane.gamma);
    put_field(m_dut->t_area, 0, kPW, t.plane.area);
    m_dut->t_id = t_id;
    tick();
    m_dut->p_valid = 0;
    tick();
    uint64_t clocks = 2;
    if (!m_dut->q_ready) std::printf("Occlude: q not ready 2 clocks after the piece\n"), std::exit(1);
    if (!equal_wide(m_dut->q_x, kQX, q.x) || !equal_wide(m_dut->q_y, kQX, q.y) || !equal_wide(m_dut->q_w, kQW, q.w)) {
      if (m_mismatches++ < 10) std::printf("MISMATCH interior point of a %zu-gon\n", piece.size());
      ++cov.q_mismatch;
    }
    // Stream occluders until the model's first hit; the verdicts return 2 clocks later.
    std::deque<bool> expect;
    bool hit = false;
    size_t k = 0;
    while (k < occ.size() || !expect.empty()) {
      const bool issue = k < occ.size() && !hit;
      m_dut->o_valid = issue;
      if (issue) {
        const Occluder& o = occ[k++];
        const auto& u = *o.u;
        for (int i = 0; i < 3; ++i) {
          put_field(m_dut->u_la, i * kLA, kLA, u.edges.edge[size_t(i)].a);
          put_field(m_dut->u_lb, i * kLA, kLA, u.edges.edge[size_t(i)].b);
          put_field(m_dut->u_lc, i * kLC, kLC, u.edges.edge[size_t(i)].c);
        }
        m_dut->u_edges_valid = u.edges.valid;
        put_field(m_dut->u_alpha, 0, kAW, u.plane.alpha);
        put_field(m_dut->u_beta, 0, kAW, u.plane.beta);
        put_field(m_dut->u_gamma, 0, kGW, u.plane.gamma);
        put_field(m_dut->u_area, 0, kPW, u.plane.area);
        m_dut->u_id = o.id;
        const bool want = vis::svgpu::occludes(u, o.id, t, t_id, q);
        ++cov.tests;
        cov.occluded += want;
        if (u.plane.valid() && geom::depth_order(u.plane, t.plane, q) == 0) ++cov.depth_ties;
        for (const auto& l : u.edges.edge) cov.on_edge += u.edges.valid && geom::side(l, q) == 0;
        expect.push_back(want);
        hit = want;
      } else if (k < occ.size() && hit) {
        k = occ.size();
      }
      tick();
      ++clocks;
      if (m_dut->r_valid) {
        const bool got = m_dut->r_occluded;
        if (expect.empty()) std::printf("Occlude: a verdict nobody asked for\n"), std::exit(1);
        if (got != expect.front() && m_mismatches++ < 10)
          std::printf("MISMATCH occlusion verdict: rtl %d, model %d\n", got, int(expect.front()));
        expect.pop_front();
      } else if (!issue && !expect.empty() && clocks > 4 + 2 * occ.size() + 4) {
        std::printf("Occlude: verdicts missing\n");
        std::exit(1);
      }
    }
    m_dut->o_valid = 0;
    cov.clocks += clocks;
    return hit;
  }
  uint64_t mismatches() const { return m_mismatches; }

 private:
  void tick() {
    m_dut->clk = 1;
    m_dut->eval();
    m_dut->clk = 0;
    m_dut->eval();
  }
  std::unique_ptr<VerilatedContext> m_ctx;
  std::unique_ptr<VOcclude> m_dut;
  uint64_t m_mismatches = 0;
};

}  // namespace

int main(int argc, char** argv) {
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
  Verilated::commandArgs(argc, argv);
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
  // Per tile job: the RTL's clocks at one lane beside the SystemC EVU occlude stage's cycles
  // for the same work at one lane (EvuOcclude::cost: per triangle pieces + occlusion tests at
  // ii 1, or 1 without any, plus the latency 10 once).
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
      // Occluders: the tile's opaque triangles, nearest z_min first (stable), as TileFrame::occluders.
      std::vector<uint32_t> occ_ix;
      for (uint32_t i = 0; i < r.triangles.size(); ++i)
        if (r.triangles[i].opaque) occ_ix.push_back(i);
      std::stable_sort(occ_ix.begin(), occ_ix.end(),
                       [&](uint32_t a, uint32_t c) { return r.triangles[a].t.z_min < r.triangles[c].t.z_min; });
      int64_t tests = 0, visible = 0, pieces = 0;
      const uint64_t clocks0 = cov.clocks;
      uint64_t model = 10;
      for (const auto& rt : r.triangles) {
        const int64_t tests0 = tests;
        int64_t tri_pieces = 0;
        for (const auto& piece : rt.pieces) {
          if (piece.empty()) continue;
          const geom::RationalPoint q = geom::interior_point(piece);
          const double qx = q.fx / q.fw, qy = q.fy / q.fw;
          // The resolver's scan (analytic_resolver.cpp, occluded()): the screens before an
          // exact test are its own; the exact tests go to the RTL.
          std::vector<Occluder> occ;
          for (uint32_t oi : occ_ix) {
            const auto& u = r.triangles[oi];
            if (u.t.z_min > rt.t.z_max) break;
            if (u.id == rt.id) continue;
            if (qx < u.t.bbox.x0 - 1.0 || qx > u.t.bbox.x1 + 1.0 || qy < u.t.bbox.y0 - 1.0 || qy > u.t.bbox.y1 + 1.0)
              continue;
            occ.push_back({&u.t, u.id});
          }
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
