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

TileWork* tile_of(std::vector<TriangleWork> tris) {
  auto* w = new TileWork;  // lives until the child exits
  w->tris = std::move(tris);
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
                        MakeUnit&& make) {
  return simtest::in_child([&] {
    sc_core::sc_report_handler::set_handler(collect);
    FrameWorkConfig fc;
    fc.mode = mode;
    FrameWork work(empty_frame(), fc);
    UnitEnv env{&work, kPeriod, false, nullptr};
    Harness h("harness", expected);
    h.items = items_of(tile_of(std::move(tris)), per_triangle);
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

TriangleWork pairs(uint32_t p) {
  TriangleWork t;
  t.pair_tests = p;
  return t;
}
TriangleWork clips(uint32_t candidates, uint32_t splits) {
  TriangleWork t;
  t.candidate_pairs = candidates;
  t.clip_polygons = splits;
  return t;
}
TriangleWork occlusion(uint32_t pieces, uint32_t tests) {
  TriangleWork t;
  t.pieces = pieces;
  t.occlusion_tests = tests;
  return t;
}

}  // namespace

TEST(UnitTiming, RejectIssuesPairTestsAcrossItsLanes) {
  // 8 lanes, II 1, latency 6: ceil(20/8) + 1 (no pairs: passes in a cycle) + ceil(9/8) + 6 = 12.
  const EarlyVisibilityConfig cfg;
  const auto r = run_unit(12, Mode::analytic, {pairs(20), pairs(0), pairs(9)}, false,
                          [&](const UnitEnv& env) { return std::make_unique<EvuReject>("reject", env, cfg); });
  expect_boundary(r, 12);
}

TEST(UnitTiming, ClipPaysItsInitiationInterval) {
  // 2 lanes, II 4, latency 12: ceil(5/2)*4 + 1 + ceil(1/2)*4 + 12 = 29.
  const EarlyVisibilityConfig cfg;
  const auto r = run_unit(29, Mode::analytic, {clips(3, 2), clips(0, 0), clips(1, 0)}, false,
                          [&](const UnitEnv& env) { return std::make_unique<EvuClip>("clip", env, cfg); });
  expect_boundary(r, 29);
}

TEST(UnitTiming, OccludeTestsPiecesAgainstOccluders) {
  // 4 lanes, II 1, latency 10: ceil(11/4) + ceil(1/4) + ceil(7/4) + 10 = 16.
  const EarlyVisibilityConfig cfg;
  const auto r = run_unit(16, Mode::analytic, {occlusion(2, 9), occlusion(1, 0), occlusion(3, 4)}, false,
                          [&](const UnitEnv& env) { return std::make_unique<EvuOcclude>("occlude", env, cfg); });
  expect_boundary(r, 16);
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

// The whole EVU: reject -> clip -> occlude.
nlohmann::json run_evu(uint64_t expected, bool per_triangle) {
  const std::vector<TriangleWork> tris = {
      [] { TriangleWork t = pairs(20); t.candidate_pairs = 3; t.clip_polygons = 2; t.pieces = 2; t.occlusion_tests = 9; return t; }(),
      [] { TriangleWork t = pairs(0); t.pieces = 1; return t; }(),
      [] { TriangleWork t = pairs(9); t.candidate_pairs = 1; t.pieces = 3; t.occlusion_tests = 4; return t; }()};
  return simtest::in_child([&] {
    sc_core::sc_report_handler::set_handler(collect);
    FrameWork work(empty_frame(), {});
    UnitEnv env{&work, kPeriod, false, nullptr};
    Harness h("harness", expected);
    h.items = items_of(tile_of(tris), per_triangle);
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
  // One transaction for the tile: reject 12, then clip 12+1+4+12 = 29, then occlude 16: 57.
  const auto r = run_evu(57, false);
  expect_boundary(r, 57);
  EXPECT_EQ(r["busy"].get<double>(), 57.0);
}

TEST(UnitTiming, EvuPrimitiveTransactionsPipelineTheSubUnits) {
  // Per triangle: reject ends at 3, 4, 4+2+6 = 12; clip starts each when both it and the
  // triangle are ready: 3..15, 15..16, 16..16+4+12 = 32; occlude: 15..18, 18..19, 32..32+2+10 = 44.
  const auto r = run_evu(44, true);
  expect_boundary(r, 44);
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
