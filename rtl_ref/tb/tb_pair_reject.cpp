// PairReject against the public tests of model/visibility, bit for bit: constrained-random
// pairs (--random N --seed S) and every pair of the dumped tile jobs (--jobs FILE), issued in
// the analytic resolver's order. Prints the decisions' coverage; exits 1 on any mismatch.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "VPairReject.h"
#include "port_bits.h"
#include "scoreboard.h"
#include "verilated.h"
#include "visibility/evu_jobs.h"

using namespace tilevis;
using namespace tilevis::rtl;

namespace {

constexpr int kLanes = TB_LANES, kMaxV = 8, kZW = 32, kCW = 25, kLA = 26, kLC = 49, kPX = 74, kPW = 51, kNW = 4;
constexpr int kLatency = 3;

struct Pending {
  bool valid[kLanes] = {};
  int expected[kLanes] = {};
  uint64_t index[kLanes] = {};
};

class Bench {
 public:
  Bench() : m_ctx(std::make_unique<VerilatedContext>()), m_dut(std::make_unique<VPairReject>(m_ctx.get())) {
    m_dut->clk = 0;
    m_dut->rst = 1;
    tick();
    tick();
    m_dut->rst = 0;
  }

  // Queues one pair; issues when every lane holds one.
  void push(const PairVector& v, int expected) {
    m_lane_vec[m_fill] = v;
    m_lane_exp[m_fill] = expected;
    if (++m_fill == kLanes) issue();
  }
  void flush() {
    if (m_fill) issue();
    for (int i = 0; i < kLatency; ++i) {
      m_dut->in_valid = 0;
      cycle();
    }
  }
  uint64_t mismatches() const { return m_mismatches; }
  uint64_t cycles() const { return m_cycles; }
  const PairCoverage& coverage() const { return m_cov; }
  int last_code(uint64_t index) const { return m_codes.at(index); }
  void keep_codes(bool k) { m_keep = k; }
  void clear_codes() {
    m_codes.clear();
    m_next_index = 0;
  }

 private:
  void tick() {
    m_dut->clk = 1;
    m_dut->eval();
    m_dut->clk = 0;
    m_dut->eval();
  }
  void issue() {
    Pending p;
    m_dut->in_valid = 0;
    for (int l = 0; l < m_fill; ++l) {
      load(l, m_lane_vec[l]);
      m_dut->in_valid |= 1u << l;
      p.valid[l] = true;
      p.expected[l] = m_lane_exp[l];
      p.index[l] = m_next_index++;
      m_cov.add(m_lane_vec[l], m_lane_exp[l]);
      if (m_keep) m_codes.push_back(-1);
    }
    m_pending.push_back(p);
    m_fill = 0;
    cycle();
  }
  void cycle() {
    tick();
    ++m_cycles;
    if (m_dut->in_valid == 0) m_pending.push_back(Pending{});
    if (m_pending.size() > size_t(kLatency)) std::printf("PairReject: more in flight than the latency\n"), std::exit(1);
    if (m_pending.size() == size_t(kLatency)) {
      const Pending& p = m_pending.front();
      for (int l = 0; l < kLanes; ++l) {
        const bool v = get_bit(m_dut->out_valid, l);
        if (v != p.valid[l]) {
          std::printf("MISMATCH lane %d: out_valid %d, expected %d\n", l, v, p.valid[l]);
          ++m_mismatches;
          continue;
        }
        if (!v) continue;
        const int code = int(get_field(m_dut->out_code, l * 3, 3));
        if (m_keep) m_codes[p.index[l]] = code;
        if (code != p.expected[l]) {
          if (m_mismatches < 20)
            std::printf("MISMATCH vector %llu lane %d: rtl %s, model %s\n", (unsigned long long)p.index[l], l,
                        pair_code_name(code), pair_code_name(p.expected[l]));
          ++m_mismatches;
        }
      }
      m_pending.pop_front();
    }
  }
  void load(int l, const PairVector& v) {
    put_field(m_dut->e_ax, l * kCW, kCW, v.e.a.x);
    put_field(m_dut->e_ay, l * kCW, kCW, v.e.a.y);
    put_field(m_dut->e_bx, l * kCW, kCW, v.e.b.x);
    put_field(m_dut->e_by, l * kCW, kCW, v.e.b.y);
    put_field(m_dut->e_az, l * kZW, kZW, v.e.a.z);
    put_field(m_dut->e_bz, l * kZW, kZW, v.e.b.z);
    for (int i = 0; i < 3; ++i) {
      put_field(m_dut->t_x, (l * 3 + i) * kCW, kCW, v.t.tri.v[i].x);
      put_field(m_dut->t_y, (l * 3 + i) * kCW, kCW, v.t.tri.v[i].y);
      put_field(m_dut->t_z, (l * 3 + i) * kZW, kZW, v.t.tri.v[i].z);
    }
    put_field(m_dut->p_n, l * kNW, kNW, int64_t(v.poly.size()));
    for (int i = 0; i < kMaxV; ++i) {
      const bool used = size_t(i) < v.poly.size();
      const geom::Line ln = used ? v.poly.line(size_t(i)) : geom::Line{};
      const geom::ImplicitPoint p = used ? v.poly.vertex(size_t(i)) : geom::ImplicitPoint{};
      const int k = l * kMaxV + i;
      put_field(m_dut->p_la, k * kLA, kLA, ln.a);
      put_field(m_dut->p_lb, k * kLA, kLA, ln.b);
      put_field(m_dut->p_lc, k * kLC, kLC, ln.c);
      put_field(m_dut->p_vx, k * kPX, kPX, p.x);
      put_field(m_dut->p_vy, k * kPX, kPX, p.y);
      put_field(m_dut->p_vw, k * kPW, kPW, p.w);
    }
  }

  std::unique_ptr<VerilatedContext> m_ctx;
  std::unique_ptr<VPairReject> m_dut;
  PairVector m_lane_vec[kLanes];
  int m_lane_exp[kLanes] = {};
  int m_fill = 0;
  std::deque<Pending> m_pending;
  uint64_t m_cycles = 0, m_mismatches = 0, m_next_index = 0;
  PairCoverage m_cov;
  bool m_keep = false;
  std::vector<int> m_codes;
};

// Every pair of a tile job in the resolver's order: per triangle, the edges by z_min until the
// first that is behind (test 6; the sequencer issues it and stops). The tile's pair_tests and
// candidate_pairs (test 3 by svgpu::survives where the RTL says "depth") must equal golden's.
struct JobCheck {
  uint64_t jobs = 0, pairs = 0, counter_mismatches = 0;
};

void run_job(Bench& b, const vis::EvuJob& j, JobCheck& jc) {
  std::vector<vis::svgpu::Edge> edges;
  for (size_t k = 0; k < j.edges.size(); k += 2) edges.push_back(vis::svgpu::Edge::from(j.edges[k], j.edges[k + 1]));
  std::vector<uint32_t> order(edges.size());
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t c) { return edges[a].z_min < edges[c].z_min; });
  std::vector<PairVector> issued;
  int64_t pair_tests = 0;
  for (const auto& jt : j.triangles) {
    const auto t = vis::svgpu::Triangle::from(jt.v[0], jt.v[1], jt.v[2]);
    const geom::ConvexPolygon poly = geom::triangle_in_rect(t.tri, j.rect);
    if (poly.empty()) continue;
    for (uint32_t ei : order) {
      PairVector v{t, edges[ei], poly};
      issued.push_back(v);
      if (vis::svgpu::edge_behind(v.e, t)) break;
      ++pair_tests;
    }
  }
  b.clear_codes();
  for (const auto& v : issued) b.push(v, expected_pair_code(v.poly, v.t, v.e));
  b.flush();
  int64_t candidates = 0;
  for (size_t k = 0; k < issued.size(); ++k)
    if (b.last_code(k) == kDepth) candidates += vis::svgpu::survives(issued[k].poly, issued[k].t, issued[k].e);
  ++jc.jobs;
  jc.pairs += issued.size();
  if (pair_tests != j.golden.pair_tests || candidates != j.golden.candidate_pairs) {
    if (jc.counter_mismatches < 10)
      std::printf("COUNTER MISMATCH tile %u: pair_tests %lld/%lld candidates %lld/%lld (rtl/golden)\n", j.tile,
                  (long long)pair_tests, (long long)j.golden.pair_tests, (long long)candidates,
                  (long long)j.golden.candidate_pairs);
    ++jc.counter_mismatches;
  }
}

}  // namespace

int main(int argc, char** argv) {
  const TbOptions opt = parse_tb_options(argc, argv, kTbMaxJobs);
  const uint64_t random = opt.random, seed = opt.seed, job_stride = opt.job_stride, max_jobs = opt.max_jobs;
  const std::vector<std::string>& jobs = opt.jobs;
  Verilated::commandArgs(argc, argv);
  uint64_t bad = 0;
  if (random) {
    Bench b;
    PairSource src(seed);
    for (uint64_t k = 0; k < random; ++k) {
      const PairVector v = src.next();
      b.push(v, expected_pair_code(v.poly, v.t, v.e));
    }
    b.flush();
    std::printf("PairReject x%d random (seed %llu): %s; %llu cycles; mismatches %llu\n", kLanes,
                (unsigned long long)seed, b.coverage().report().c_str(), (unsigned long long)b.cycles(),
                (unsigned long long)b.mismatches());
    bad += b.mismatches();
  }
  for (const std::string& f : jobs) {
    Bench b;
    b.keep_codes(true);
    JobCheck jc;
    uint64_t seen = 0;
    try {
      vis::read_evu_jobs(f, [&](const vis::EvuJob& j) {
        if (seen++ % job_stride != 0 || jc.jobs >= max_jobs) return;
        run_job(b, j, jc);
      });
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      return 2;
    }
    std::printf(
        "PairReject x%d jobs %s: %llu of %llu tile jobs, %llu pairs; %s; mismatches %llu, tile counter "
        "mismatches %llu\n",
        kLanes, f.c_str(), (unsigned long long)jc.jobs, (unsigned long long)seen, (unsigned long long)jc.pairs,
        b.coverage().report().c_str(), (unsigned long long)b.mismatches(), (unsigned long long)jc.counter_mismatches);
    bad += b.mismatches() + jc.counter_mismatches;
  }
  return bad ? 1 : 0;
}
