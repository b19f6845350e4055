// The memory system's plain C++ parts: DRAM timing (rows, banks, channels, refresh) and
// the stream cache. Expected times are worked out here by hand from the LPDDR4-4266
// timings in tCK (dram.h), not by calling the model.
#include <gtest/gtest.h>

#include <set>

#include "units/memory/cache.h"
#include "units/memory/dram.h"

using namespace tilevis::sim;

namespace {

constexpr uint64_t kTck = 469;
uint64_t tck(uint64_t n) { return n * kTck; }

}  // namespace

TEST(Dram, RowMissHitAndConflictCostWhatTheTimingsSay) {
  Dram d{DramConfig{}};
  // Closed bank: RCD + RL, then one 8-tCK burst.
  EXPECT_EQ(d.access(0, 0, 32, true), tck(39 + 36 + 8));
  // Same row, bank ready again at 8 tCK after the first column command: RL + burst.
  const uint64_t t = tck(1000);
  EXPECT_EQ(d.access(t, 32, 32, true), t + tck(36 + 8));
  // Another row of the same bank (the first such address: channel 0's bytes are every
  // fourth 256-byte block): precharge + activate + read.
  const Dram::Location a = d.locate(0);
  uint64_t other = 0;
  for (uint64_t x = 2048 * 4; !other; x += 2048 * 4) {
    const Dram::Location b = d.locate(x);
    if (b.channel == a.channel && b.bank == a.bank && b.row != a.row) other = x;
  }
  const uint64_t t2 = tck(2000);
  EXPECT_EQ(d.access(t2, other, 32, true), t2 + tck(39 + 39 + 36 + 8));
  EXPECT_EQ(d.counters().row_misses, 1u);
  EXPECT_EQ(d.counters().row_hits, 1u);
  EXPECT_EQ(d.counters().row_conflicts, 1u);
}

TEST(Dram, FarApartStreamsStartInDifferentBanks) {
  // The regions of traffic.h are 1 GiB apart: without the row folded into the bank every
  // one of them would start in bank 0 and two streams would close each other's rows.
  Dram d{DramConfig{}};
  std::set<uint32_t> banks;
  for (uint64_t g = 0; g < 6; ++g) banks.insert(d.locate(g << 30).bank);
  EXPECT_GE(banks.size(), 5u);
}

TEST(Dram, ChannelsServeAStreamSideBySide) {
  // 1 KiB at address 0: four 256-byte pieces on four channels, 8 bursts each; the first
  // burst of each waits RCD + RL, the other 7 follow at one burst per 8 tCK.
  Dram four{DramConfig{}};
  EXPECT_EQ(four.access(0, 0, 1024, true), tck(39 + 36 + 8 * 8));
  DramConfig one;
  one.channels = 1;
  Dram single{one};
  EXPECT_EQ(single.access(0, 0, 1024, true), tck(39 + 36 + 32 * 8));
}

TEST(Dram, RefreshHoldsBurstsAndClosesRows) {
  Dram d{DramConfig{}};
  d.access(0, 0, 32, true);  // opens the row
  // Inside the first refresh window (REFI 8,341 .. + RFC 812): waits for its end, and the
  // row is closed again: a miss.
  const uint64_t in_window = tck(8341 + 100);
  EXPECT_EQ(d.access(in_window, 0, 32, true), tck(8341 + 812) + tck(39 + 36 + 8));
  EXPECT_EQ(d.counters().refreshes, 1u);
  EXPECT_EQ(d.counters().row_misses, 2u);
  EXPECT_EQ(d.counters().refresh_wait_ps, tck(812 - 100));
}

TEST(Dram, SequentialStreamReachesMostOfThePeakBandwidth) {
  Dram d{DramConfig{}};
  const uint64_t bytes = uint64_t(1) << 20;
  const uint64_t done = d.access(0, 0, bytes, true);
  const double seconds = double(done) * 1e-12;
  const double achieved = double(bytes) / seconds;
  // Peak 4 x 32 B / (8 x 469 ps) = 34.1 GB/s; a row miss every 64 bursts per bank and one
  // refresh window in the ~31 us: above 85 % of peak, never above it.
  EXPECT_LE(achieved, DramConfig{}.peak_bytes_per_second());
  EXPECT_GT(achieved, 0.85 * DramConfig{}.peak_bytes_per_second());
}

TEST(Dram, PostedWriteReturnsWhenItsFirstBurstIsTaken) {
  Dram d{DramConfig{}};
  EXPECT_EQ(d.access(0, 0, 64, false), tck(39));  // activate, then the first write command
}

TEST(Dram, BacklogIsHowFarTheBusesAreBehindOnAverage) {
  // The data queued on each channel, sent back to back from its arrival: a row miss's wait
  // (activate, read latency) is not backlog, only the bursts' own time on the bus.
  Dram d{DramConfig{}};
  EXPECT_EQ(d.backlog(0), 0u);
  d.access(0, 0, 256, true);  // 8 bursts of 8 tCK on channel 0: 64 tCK of data
  EXPECT_EQ(d.backlog(0), tck(64) / 4);
  EXPECT_EQ(d.backlog(tck(64)), 0u);
  d.access(0, 256, 256, true);  // channel 1, the same
  EXPECT_EQ(d.backlog(tck(39)), 2 * tck(25) / 4);
  d.access(tck(64), 0, 32, true);  // a burst after the queue drained: its own 8 tCK only
  EXPECT_EQ(d.backlog(tck(64)), tck(8) / 4);
}

TEST(Cache, LeastRecentlyUsedLineGoes) {
  Cache c{CacheConfig{128, 64, 2}};  // one set of two 64-byte lines
  Traffic miss;
  EXPECT_EQ(c.read(0, 64, miss), 0u);     // A
  EXPECT_EQ(c.read(64, 64, miss), 0u);    // B
  EXPECT_EQ(c.read(0, 64, miss), 1u);     // A hits, B is now least recent
  EXPECT_EQ(c.read(128, 64, miss), 0u);   // C evicts B
  EXPECT_EQ(c.read(0, 64, miss), 1u);     // A stays
  EXPECT_EQ(c.read(64, 64, miss), 0u);    // B was evicted
  EXPECT_EQ(c.hits(), 2u);
  EXPECT_EQ(c.misses(), 4u);
  EXPECT_EQ(miss.bytes(), 4u * 64);
}

TEST(Cache, ARangeTouchesEveryLineItSpans) {
  Cache c{CacheConfig{16384, 64, 4}};
  Traffic miss;
  EXPECT_EQ(c.read(60, 10, miss), 0u);  // bytes 60..69: lines 0 and 1
  ASSERT_EQ(miss.spans.size(), 1u);     // adjacent misses merge into one span
  EXPECT_EQ(miss.spans[0].address, 0u);
  EXPECT_EQ(miss.spans[0].bytes, 128u);
  EXPECT_THROW(Cache(CacheConfig{100, 64, 4}), std::invalid_argument);
}
