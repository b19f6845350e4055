#include "drivers.h"

#include <algorithm>
#include <cstdio>
#include <deque>
#include <stdexcept>
#include <string>

#include "VClip.h"
#include "VOcclude.h"
#include "VTileSequencer.h"
#include "port_bits.h"
#include "verilated.h"

namespace tilevis::rtl {
namespace {

// A Verilated unit with its own context. An assertion that fails in the RTL ($error under
// --assert) marks the context: tick() resets the unit and throws, as fail() does for a
// protocol the unit broke, so that the next operation starts from reset.
//
// Verilator 5.006 reports $error and erases a model's scopes on destruction through the
// thread's current context (Verilated::threadContextp(), the last one constructed), not the
// model's: with several units in one process, each clock and the destructor make the unit's
// context current first, and the destructor leaves the default one current (no pointer to a
// deleted context).
template <class V>
struct Dut {
  explicit Dut(const char* name) : unit(name), ctx(std::make_unique<VerilatedContext>()) {
    ctx->fatalOnError(false);
    v = std::make_unique<V>(ctx.get());
    reset();
  }
  ~Dut() {
    Verilated::threadContextp(ctx.get());
    v.reset();
    ctx.reset();
    Verilated::threadContextp(Verilated::defaultContextp());
  }
  Dut(const Dut&) = delete;
  Dut& operator=(const Dut&) = delete;
  void reset() {
    Verilated::threadContextp(ctx.get());
    ctx->gotError(false);
    ctx->gotFinish(false);
    v->rst = 1;
    clock();
    clock();
    v->rst = 0;
  }
  void clock() {
    Verilated::threadContextp(ctx.get());
    v->clk = 1;
    v->eval();
    v->clk = 0;
    v->eval();
  }
  void tick() {
    clock();
    if (ctx->gotError()) fail("an RTL assertion failed (see the output above)");
  }
  [[noreturn]] void fail(const std::string& what) {
    reset();
    throw std::runtime_error(std::string(unit) + ": " + what);
  }
  const char* unit;
  std::unique_ptr<VerilatedContext> ctx;
  std::unique_ptr<V> v;
};

}  // namespace

// ---- TileSequencer ----------------------------------------------------------------------------

struct TileSequencerDriver::Impl {
  Dut<VTileSequencer> d{"TileSequencer"};
};

TileSequencerDriver::TileSequencerDriver() : m(std::make_unique<Impl>()) {}
TileSequencerDriver::~TileSequencerDriver() = default;

TileSequencerDriver::Result TileSequencerDriver::run(const std::vector<uint32_t>& tri_zmax,
                                                     const std::vector<uint32_t>& edge_zmin) {
  constexpr int kEIW = 9;  // $clog2(kSeqEdgeCap + 1)
  static_assert((1u << (kEIW - 1)) <= kSeqEdgeCap && kSeqEdgeCap < (1u << kEIW));
  auto& d = m->d;
  auto& v = *d.v;
  const uint32_t nt = uint32_t(tri_zmax.size()), ne = uint32_t(edge_zmin.size());
  if (nt == 0) throw std::invalid_argument("TileSequencer: a pass needs at least one triangle");
  Result r;
  r.tri_clocks.assign(nt, 0);
  for (uint32_t t0 = 0; t0 < nt; t0 += kSeqTriCap) {
    const uint32_t tn = std::min(kSeqTriCap, nt - t0);
    std::vector<bool> stopped_before(tn, false);
    for (uint32_t e0 = 0; e0 == 0 || e0 < ne; e0 += kSeqEdgeCap) {
      const uint32_t en = std::min(kSeqEdgeCap, ne - e0);
      // Load: one entry per list per clock (the longer list sets the time).
      const uint32_t load = std::max(tn, en);
      for (uint32_t k = 0; k < load; ++k) {
        v.tri_we = k < tn;
        v.tri_waddr = uint16_t(k);
        v.tri_wzmax = k < tn ? tri_zmax[t0 + k] : 0;
        v.edge_we = k < en;
        v.edge_waddr = uint16_t(k);
        v.edge_wzmin = k < en ? edge_zmin[e0 + k] : 0;
        d.tick();
      }
      v.tri_we = v.edge_we = 0;
      r.load_clocks += load;
      ++r.passes;
      v.n_tris = uint16_t(tn);
      v.n_edges = uint16_t(en);
      v.start = 1;
      // Clock 1 starts the pass; from clock 3 on, each clock's issue row is one row stage A
      // read (or the one it read ahead and dropped, which shows as a row of the same
      // triangle issuing nothing); `done` comes with the last.
      uint64_t walk = 0;
      for (;;) {
        d.tick();
        v.start = 0;
        ++walk;
        if (walk >= 3) {
          if (v.iss_tri >= tn) d.fail("an issue row of a triangle beyond the pass");
          ++r.tri_clocks[t0 + v.iss_tri];
        }
        for (uint32_t l = 0; l < kSeqLanes; ++l)
          if (get_bit(v.iss_valid, int(l)))
            r.issued.emplace_back(t0 + v.iss_tri, e0 + uint32_t(get_field(v.iss_edge, int(l) * kEIW, kEIW)));
        if (v.tri_end && v.tri_stop) {
          r.stopped += !stopped_before[v.iss_tri];
          stopped_before[v.iss_tri] = true;
        }
        if (v.done) break;
        if (walk > 4 + uint64_t(tn) * (kSeqEdgeCap / kSeqLanes + 2))
          d.fail("a pass never ended");
      }
      r.walk_clocks += walk;
      if (ne == 0) break;
    }
  }
  return r;
}

// ---- Clip ---------------------------------------------------------------------------------------

namespace {
constexpr int kCW = 25, kLA = 26, kLC = 49, kPX = 74, kPW = 51;
}

struct ClipDriver::Impl {
  Dut<VClip> d{"Clip"};
  void collect(geom::ConvexPolygon& in, geom::ConvexPolygon& out) {
    auto& v = *d.v;
    for (int s = 0; s < 2; ++s) {
      if ((v.o_in_valid >> s) & 1)
        in.push_edge({int64_t(get_signed(v.o_in_la, s * kLA, kLA)), int64_t(get_signed(v.o_in_lb, s * kLA, kLA)),
                      int64_t(get_signed(v.o_in_lc, s * kLC, kLC))},
                     {get_signed(v.o_in_vx, s * kPX, kPX), get_signed(v.o_in_vy, s * kPX, kPX),
                      int64_t(get_signed(v.o_in_vw, s * kPW, kPW))});
      if ((v.o_out_valid >> s) & 1)
        out.push_edge({int64_t(get_signed(v.o_out_la, s * kLA, kLA)), int64_t(get_signed(v.o_out_lb, s * kLA, kLA)),
                       int64_t(get_signed(v.o_out_lc, s * kLC, kLC))},
                      {get_signed(v.o_out_vx, s * kPX, kPX), get_signed(v.o_out_vy, s * kPX, kPX),
                       int64_t(get_signed(v.o_out_vw, s * kPW, kPW))});
    }
  }
};

ClipDriver::ClipDriver() : m(std::make_unique<Impl>()) {}
ClipDriver::~ClipDriver() = default;

ClipDriver::Split ClipDriver::split(const geom::ConvexPolygon& poly, const vis::svgpu::Edge& e) {
  const size_t n = poly.size();
  if (n < 3 || n >= (size_t(1) << kClipNW))
    throw std::invalid_argument("Clip: a parent of " + std::to_string(n) + " edges, outside 3.." +
                                std::to_string((1u << kClipNW) - 1) + " (n is " + std::to_string(kClipNW) + " bits)");
  auto& d = m->d;
  auto& v = *d.v;
  constexpr uint32_t kMask = (1u << kCW) - 1;
  v.start = 1;
  v.n = uint16_t(n);
  v.ax = uint32_t(e.a.x) & kMask;
  v.ay = uint32_t(e.a.y) & kMask;
  v.bx = uint32_t(e.b.x) & kMask;
  v.by = uint32_t(e.b.y) & kMask;
  d.tick();
  v.start = 0;
  uint32_t clocks = 1;
  Split s;
  // The parent streamed from the piece memory, one edge a clock: LOAD, then EMIT when the
  // line crosses (the lane is in EMIT as the first pass ends; children come with edges 1..n-1).
  auto stream = [&](bool collect) {
    for (size_t i = 0; i < n; ++i) {
      const auto& l = poly.line(i);
      const auto& p = poly.vertex(i);
      v.e_valid = 1;
      put_field(v.e_la, 0, kLA, l.a);
      put_field(v.e_lb, 0, kLA, l.b);
      put_field(v.e_lc, 0, kLC, l.c);
      put_field(v.e_vx, 0, kPX, p.x);
      put_field(v.e_vy, 0, kPX, p.y);
      put_field(v.e_vw, 0, kPW, p.w);
      d.tick();
      ++clocks;
      if (collect) m->collect(s.inside, s.outside);
      if (v.done) d.fail("done before the parent's last edge");
    }
    v.e_valid = 0;
  };
  stream(false);
  if (v.ready) d.fail("idle after the parent's first pass");
  // The lane's state after LOAD is not a port: a crossing shows as status 0 (set as LOAD ends).
  if (v.status == 0) stream(true);
  // The last clock: the pair (n - 1, 0) and done.
  d.tick();
  ++clocks;
  m->collect(s.inside, s.outside);
  if (!v.done) d.fail("no done after " + std::to_string(clocks) + " clocks");
  s.status = int(v.status);
  s.clocks = clocks;
  return s;
}

int split_status(const geom::SplitResult& want) { return !want.outside.empty() ? (want.inside.empty() ? 2 : 0) : 1; }

namespace {
bool same(const geom::ConvexPolygon& a, const geom::ConvexPolygon& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    const auto &la = a.line(i), &lb = b.line(i);
    const auto &va = a.vertex(i), &vb = b.vertex(i);
    if (!(la == lb) || va.x != vb.x || va.y != vb.y || va.w != vb.w) return false;
  }
  return true;
}
}  // namespace

bool split_matches(const ClipDriver::Split& got, const geom::SplitResult& want) {
  const int status = split_status(want);
  if (got.status != status) return false;
  return status != 0 || (same(got.inside, want.inside) && same(got.outside, want.outside));
}

// ---- Occlude ------------------------------------------------------------------------------------

namespace {
constexpr int kQX = 174, kQW = 151, kAW = 59, kGW = 84;

template <class T, int L>
bool equal_wide(const T& port, int width, const geom::WideInt<L>& v) {
  for (int i = 0; i < width; ++i)
    if (get_bit(port, i) != bool((v.limb[i / 64] >> (i % 64)) & 1)) return false;
  for (int i = width; i < 64 * L; ++i)  // the rest of v is the sign
    if (bool((v.limb[i / 64] >> (i % 64)) & 1) != get_bit(port, width - 1)) return false;
  return true;
}
}  // namespace

struct OccludeDriver::Impl {
  Dut<VOcclude> d{"Occlude"};
};

OccludeDriver::OccludeDriver() : m(std::make_unique<Impl>()) {}
OccludeDriver::~OccludeDriver() = default;

OccludeDriver::Result OccludeDriver::run(const geom::ConvexPolygon& piece, const vis::svgpu::Triangle& t, uint32_t t_id,
                                         const std::vector<Occluder>& occ) {
  auto& d = m->d;
  auto& v = *d.v;
  Result r;
  const geom::RationalPoint q = geom::interior_point(piece);
  v.o_valid = 0;
  v.p_valid = 1;
  for (int i = 0; i < 3; ++i) {
    put_field(v.p_vx, i * kPX, kPX, piece.vertex(size_t(i)).x);
    put_field(v.p_vy, i * kPX, kPX, piece.vertex(size_t(i)).y);
    put_field(v.p_vw, i * kPW, kPW, piece.vertex(size_t(i)).w);
  }
  put_field(v.t_alpha, 0, kAW, t.plane.alpha);
  put_field(v.t_beta, 0, kAW, t.plane.beta);
  put_field(v.t_gamma, 0, kGW, t.plane.gamma);
  put_field(v.t_area, 0, kPW, t.plane.area);
  v.t_id = t_id;
  d.tick();
  v.p_valid = 0;
  d.tick();
  uint32_t clocks = 2;
  if (!v.q_ready) d.fail("q not ready 2 clocks after the piece");
  r.q_matches = equal_wide(v.q_x, kQX, q.x) && equal_wide(v.q_y, kQX, q.y) && equal_wide(v.q_w, kQW, q.w);
  // Stream occluders until the scoreboard's first hit; the verdicts return 2 clocks later.
  std::deque<bool> expect;
  bool hit = false;
  size_t k = 0;
  while ((k < occ.size() && !hit) || !expect.empty()) {
    const bool issue = k < occ.size() && !hit;
    v.o_valid = issue;
    if (issue) {
      const Occluder& o = occ[k++];
      const auto& u = *o.u;
      for (int i = 0; i < 3; ++i) {
        put_field(v.u_la, i * kLA, kLA, u.edges.edge[size_t(i)].a);
        put_field(v.u_lb, i * kLA, kLA, u.edges.edge[size_t(i)].b);
        put_field(v.u_lc, i * kLC, kLC, u.edges.edge[size_t(i)].c);
      }
      v.u_edges_valid = u.edges.valid;
      put_field(v.u_alpha, 0, kAW, u.plane.alpha);
      put_field(v.u_beta, 0, kAW, u.plane.beta);
      put_field(v.u_gamma, 0, kGW, u.plane.gamma);
      put_field(v.u_area, 0, kPW, u.plane.area);
      v.u_id = o.id;
      const bool want = vis::svgpu::occludes(u, o.id, t, t_id, q);
      ++r.tests;
      expect.push_back(want);
      hit = want;
    }
    d.tick();
    ++clocks;
    if (v.r_valid) {
      if (expect.empty()) d.fail("a verdict nobody asked for");
      const bool got = v.r_occluded;
      r.verdict_mismatches += got != expect.front();
      r.occluded = got;
      expect.pop_front();
    } else if (!issue && !expect.empty() && clocks > 4 + 2 * occ.size() + 4) {
      d.fail("verdicts missing");
    }
  }
  v.o_valid = 0;
  r.clocks = clocks;
  return r;
}

std::vector<uint32_t> occluder_order(const ReplayedJob& r) {
  std::vector<uint32_t> order;
  for (uint32_t i = 0; i < r.triangles.size(); ++i)
    if (r.triangles[i].opaque) order.push_back(i);
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t c) { return r.triangles[a].t.z_min < r.triangles[c].t.z_min; });
  return order;
}

void screened_occluders(const ReplayedJob& r, const std::vector<uint32_t>& order, const ReplayedTriangle& rt,
                        const geom::RationalPoint& q, std::vector<OccludeDriver::Occluder>& out) {
  const double qx = q.fx / q.fw, qy = q.fy / q.fw;
  out.clear();
  for (uint32_t oi : order) {
    const ReplayedTriangle& u = r.triangles[oi];
    if (u.t.z_min > rt.t.z_max) break;
    if (u.id == rt.id) continue;
    if (qx < u.t.bbox.x0 - 1.0 || qx > u.t.bbox.x1 + 1.0 || qy < u.t.bbox.y0 - 1.0 || qy > u.t.bbox.y1 + 1.0) continue;
    out.push_back({&u.t, u.id});
  }
}

int run_bench(int (*bench)(int, char**), int argc, char** argv) {
  try {
    return bench(argc, argv);
  } catch (const std::exception& e) {
    std::printf("%s\n", e.what());
    return 1;
  }
}

}  // namespace tilevis::rtl
