// The memory system's plain C++ parts: DRAM timing (rows, banks, channels, refresh), the
// DRAM controller (read queue, write buffer, drains), the bandwidth model and the stream cache. Expected times
// are worked out here by hand from the LPDDR4-4266 timings in tCK (dram.h), not by
// calling the model.
#include <gtest/gtest.h>

#include <random>
#include <set>

#include "units/memory/bandwidth_model.h"
#include "units/memory/cache.h"
#include "units/memory/dram.h"
#include "units/memory/dram_controller.h"

using namespace tilevis::sim;

namespace {

constexpr uint64_t kTck = 469;
uint64_t tck(uint64_t n) { return n * kTck; }

// Addresses on channel 0 (256-byte blocks, four channels): the k-th burst of the channel's
// own byte space, and the first burst of a bank's row `row` there.
uint64_t ch0_burst(uint64_t k) { return (k / 8) * 1024 + (k % 8) * 32; }

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

TEST(Dram, TheAddressMapByShiftsIsTheMapByDivisions) {
  // Power-of-two sizes (the defaults) take shifts and masks: the same map, written out here
  // with divisions as dram.h states it, over addresses of every region and odd offsets.
  const DramConfig c;
  Dram d{c};
  std::mt19937_64 rng(7);
  for (int i = 0; i < 100000; ++i) {
    const uint64_t a = (uint64_t(i % 6) << 30) + (rng() % (uint64_t(1) << 29));
    const uint64_t block = a / c.interleave_bytes;
    const uint64_t local = (block / c.channels) * c.interleave_bytes + a % c.interleave_bytes;
    const uint64_t row_index = local / c.row_bytes, row = row_index / c.banks;
    uint64_t fold = 0;
    for (uint64_t r = row; r; r /= c.banks) fold += r % c.banks;
    const Dram::Location l = d.locate(a);
    ASSERT_EQ(l.channel, block % c.channels) << a;
    ASSERT_EQ(l.row, row) << a;
    ASSERT_EQ(l.bank, (row_index + fold) % c.banks) << a;
  }
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

TEST(Dram, ABankReadyEarlyFillsTheBusBehindAnotherRowOpening) {
  // First ready: a burst whose bank is ready takes an idle stretch of the data bus that an
  // earlier burst, still opening its row, left. Channel 0, bank 0 (address 0) and bank 1
  // (8192: the channel's second 2 KiB row). Bank 0's row is opened and used at 0; a
  // conflicting row of bank 0 (a row of the same bank) then needs PRE + ACT + RCD + RL,
  // and a row hit on bank 0's neighbour issued after it still goes first.
  Dram d{DramConfig{}};
  EXPECT_EQ(d.access(0, 8192, 32, true), tck(39 + 36 + 8));  // bank 1 opened
  const Dram::Location a = d.locate(0);
  uint64_t other = 0;
  for (uint64_t x = 2048 * 4; !other; x += 2048 * 4) {
    const Dram::Location b = d.locate(x);
    if (b.channel == a.channel && b.bank == a.bank && b.row != a.row) other = x;
  }
  d.access(0, 0, 32, true);  // bank 0 opened: data at 75 + 8 tCK (after bank 1's)
  const uint64_t t = tck(200);
  // Bank 0 conflict issued first: data at t + RP + RCD + RL (RAS long past).
  EXPECT_EQ(d.access(t, other, 32, true), t + tck(39 + 39 + 36 + 8));
  // Bank 1 row hit issued after it: its data (t + RL) goes before the conflict's.
  EXPECT_EQ(d.access(t, 8192 + 32, 32, true), t + tck(36 + 8));
}

TEST(DramController, ReadsOvertakeBufferedWrites) {
  // Ten write bursts posted at 0 stay in the buffer (below the low watermark, 32); a read
  // at 0 to another bank goes at once: RCD + RL + a burst, as on an idle DRAM. The
  // device alone (in order) puts it behind the ten writes.
  DramController c{DramConfig{}, ControllerConfig{}};
  for (uint64_t k = 0; k < 10; ++k) EXPECT_EQ(c.write(0, ch0_burst(k), 32), 0u);  // posted: no wait
  EXPECT_EQ(c.read(0, 8192, 32).done, tck(39 + 36 + 8));
  Dram in_order{DramConfig{}};
  for (uint64_t k = 0; k < 10; ++k) in_order.access(0, ch0_burst(k), 32, false);
  EXPECT_GT(in_order.access(0, 8192, 32, true), tck(39 + 36 + 8));
  EXPECT_EQ(c.counters().drained_idle + c.counters().drained_forced, 0u);
  EXPECT_EQ(c.write_occupancy(0, 0), 10u);
}

TEST(DramController, CombiningMergesPartialBursts) {
  // 48 bytes at 0 (bursts 0 and 32) and 48 at 48 (bursts 32 and 64): four posted bursts,
  // three on the bus, as one 96-byte write would be.
  DramController c{DramConfig{}, ControllerConfig{}};
  c.write(0, 0, 48);
  c.write(tck(10), 48, 48);
  EXPECT_EQ(c.counters().writes, 4u);
  EXPECT_EQ(c.counters().writes_combined, 1u);
  c.flush();
  EXPECT_EQ(c.dram().counters().bursts, 3u);
  EXPECT_EQ(c.counters().drained_flush, 3u);
  Dram alone{DramConfig{}};
  alone.access(0, 0, 48, false);
  alone.access(tck(10), 48, 48, false);
  EXPECT_EQ(alone.counters().bursts, 4u);
}

TEST(DramController, ReadsOfBufferedOrInFlightBurstsCostNoBurst) {
  DramController c{DramConfig{}, ControllerConfig{}};
  c.write(0, 0, 32);
  EXPECT_EQ(c.read(tck(1), 0, 32).done, tck(1));  // from the write buffer
  const uint64_t first = c.read(tck(2), 8192, 32).done;
  EXPECT_EQ(first, tck(2 + 39 + 36 + 8));
  EXPECT_EQ(c.read(tck(3), 8192, 32).done, first);  // merged with its own one in flight
  EXPECT_EQ(c.read(tck(3), 8192, 32, 1).done, first + tck(8));  // another requester's: a burst of its own
  EXPECT_EQ(c.counters().reads_forwarded, 1u);
  EXPECT_EQ(c.counters().reads_merged, 1u);
  EXPECT_EQ(c.dram().counters().bursts, 2u);
  ControllerConfig no_merge;
  no_merge.read_merge = 0;
  DramController d{DramConfig{}, no_merge};
  d.read(tck(2), 8192, 32);
  EXPECT_EQ(d.read(tck(3), 8192, 32).done, tck(2 + 39 + 36 + 8) + tck(8));  // a second burst, a row hit behind it
}

TEST(DramController, AFullWriteBufferStallsTheWriterByExactlyTheDrainTime) {
  // Four entries, a batch from four down to two. Four bursts of one row at 0: the fourth
  // reaches the high watermark and sends the two oldest (a row miss: data at RCD + WL;
  // then a hit: data 8 tCK later). A fifth at 0 finds the buffer full (two waiting, two
  // sent) and waits until the oldest sent burst's data leaves it: RCD + WL, not a tCK less.
  ControllerConfig q;
  q.write_buffer = 4;
  q.write_high = 4;
  q.write_low = 2;
  DramController c{DramConfig{}, q};
  for (uint64_t k = 0; k < 4; ++k) EXPECT_EQ(c.write(0, ch0_burst(k), 32), 0u);
  EXPECT_EQ(c.counters().drains, 1u);
  EXPECT_EQ(c.counters().drained_forced, 2u);
  EXPECT_EQ(c.write_occupancy(0, 0), 4u);
  EXPECT_EQ(c.write_occupancy(0, tck(39 + 18) - 1), 4u);
  EXPECT_EQ(c.write_occupancy(0, tck(39 + 18)), 3u);
  EXPECT_EQ(c.write(0, ch0_burst(4), 32), tck(39 + 18));
  EXPECT_EQ(c.counters().full_stalls, 1u);
  EXPECT_EQ(c.counters().write_stall_ps, tck(39 + 18));
}

TEST(DramController, WatermarksStartABatchAndIdleGapsDrainAboveTheLowOne) {
  // Defaults: 64 entries, batch at 54 down to 32, idle drains above 32.
  DramController c{DramConfig{}, ControllerConfig{}};
  for (uint64_t k = 0; k < 53; ++k) c.write(0, ch0_burst(k), 32);
  EXPECT_EQ(c.counters().drains, 0u);
  EXPECT_EQ(c.write_occupancy(0, 0), 53u);
  c.write(0, ch0_burst(53), 32);
  EXPECT_EQ(c.counters().drains, 1u);
  EXPECT_EQ(c.counters().drained_forced, 54u - 32u);
  EXPECT_EQ(c.write_occupancy(0, 0), 54u);       // sent, but not yet on the bus
  EXPECT_EQ(c.write_occupancy(0, tck(4000)), 32u);  // the batch has left
  // One more write at 4,000 tCK: 33 waiting, one above the low watermark; a read at 5,000
  // tCK finds the bus idle before it and that one write has gone in the gap.
  c.write(tck(4000), ch0_burst(54), 32);
  EXPECT_EQ(c.counters().drained_idle, 0u);
  c.read(tck(5000), 8192, 32);
  EXPECT_EQ(c.counters().drained_idle, 1u);
  EXPECT_EQ(c.write_occupancy(0, tck(5000)), 32u);
}

TEST(DramController, AHiddenReaderWaitsOnlyForAReadQueueSlot) {
  // Read queue of two: two reads at 0 (banks 0 and 1 of channel 0) are queued at once and
  // their reader waits for nothing; a third (bank 2) waits until the first's data has
  // left the bus (RCD + RL + a burst), not for its own latency.
  ControllerConfig q;
  q.read_queue = 2;
  DramController c{DramConfig{}, q};
  EXPECT_EQ(c.read(0, 0, 32).queued, 0u);
  const DramController::ReadDone second = c.read(0, 8192, 32);
  EXPECT_EQ(second.queued, 0u);
  EXPECT_EQ(second.done, tck(39 + 36 + 8) + tck(8));  // behind the first on the bus
  const DramController::ReadDone third = c.read(0, 16384, 32);
  EXPECT_EQ(third.queued, tck(39 + 36 + 8));
  EXPECT_EQ(third.done, tck(39 + 36 + 8) + tck(39 + 36 + 8));  // opened its row from then
  EXPECT_EQ(c.counters().read_queue_full_ps, tck(39 + 36 + 8));
}

TEST(DramController, ARequestsBurstsEnterTheReadQueueInOrder) {
  // Read queue of two, four bursts of one row (128 bytes at 0, channel 0): the first two
  // enter at 0 (a miss: data 75..83 tCK, then a hit: 83..91); the third enters when the
  // first leaves (83) and its data follows RL later (119..127); the fourth enters when the
  // second leaves (91) and follows on the bus (127..135). Its reader waits 91 tCK.
  ControllerConfig q;
  q.read_queue = 2;
  DramController c{DramConfig{}, q};
  const DramController::ReadDone r = c.read(0, 0, 128);
  EXPECT_EQ(r.queued, tck(91));
  EXPECT_EQ(r.done, tck(135));
  EXPECT_EQ(c.counters().read_queue_full_ps, tck(91));  // 83 for the third, 8 more for the fourth
}

TEST(DramController, TheWaitsNeverLeaveTheBusScheduleBehind) {
  // A reader and a writer that each wait exactly what they are told and do nothing else,
  // streaming 8 MiB each over every channel: neither ever runs ahead of the data bus by
  // more than the controller's queues hold (the read queue and the write buffer, in bursts
  // of 8 tCK, plus one row opening, RP + RCD + RL, and one refresh, RFC), however long the
  // stream: no debt builds up to be paid later. And a reader never waits past its data.
  DramController c{DramConfig{}, ControllerConfig{}};
  const ControllerConfig q;
  const uint64_t slack = tck(39 + 39 + 36 + 812 + 8);
  uint64_t rt = 0, wt = 0, worst_read = 0, worst_write = 0;
  for (uint64_t a = 0; a < (uint64_t(8) << 20); a += 64) {
    const DramController::ReadDone r = c.read(rt, (uint64_t(1) << 30) + a, 64);
    ASSERT_LE(rt + r.queued, r.done);
    worst_read = std::max(worst_read, r.done - (rt + r.queued));
    rt += r.queued;
    wt = c.write(wt, (uint64_t(2) << 30) + a, 64);
    uint64_t bus = 0;
    for (uint32_t ch = 0; ch < 4; ++ch) bus = std::max(bus, c.dram().bus_free(ch));
    worst_write = std::max(worst_write, bus > wt ? bus - wt : 0);
  }
  EXPECT_LE(worst_read, (q.read_queue + q.write_buffer) * tck(8) + slack);
  EXPECT_LE(worst_write, (q.write_buffer + q.read_queue) * tck(8) + slack);
  EXPECT_GT(c.counters().drains, 0u);  // the writer did fill the buffer
}

TEST(DramController, SaturatedBandwidthIsThePeakLessRefreshAndRowOpenings) {
  // 4 MiB read by one latency-hidden stream that waits only for read-queue slots: the data
  // buses stay busy except while a refresh holds them (RFC of every REFI) and while the row
  // a refresh closed opens again (RCD + RL, at most once a window): between
  // peak x (REFI - RFC - RCD - RL - 8) / REFI and peak x (REFI - RFC) / REFI. The stream
  // moves from row to row of each bank (conflicts), and the next bank's row opens while
  // the others send: those cost no bandwidth.
  DramController c{DramConfig{}, ControllerConfig{}};
  const uint64_t bytes = uint64_t(4) << 20;
  uint64_t t = 0, done = 0;
  for (uint64_t a = 0; a < bytes; a += 1024) {
    const DramController::ReadDone r = c.read(t, a, 1024);
    t += r.queued;
    done = std::max(done, r.done);
  }
  const double achieved = double(bytes) / (double(done) * 1e-12);
  const double peak = DramConfig{}.peak_bytes_per_second();
  EXPECT_LE(achieved, peak * (8341.0 - 812) / 8341);
  EXPECT_GE(achieved, peak * (8341.0 - 812 - 39 - 36 - 8) / 8341);
  EXPECT_GT(c.dram().counters().row_conflicts, 0u);
}

TEST(BandwidthModel, AStreamSpreadsOverTheChannelsAtTheEfficiencysRate) {
  // 1,024 bytes from 0: four 256-byte blocks, one per channel, 8 bursts each; a burst takes
  // ccd = 8 tCK at efficiency 1 and 8 / 0.5 at 0.5.
  BandwidthModel full(DramConfig{}, 1.0), half(DramConfig{}, 0.5);
  EXPECT_EQ(full.burst_ps(), tck(8));
  EXPECT_EQ(half.burst_ps(), tck(16));
  EXPECT_EQ(full.transfer(1000, 0, 1024), 1000 + 8 * tck(8));
  EXPECT_EQ(half.transfer(1000, 0, 1024), 1000 + 8 * tck(16));
  EXPECT_EQ(full.bursts(), 32u);
  EXPECT_EQ(full.busy_ps(), 32 * tck(8));
  for (uint32_t c = 0; c < 4; ++c) EXPECT_EQ(full.free_at(c), 1000 + 8 * tck(8));
}

TEST(BandwidthModel, OneChannelQueuesItsBurstsAndTheOthersStayFree) {
  BandwidthModel m(DramConfig{}, 1.0);
  // Channel 0's first block, then its second (address 1024), issued at the same time: the
  // second waits for the first; a block of channel 1 (256) does not.
  EXPECT_EQ(m.transfer(0, 0, 256), tck(64));
  EXPECT_EQ(m.transfer(0, 1024, 64), tck(64 + 16));
  EXPECT_EQ(m.transfer(0, 256, 32), tck(8));
  EXPECT_EQ(m.free_at(2), 0u);
  // Issued after the channel is free again: no wait behind earlier bursts.
  EXPECT_EQ(m.transfer(tck(1000), 0, 32), tck(1000 + 8));
}

TEST(BandwidthModel, EveryBurstASpanTouchesCountsWhole) {
  BandwidthModel m(DramConfig{}, 1.0);
  EXPECT_EQ(m.transfer(0, 31, 1), tck(8));       // one byte: one burst
  EXPECT_EQ(m.transfer(0, 31, 2), tck(8 + 16));  // across a burst boundary: two more
  EXPECT_EQ(m.bursts(), 3u);
  EXPECT_EQ(m.transfer(5, 0, 0), 5u);  // nothing moved, nothing counted
  EXPECT_EQ(m.bursts(), 3u);
  // A span across a block boundary (248 .. 263): one burst on channel 0, one on channel 1.
  BandwidthModel n(DramConfig{}, 1.0);
  EXPECT_EQ(n.transfer(0, 248, 16), tck(8));
  EXPECT_EQ(n.free_at(0), tck(8));
  EXPECT_EQ(n.free_at(1), tck(8));
  EXPECT_THROW(BandwidthModel(DramConfig{}, 0.0), std::invalid_argument);
  EXPECT_THROW(BandwidthModel(DramConfig{}, 1.5), std::invalid_argument);
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
