// Direction tests of the DRAM controller (units/memory/dram_controller.h) on a whole frame
// (simtest::kSpheres at fidelity primitive): a shallow read queue throttles prefetching, a
// deeper write buffer never slows the frame, and merging a requester's reads of a burst it
// has in flight saves bursts. Each simulation runs in a child process.
#include <gtest/gtest.h>

#include <string>

#include "sim_support.h"
#include "top/simulate.h"

using namespace tilevis;
using namespace tilevis::sim;

namespace {

nlohmann::json run(std::vector<std::string> params) {
  return simtest::in_child([&] {
    const trace::Frame f = simtest::frame_of("dram_direction", simtest::kSpheres);
    params.push_back("sim.fidelity=primitive");
    const SimOutput o = simulate(f, load_config("", params));
    const nlohmann::json& m = o.result.stats["units"]["memory"]["stats"];
    return nlohmann::json{{"cycles", o.cycles},
                          {"bursts", m["bursts"]["value"]},
                          {"merged", m["reads_merged"]["value"]},
                          {"combined", m["writes_combined"]["value"]},
                          {"reports", o.systemc_reports}};
  });
}

double value(const nlohmann::json& r, const char* key) {
  EXPECT_FALSE(r.contains("error")) << r.dump();
  EXPECT_TRUE(r.value("reports", nlohmann::json::array()).empty()) << r.dump();
  return r.value(key, 0.0);
}

}  // namespace

TEST(Direction, AShallowReadQueueThrottlesPrefetchAndADeepOneBuysNothingMore) {
  // Eight slots per channel hold the prefetching units back (they wait for slots: slower);
  // past 32 the reads already go as fast as the bus lets them, so 128 is within 1 %, and
  // not strictly faster: the prefetches it admits queue ahead of the reads that wait for
  // their latency (measured: 23,038 cycles at 32, 23,089 at 128).
  const double shallow = value(run({"memory.read_queue=8"}), "cycles");
  const double base = value(run({}), "cycles");
  const double deep = value(run({"memory.read_queue=128"}), "cycles");
  EXPECT_GT(shallow, base);
  EXPECT_LE(deep, 1.01 * base);
  EXPECT_GE(deep, 0.99 * base);
}

TEST(Direction, ADeeperWriteBufferNeverSlowsTheFrame) {
  const double small = value(run({"memory.write_buffer=16", "memory.write_high=14", "memory.write_low=8"}), "cycles");
  const double large = value(run({"memory.write_buffer=256", "memory.write_high=218", "memory.write_low=128"}), "cycles");
  const double base = value(run({}), "cycles");
  EXPECT_LE(large, base);
  EXPECT_LE(base, small);
}

TEST(Direction, MergingReadsSavesBurstsAndNeverSlowsTheFrame) {
  const auto merged = run({}), apart = run({"memory.read_merge=0"});
  EXPECT_GT(value(merged, "merged"), 0.0);
  EXPECT_EQ(value(apart, "merged"), 0.0);
  EXPECT_LT(value(merged, "bursts"), value(apart, "bursts"));
  EXPECT_LE(value(merged, "cycles"), value(apart, "cycles"));
}
