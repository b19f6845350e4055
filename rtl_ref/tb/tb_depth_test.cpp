// DepthTest (test 3) against svgpu::survives, bit for bit, on the pairs that pass tests 1, 2,
// 4 and 6 (PairReject's code 0): constrained-random ones (--random N --seed S: N such pairs)
// and every such pair of the dumped tile jobs in the resolver's order (--jobs FILE), where the
// pairs that survive must number golden's candidate_pairs per tile.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "VDepthTest.h"
#include "port_bits.h"
#include "scoreboard.h"
#include "verilated.h"
#include "visibility/evu_jobs.h"

using namespace tilevis;
using namespace tilevis::rtl;

namespace {

constexpr int kMaxV = 8, kZW = 32, kCW = 25, kLA = 26, kLC = 49, kPX = 74, kPW = 51, kAW = 59, kGW = 84, kNW = 4;
constexpr int kLatency = 3;

class Bench {
 public:
  Bench() : m_ctx(std::make_unique<VerilatedContext>()), m_dut(std::make_unique<VDepthTest>(m_ctx.get())) {
    m_dut->rst = 1;
    tick();
    tick();
    m_dut->rst = 0;
  }
  void push(const PairVector& v, bool expected) {
    m_dut->in_valid = 1;
    put_field(m_dut->ax, 0, kCW, v.e.a.x);
    put_field(m_dut->ay, 0, kCW, v.e.a.y);
    put_field(m_dut->bx, 0, kCW, v.e.b.x);
    put_field(m_dut->by, 0, kCW, v.e.b.y);
    put_field(m_dut->az, 0, kZW, v.e.a.z);
    put_field(m_dut->bz, 0, kZW, v.e.b.z);
    put_field(m_dut->n, 0, kNW, int64_t(v.poly.size()));
    for (int i = 0; i < kMaxV; ++i) {
      const bool used = size_t(i) < v.poly.size();
      const geom::Line ln = used ? v.poly.line(size_t(i)) : geom::Line{};
      const geom::ImplicitPoint p = used ? v.poly.vertex(size_t(i)) : geom::ImplicitPoint{};
      put_field(m_dut->p_la, i * kLA, kLA, ln.a);
      put_field(m_dut->p_lb, i * kLA, kLA, ln.b);
      put_field(m_dut->p_lc, i * kLC, kLC, ln.c);
      put_field(m_dut->p_vx, i * kPX, kPX, p.x);
      put_field(m_dut->p_vy, i * kPX, kPX, p.y);
      put_field(m_dut->p_vw, i * kPW, kPW, p.w);
    }
    put_field(m_dut->alpha, 0, kAW, v.t.plane.alpha);
    put_field(m_dut->beta, 0, kAW, v.t.plane.beta);
    put_field(m_dut->gamma, 0, kGW, v.t.plane.gamma);
    put_field(m_dut->area, 0, kPW, v.t.plane.area);
    m_expect.push_back(expected);
    ++m_vectors;
    m_survive += expected;
    cycle();
  }
  void flush() {
    m_dut->in_valid = 0;
    while (!m_expect.empty()) cycle();
  }
  uint64_t mismatches() const { return m_mismatches; }
  uint64_t vectors() const { return m_vectors; }
  uint64_t survive() const { return m_survive; }

 private:
  void cycle() {
    tick();
    ++m_clock;
    if (m_dut->out_valid) {
      if (m_expect.empty()) std::printf("DepthTest: a verdict nobody asked for\n"), std::exit(1);
      if (bool(m_dut->out_survives) != m_expect.front() && m_mismatches++ < 10)
        std::printf("MISMATCH pair %llu: rtl %d, model %d\n", (unsigned long long)(m_vectors - m_expect.size()),
                    int(m_dut->out_survives), int(m_expect.front()));
      m_expect.pop_front();
    }
    if (m_expect.size() > size_t(kLatency)) std::printf("DepthTest: verdicts late\n"), std::exit(1);
  }
  void tick() {
    m_dut->clk = 1;
    m_dut->eval();
    m_dut->clk = 0;
    m_dut->eval();
  }
  std::unique_ptr<VerilatedContext> m_ctx;
  std::unique_ptr<VDepthTest> m_dut;
  std::deque<bool> m_expect;
  uint64_t m_mismatches = 0, m_vectors = 0, m_survive = 0, m_clock = 0;
};

}  // namespace

int main(int argc, char** argv) {
  const TbOptions opt = parse_tb_options(argc, argv, 0);
  const uint64_t random = opt.random, seed = opt.seed, job_stride = opt.job_stride;
  const std::vector<std::string>& jobs = opt.jobs;
  Verilated::commandArgs(argc, argv);
  uint64_t bad = 0;
  if (random) {
    Bench b;
    PairSource src(seed);
    uint64_t drawn = 0, level = 0;
    while (b.vectors() < random) {
      const PairVector v = src.next();
      ++drawn;
      if (expected_pair_code(v.poly, v.t, v.e) != kDepth) continue;
      level += v.e.a.z == v.e.b.z;
      b.push(v, vis::svgpu::survives(v.poly, v.t, v.e));
    }
    b.flush();
    std::printf(
        "DepthTest random (seed %llu): %llu pairs past tests 1, 2, 4, 6 (of %llu drawn), %llu survive, %llu "
        "with a level edge; mismatches %llu\n",
        (unsigned long long)seed, (unsigned long long)b.vectors(), (unsigned long long)drawn,
        (unsigned long long)b.survive(), (unsigned long long)level, (unsigned long long)b.mismatches());
    bad += b.mismatches();
  }
  for (const std::string& f : jobs) {
    Bench b;
    uint64_t seen = 0, checked = 0, counter_mismatch = 0;
    vis::read_evu_jobs(f, [&](const vis::EvuJob& j) {
      if (seen++ % job_stride != 0) return;
      ++checked;
      std::vector<vis::svgpu::Edge> edges;
      for (size_t k = 0; k < j.edges.size(); k += 2)
        edges.push_back(vis::svgpu::Edge::from(j.edges[k], j.edges[k + 1]));
      std::vector<uint32_t> order(edges.size());
      for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
      std::stable_sort(order.begin(), order.end(),
                       [&](uint32_t a, uint32_t c) { return edges[a].z_min < edges[c].z_min; });
      int64_t candidates = 0;
      for (const auto& jt : j.triangles) {
        const auto t = vis::svgpu::Triangle::from(jt.v[0], jt.v[1], jt.v[2]);
        const geom::ConvexPolygon poly = geom::triangle_in_rect(t.tri, j.rect);
        if (poly.empty()) continue;
        for (uint32_t ei : order) {
          if (vis::svgpu::edge_behind(edges[ei], t)) break;
          if (expected_pair_code(poly, t, edges[ei]) != kDepth) continue;
          const bool s = vis::svgpu::survives(poly, t, edges[ei]);
          candidates += s;
          b.push({t, edges[ei], poly}, s);
        }
      }
      b.flush();
      if (candidates != j.golden.candidate_pairs) ++counter_mismatch;
    });
    std::printf(
        "DepthTest jobs %s: %llu of %llu tile jobs, %llu pairs past tests 1, 2, 4, 6, %llu survive; mismatches "
        "%llu, tile counter mismatches %llu\n",
        f.c_str(), (unsigned long long)checked, (unsigned long long)seen, (unsigned long long)b.vectors(),
        (unsigned long long)b.survive(), (unsigned long long)b.mismatches(), (unsigned long long)counter_mismatch);
    bad += b.mismatches() + counter_mismatch;
  }
  return bad ? 1 : 0;
}
