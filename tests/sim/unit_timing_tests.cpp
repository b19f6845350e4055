// Unit timing at the boundary (Ramulator/VCML habit): a unit with cost N cycles is not
// done at N-1 and is done at N. Each test elaborates a small harness around one unit in a
// child process (one sc_start per process) and returns what the probes saw. The expected
// N is worked out here by hand from the unit's documented cost, not by calling it.
#include <gtest/gtest.h>

#include <systemc>
#include <tlm_utils/simple_initiator_socket.h>

#include "sim_support.h"
#include "units/early_visibility_unit/early_visibility_unit.h"
#include "units/hsr_unit/hsr_unit.h"
#include "units/memory/memory.h"

using namespace tilevis;
using namespace tilevis::sim;
using sc_core::sc_time;
using sc_core::SC_ZERO_TIME;

namespace {

const sc_time kPeriod(1250, sc_core::SC_PS);  // 800 MHz

std::vector<std::string> g_reports;
void collect(const sc_core::sc_report& r, const sc_core::sc_actions& a) {
  if (r.get_severity() >= sc_core::SC_WARNING) g_reports.push_back(r.get_msg());
  sc_core::sc_report_handler::default_handler(r, a);
}

// Feeds items to a unit, drains what it passes on, and probes "done?" at N-1 and N cycles.
struct Harness : sc_core::sc_module {
  sc_core::sc_fifo<Item> to_unit, from_unit;
  std::vector<Item> items;
  uint64_t n;
  bool done = false, done_before = true, done_at_n = false;
  sc_time done_at;

  SC_HAS_PROCESS(Harness);
  Harness(const sc_core::sc_module_name& name, uint64_t expected)
      : sc_core::sc_module(name), to_unit("to_unit", 64), from_unit("from_unit", 64), n(expected) {
    SC_THREAD(feed);
    SC_THREAD(drain);
    SC_THREAD(probe);
  }
  void feed() {
    for (const Item& it : items) to_unit.write(it);
  }
  void drain() {
    for (size_t i = 0; i < items.size(); ++i) from_unit.read();
    done = true;
    done_at = sc_core::sc_time_stamp();
  }
  void settle() {  // let a write at this time reach the drain (two delta cycles)
    wait(SC_ZERO_TIME);
    wait(SC_ZERO_TIME);
  }
  void probe() {
    wait(sc_time::from_value(kPeriod.value() * (n - 1)));
    settle();
    done_before = done;
    wait(kPeriod);
    settle();
    done_at_n = done;
  }
  nlohmann::json result() const {
    return {{"done_before", done_before},
            {"done_at_n", done_at_n},
            {"cycles", done_at.value() / kPeriod.value()},
            {"reports", g_reports}};
  }
};

trace::Frame empty_frame() {
  trace::Frame f;
  f.width = f.height = 64;
  f.samples = trace::standard_samples(1);
  return f;
}

TileWork* tile_of(std::vector<TriangleWork> tris, uint32_t edges = 0) {
  auto* w = new TileWork;  // lives until the child exits
  w->tris = std::move(tris);
  w->edges = edges;
  w->draws.assign(w->tris.size(), 0);
  w->resolved = true;
  return w;
}

// One item for the whole tile (fidelity tile) or one per triangle (fidelity primitive).
std::vector<Item> items_of(TileWork* w, bool per_triangle) {
  std::vector<Item> v;
  const uint32_t n = uint32_t(w->tris.size()), step = per_triangle ? 1 : n;
  for (uint32_t a = 0; a < n; a += step) {
    Item it;
    it.tile = w;
    it.first = a;
    it.count = std::min(step, n - a);
    it.first_of_tile = a == 0;
    it.last = a + it.count == n;
    v.push_back(it);
  }
  return v;
}

template <typename MakeUnit>
nlohmann::json run_unit(uint64_t expected, Mode mode, std::vector<TriangleWork> tris, bool per_triangle,
                        MakeUnit&& make, uint32_t edges = 0) {
  return simtest::in_child([&] {
    sc_core::sc_report_handler::set_handler(collect);
    FrameWorkConfig fc;
    fc.mode = mode;
    const trace::Frame frame = empty_frame();
    FrameWork work(frame, fc);
    UnitEnv env{&work, kPeriod, false, nullptr};
    Harness h("harness", expected);
    h.items = items_of(tile_of(std::move(tris), edges), per_triangle);
    auto unit = make(env);
    unit->in(h.to_unit);
    unit->out(h.from_unit);
    sc_core::sc_start();
    nlohmann::json r = h.result();
    r["busy"] = unit->stats().value("busy_cycles");
    return r;
  });
}

void expect_boundary(const nlohmann::json& r, uint64_t n) {
  ASSERT_FALSE(r.contains("error")) << r.dump();
  EXPECT_FALSE(r["done_before"].get<bool>()) << "done already at N-1 = " << n - 1;
  EXPECT_TRUE(r["done_at_n"].get<bool>()) << "not done at N = " << n;
  EXPECT_EQ(r["cycles"].get<uint64_t>(), n);
  EXPECT_TRUE(r["reports"].empty()) << r["reports"].dump();
}

// A triangle of a tile whose depth-sorted edge walk issued `p` pairs, ending on test 6 or not.
TriangleWork pairs(uint32_t p, bool test6_stop) {
  TriangleWork t;
  t.pair_tests = p;
  t.shape.test6_stop = test6_stop;
  return t;
}
// Splits of parents of `split_edges` edges in all (`crossing_edges` of them crossed), and
// `checks` re-checks of pieces against candidate edges.
TriangleWork clips(uint32_t splits, uint32_t split_edges, uint32_t crossing_edges, uint32_t checks) {
  TriangleWork t;
  t.clip_polygons = splits;
  t.shape.split_edges = split_edges;
  t.shape.crossing_edges = crossing_edges;
  t.shape.piece_checks = checks;
  return t;
}
TriangleWork occlusion(uint32_t pieces, uint32_t tests, uint32_t pieces_tested) {
  TriangleWork t;
  t.pieces = pieces;
  t.occlusion_tests = tests;
  t.shape.pieces_tested = pieces_tested;
  return t;
}

}  // namespace

// The defaults are the RTL's clocks (rtl_ref, reports/rtl/README.md): the RTL library's test
// (tests/rtl) checks the same formulas against the Verilated units on real tile jobs.
TEST(UnitTiming, RejectWalksRowsOfEdgesLikeTheTileSequencer) {
  // 8 lanes, 24 edges (3 rows). A triangle that walks every edge: 3 rows; one stopped by test
  // 6 on its first edge: its row and the row read ahead, 2; the last triangle stopped on edge
  // 9: rows 0 and 1, nothing read ahead after the last, 2. Per tile: lists loaded through one
  // write port (max(3, 24) = 24 clocks), the pass's start and end (2), PairReject and
  // DepthTest drained (3 + 3): 7 + 24 + 2 + 6 = 39.
  const EarlyVisibilityConfig cfg;
  const auto r = run_unit(39, Mode::analytic, {pairs(24, false), pairs(0, true), pairs(9, true)}, false,
                          [&](const UnitEnv& env) { return std::make_unique<EvuReject>("reject", env, cfg); }, 24);
  expect_boundary(r, 39);
}

TEST(UnitTiming, ClipPaysTwoClocksASplitAndItsParentsEdges) {
  // 2 lanes: (2 splits x 2 + 7 parent edges + 3 crossing edges + 3 re-checks) / 2 = 9, nothing,
  // (2 + 5 + 0 + 1) / 2 = 4: 13.
  const EarlyVisibilityConfig cfg;
  const auto r = run_unit(13, Mode::analytic, {clips(2, 7, 3, 3), clips(0, 0, 0, 0), clips(1, 5, 0, 1)}, false,
                          [&](const UnitEnv& env) { return std::make_unique<EvuClip>("clip", env, cfg); });
  expect_boundary(r, 13);
}

TEST(UnitTiming, OccludeTestsPiecesAgainstOccluders) {
  // 4 lanes; a piece: 2 clocks for its interior point, one a test, one for the last verdict
  // when it had tests: ceil((4 + 9 + 2) / 4) + ceil(2 / 4) + ceil((6 + 4 + 2) / 4) = 4 + 1 + 3 = 8.
  const EarlyVisibilityConfig cfg;
  const auto r = run_unit(8, Mode::analytic, {occlusion(2, 9, 2), occlusion(1, 0, 0), occlusion(3, 4, 2)}, false,
                          [&](const UnitEnv& env) { return std::make_unique<EvuOcclude>("occlude", env, cfg); });
  expect_boundary(r, 8);
}

TEST(UnitTiming, HsrTestsSamplesPerClock) {
  // 32 depth tests per clock, one triangle per clock, latency 16: max(2, ceil(105/32)) + 16 = 20.
  const HsrUnitConfig cfg;
  TriangleWork a, b;
  a.depth_tests = 100;
  b.depth_tests = 5;
  const auto r = run_unit(20, Mode::hsr, {a, b}, false,
                          [&](const UnitEnv& env) { return std::make_unique<HsrUnit>("hsr", env, cfg); });
  expect_boundary(r, 20);
}

namespace {

// The whole EVU: reject -> clip -> occlude, on a tile of 24 edges.
nlohmann::json run_evu(uint64_t expected, bool per_triangle) {
  const std::vector<TriangleWork> tris = {
      [] { TriangleWork t = pairs(24, false); t.clip_polygons = 2; t.shape.split_edges = 7; t.shape.crossing_edges = 3;
           t.shape.piece_checks = 3; t.pieces = 2; t.occlusion_tests = 9; t.shape.pieces_tested = 2; return t; }(),
      [] { TriangleWork t = pairs(0, true); t.pieces = 1; return t; }(),
      [] { TriangleWork t = pairs(9, true); t.clip_polygons = 1; t.shape.split_edges = 5; t.shape.piece_checks = 1;
           t.pieces = 3; t.occlusion_tests = 4; t.shape.pieces_tested = 2; return t; }()};
  return simtest::in_child([&] {
    sc_core::sc_report_handler::set_handler(collect);
    const trace::Frame frame = empty_frame();
    FrameWork work(frame, {});
    UnitEnv env{&work, kPeriod, false, nullptr};
    Harness h("harness", expected);
    h.items = items_of(tile_of(tris, 24), per_triangle);
    EarlyVisibilityUnit evu("evu", env, EarlyVisibilityConfig{}, 16);
    evu.in(h.to_unit);
    evu.out(h.from_unit);
    sc_core::sc_start();
    nlohmann::json r = h.result();
    r["busy"] = evu.stats().value("busy_cycles");
    return r;
  });
}

}  // namespace

TEST(UnitTiming, EvuTileTransactionRunsTheSubUnitsInTurn) {
  // One transaction for the tile: reject 39, then clip 13, then occlude 8: 60.
  const auto r = run_evu(60, false);
  expect_boundary(r, 60);
  EXPECT_EQ(r["busy"].get<double>(), 60.0);
}

TEST(UnitTiming, EvuPrimitiveTransactionsPipelineTheSubUnits) {
  // Reject: 3 rows + the tile's 32 clocks, then 2, then 2: ends at 35, 37, 39. Clip starts each
  // when both it and the triangle are ready: 35..44, 44..44, 44..48; occlude: 44..48, 48..49,
  // 49..52.
  const auto r = run_evu(52, true);
  expect_boundary(r, 52);
}

namespace {

struct Initiator : sc_core::sc_module {
  tlm_utils::simple_initiator_socket<Initiator> socket;
  uint64_t bytes;
  sc_time done_at;
  SC_HAS_PROCESS(Initiator);
  Initiator(const sc_core::sc_module_name& name, uint64_t b) : sc_core::sc_module(name), socket("socket"), bytes(b) {
    SC_THREAD(run);
  }
  void run() {
    unsigned char dummy = 0;
    tlm::tlm_generic_payload p;
    p.set_command(tlm::TLM_READ_COMMAND);
    p.set_data_ptr(&dummy);
    p.set_data_length(uint32_t(bytes));
    p.set_streaming_width(uint32_t(bytes));
    sc_time delay = SC_ZERO_TIME;
    socket->b_transport(p, delay);
    wait(delay);
    done_at = sc_core::sc_time_stamp();
  }
};

}  // namespace

TEST(UnitTiming, MemoryReadOpensARowThenTheSecondHitsIt) {
  // LPDDR4-4266 defaults (tCK 469 ps, RCD 39, RL 36, 8 tCK per 32-byte burst) and 60 ns of
  // controller: a 64-byte read at address 0 on an idle DRAM activates the row (RCD), its
  // two bursts leave the bus at 75..83 and 83..91 tCK: 91 x 469 + 60,000 = 102,679 ps. A
  // second read of the same bytes issued at the same time hits the open row and follows on
  // the bus: its bursts end at 99 and 107 tCK: 107 x 469 + 60,000 = 110,183 ps.
  const auto r = simtest::in_child([] {
    sc_core::sc_report_handler::set_handler(collect);
    Memory mem("memory", MemoryConfig{}, kPeriod);
    Initiator a("a", 64), b("b", 64);
    a.socket.bind(mem.socket);
    b.socket.bind(mem.socket);
    sc_core::sc_start();
    mem.finish(1);
    const uint64_t ps = sc_time(1, sc_core::SC_PS).value();
    const uint64_t ta = a.done_at.value() / ps, tb = b.done_at.value() / ps;
    return nlohmann::json{{"first", std::min(ta, tb)}, {"second", std::max(ta, tb)},
                          {"misses", mem.stats().value("row_misses")}, {"hits", mem.stats().value("row_hits")},
                          {"reports", g_reports}};
  });
  ASSERT_FALSE(r.contains("error")) << r.dump();
  EXPECT_EQ(r["first"].get<uint64_t>(), 102679u);
  EXPECT_EQ(r["second"].get<uint64_t>(), 110183u);
  EXPECT_EQ(r["misses"].get<double>(), 1.0);
  EXPECT_EQ(r["hits"].get<double>(), 3.0);
  EXPECT_TRUE(r["reports"].empty());
}
