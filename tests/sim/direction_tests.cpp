// Direction tests: every family of timing parameters moves a crafted frame's cycles the
// way it must, by an amount worked out from the frame (Ramulator/DRAMSys habit: a model
// whose knobs do not move it is not a model). Each simulation runs in a child process.
//   overdraw(shader, texture): eight full-screen quads, one draw each, drawn without a
//     visibility unit: shading or DRAM decides the frame, by the draws' costs;
//   hotspot: a cheap full-screen quad and a small, expensive one in front of it, inside
//     one 32 x 32 tile (pixels 74..85 of 256): that tile carries most of the shading.
#include <gtest/gtest.h>

#include <string>

#include "sim_support.h"
#include "top/simulate.h"

using namespace tilevis;
using namespace tilevis::sim;

namespace {

std::string overdraw(int shader_cycles, int texture_bytes) {
  std::string objects;
  for (int i = 0; i < 8; ++i) {
    if (i) objects += ",";
    objects += R"({"name": "layer)" + std::to_string(i) + R"(", "primitive": {"type": "quads", "count": 1, "size": [6, 6],
                   "origin": [0, 0, )" + std::to_string(-0.1 * i) + R"(], "step": [0, 0, 0]},
                   "shader_cycles": )" + std::to_string(shader_cycles) + R"(, "varying_bytes": 16, "texture_bytes": )" +
               std::to_string(texture_bytes) + "}";
  }
  return R"({"viewport": [512, 512],
    "camera": {"eye": [0, 0, 3], "target": [0, 0, 0], "fov_y_deg": 50, "near": 0.1, "far": 20},
    "objects": [)" + objects + "]}";
}

const char* const kHotspot = R"({"viewport": [256, 256],
  "camera": {"eye": [0, 0, 3], "target": [0, 0, 0], "fov_y_deg": 50, "near": 0.1, "far": 20},
  "objects": [
    {"name": "ground", "primitive": {"type": "quads", "count": 1, "size": [6, 6], "origin": [0, 0, 0], "step": [0, 0, 0]},
     "shader_cycles": 1, "varying_bytes": 16, "texture_bytes": 0},
    {"name": "hot", "primitive": {"type": "quads", "count": 1, "size": [0.1, 0.1], "origin": [-0.45, 0.45, 0.5], "step": [0, 0, 0]},
     "shader_cycles": 4000, "varying_bytes": 16, "texture_bytes": 0}]})";

// Frame cycles and a few stats of one simulation.
nlohmann::json run(const std::string& scene, std::vector<std::string> params) {
  return simtest::in_child([&] {
    const trace::Frame f = simtest::frame_of("direction", scene);
    const TilerConfig c = load_config("", params);
    const SimOutput o = simulate(f, c);
    const nlohmann::json& s = o.result.stats;
    return nlohmann::json{{"cycles", o.cycles},
                          {"bound", s["totals"]["memory_bound_share"]},
                          {"dram", s["totals"]["dram_bytes"]},
                          {"pb_misses", s["units"]["fetch"]["stats"]["cache_misses"]["value"]},
                          {"imbalance", s["cores"]["load_imbalance"]},
                          {"reports", o.systemc_reports}};
  });
}

double cycles(const nlohmann::json& r) {
  EXPECT_FALSE(r.contains("error")) << r.dump();
  EXPECT_TRUE(r.value("reports", nlohmann::json::array()).empty()) << r.dump();
  return r.value("cycles", 0.0);
}

const std::vector<std::string> kNone = {"sim.mode=none"};
std::vector<std::string> with(std::vector<std::string> v, const std::string& p) {
  v.push_back(p);
  return v;
}

}  // namespace

TEST(Direction, LessBandwidthSlowsAMemoryBoundFrame) {
  // 8 layers x 512 x 512 pixels x 64 texture bytes asked, 4 of them per pixel from DRAM:
  // ~8.4 MB of texture and ~8.4 MB... the frame is DRAM-bound at 4 channels; with one
  // channel the DRAM is 4x slower, and a memory-bound frame at least 2x.
  const std::string s = overdraw(1, 64);
  const auto four = run(s, kNone), one = run(s, with(kNone, "memory.channels=1"));
  EXPECT_GT(four.value("bound", 0.0), 0.5);
  const double ratio = cycles(one) / cycles(four);
  EXPECT_GE(ratio, 2.0);
  EXPECT_LE(ratio, 4.05);
}

TEST(Direction, LongerLatencyAddsAtMostItsCountOfWaits) {
  // +1,000 ns = +800 cycles at 800 MHz per read that waits for the latency: a tile's first
  // control-stream read and a segment's first vertex read; 256 tiles at most.
  const std::string s = overdraw(1, 8);
  const double base = cycles(run(s, kNone)), slow = cycles(run(s, with(kNone, "memory.controller_latency_ns=1060")));
  EXPECT_GT(slow, base + 800);
  EXPECT_LE(slow, base + 800.0 * (256 + 8));
}

TEST(Direction, ASmallerParameterCacheReadsMoreAndIsNoFaster) {
  const char* s = simtest::kSpheres;
  const auto big = run(s, {}), tiny = run(s, {"fetch.cache_bytes=256"});
  EXPECT_GT(tiny.value("pb_misses", 0.0), big.value("pb_misses", 0.0));
  EXPECT_GT(tiny.value("dram", 0.0), big.value("dram", 0.0));
  EXPECT_GE(cycles(tiny), cycles(big));
}

TEST(Direction, AFasterClockCostsCyclesOnlyWhereDramDecides) {
  // DRAM time is in nanoseconds: doubling the clock doubles a memory-bound frame's cycles
  // (at least 1.5x: some of it is the units'), and a shading-bound frame's barely.
  const std::string mem = overdraw(1, 64), alu = overdraw(64, 0);
  const double m = cycles(run(mem, with(kNone, "sim.clock_mhz=1600"))) / cycles(run(mem, kNone));
  const double a = cycles(run(alu, with(kNone, "sim.clock_mhz=1600"))) / cycles(run(alu, kNone));
  EXPECT_GE(m, 1.5);
  EXPECT_LE(m, 2.05);
  EXPECT_LE(a, 1.1);
}

TEST(Direction, HalfTheShaderLanesDoublesAShadingBoundFrame) {
  // 8 x 262,144 fragments x 64 cycles / 32 lanes = 4.2 M cycles of shading; at 16 lanes 8.4 M.
  const std::string s = overdraw(64, 0);
  const double ratio = cycles(run(s, with(kNone, "fragment.shader_lanes=16"))) / cycles(run(s, kNone));
  EXPECT_GE(ratio, 1.8);
  EXPECT_LE(ratio, 2.0);
}

TEST(Direction, DeeperQueuesNeverSlowTheFrame) {
  const char* s = simtest::kSpheres;
  const double one = cycles(run(s, {"sim.fifo_tiles=1"})), four = cycles(run(s, {"sim.fifo_tiles=4"}));
  EXPECT_LE(four, one);
  EXPECT_GE(four, 0.7 * one);  // the queues overlap units; they do not remove work
}

TEST(Direction, TwoCoresHalveAShadingBoundFrame) {
  const std::string s = overdraw(64, 0);
  const auto one = run(s, kNone), two = run(s, with(kNone, "sim.cores=2"));
  const double ratio = cycles(two) / cycles(one);
  EXPECT_GE(ratio, 0.5);
  EXPECT_LE(ratio, 0.6);
  EXPECT_LE(two.value("imbalance", 9.0), 1.05);
}

TEST(Direction, TheDynamicSchedulerBalancesAHotspot) {
  // ~120 pixels x 4,000 cycles / 32 lanes = ~15 K cycles in one tile, against ~260 for
  // each of the 63 others (the writer's 1,024 / 4 pixels per clock): static assignment
  // leaves the hot tile's core its 31 cheap tiles too (~23 K), the dynamic scheduler
  // gives them to the other core (~16 K).
  for (const char* fidelity : {"sim.fidelity=analytic", "sim.fidelity=tile"}) {
    const std::vector<std::string> base = {"sim.mode=hsr", "sim.cores=2", fidelity};
    const auto fixed = run(kHotspot, with(base, "sim.scheduler=row_major"));
    const auto dynamic = run(kHotspot, with(base, "sim.scheduler=dynamic"));
    EXPECT_LE(cycles(dynamic), 0.95 * cycles(fixed)) << fidelity;
    EXPECT_LT(dynamic.value("imbalance", 9.0), fixed.value("imbalance", 0.0)) << fidelity;
  }
}
