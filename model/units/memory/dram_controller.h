// The DRAM controller in front of the device (dram.h), plain C++ (no SystemC), in the
// manner of gem5's MemCtrl, DRAMSys's and Ramulator's controllers, kept call-based: every
// call says at once when its request is done, no per-cycle process. Per channel:
//   - a read queue of `read_queue` bursts. Reads are served first, issued in arrival
//     order (a call returns its time, so a later read cannot delay one already promised;
//     it may still take an idle stretch of the bus ahead of it where its bank is ready
//     first: dram.h); a read that finds the queue full waits for a slot, a slot being
//     held until the burst's data has left the bus. A read of a burst still in the
//     write buffer is served from it (gem5: "serviced by the write queue"), and one of a
//     burst that the same requester already has in the read queue takes that burst's
//     data (read_merge).
//   - a write buffer of `write_buffer` bursts. A posted write is accepted at once while
//     the buffer has room; a write to a burst already in the buffer merges with it (write
//     combining: two partial writes of one burst cost one burst on the bus). A writer
//     stalls only when the buffer is full, until its oldest sent write's data leaves it.
//   - draining: when the buffer reaches `write_high` bursts, writes go to the bus in a
//     batch, ahead of later reads, until `write_low` are left; above `write_low`, writes
//     also go in the bus's idle gaps, when their command can issue before the next read
//     arrives. Which write goes next: FR-FCFS over the oldest `frfcfs_window` entries
//     (a write to its bank's open row first, else the oldest).
// What a unit waits for therefore follows the bus schedule: a writer's stall is a drain
// time, and the bus is never more than the write buffer behind the writers; a
// latency-hidden reader waits for read-queue slots, which free as the bus delivers the
// reads ahead of it (and the forced write batches ahead of those), so the bus is never
// more than the read queue behind the readers. No debt builds up in one phase to be paid
// in another (tests/sim/memory_model_tests.cpp: TheWaitsNeverLeaveTheBusScheduleBehind).
//
// Defaults: gem5's MemCtrl/DRAMInterface (src/mem/MemCtrl.py, DRAMInterface.py: read
// buffer 32 and write buffer 64 bursts, writes forced at 85 % and switched back at 50 %,
// FR-FCFS); the FR-FCFS window (gem5 scans the whole queue) is the write buffer.
// Not modelled: read reordering across calls, write-to-read turnaround (tWTR),
// min_writes_per_switch, a rank's power-down.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <vector>

#include "units/memory/dram.h"

namespace tilevis::sim {

struct ControllerConfig {
  uint32_t read_queue = 32;      // bursts per channel (gem5 read_buffer_size)
  uint32_t write_buffer = 64;    // bursts per channel (gem5 write_buffer_size)
  uint32_t write_high = 54;      // batch drain from here: 85 % of 64 (gem5 write_high_thresh_perc)
  uint32_t write_low = 32;       // down to here; idle drains above it: 50 % (gem5 write_low_thresh_perc)
  uint32_t frfcfs_window = 64;   // oldest writes searched for a row hit (gem5: the whole queue)
  // 1: a requester's read of a burst that its own earlier read has in flight (in the read
  // queue) takes that burst's data instead of a second burst (assumption: each requester's
  // port keeps its misses in flight in miss-status registers and merges a second miss to
  // the same line, as caches and fetch units do; two requesters' reads do not merge, there
  // being no shared cache in the model). 0: every read is a burst.
  uint32_t read_merge = 1;
};

struct ControllerCounters {
  uint64_t reads = 0;              // read bursts asked for
  uint64_t reads_forwarded = 0;    // read bursts served from the write buffer
  uint64_t reads_merged = 0;       // read bursts served by the same requester's burst in the read queue
  uint64_t writes = 0;             // write bursts posted (before combining)
  uint64_t writes_combined = 0;    // write bursts merged into one already buffered
  uint64_t drains = 0;             // batches forced by the high watermark
  uint64_t drained_forced = 0;     // write bursts sent in those batches
  uint64_t drained_idle = 0;       // write bursts sent in the bus's idle gaps
  uint64_t drained_flush = 0;      // write bursts sent by flush() (the frame's end)
  uint64_t full_stalls = 0;        // write bursts that found the buffer full
  uint64_t write_stall_ps = 0;     // time those waited for a slot
  uint64_t occupancy_sum = 0;      // buffer occupancy seen by each posted burst (mean = / writes)
  uint64_t occupancy_peak = 0;
  uint64_t read_queue_full_ps = 0;  // time read bursts waited for a read-queue slot
  uint64_t read_bus_wait_ps = 0;    // time read bursts waited for the bus behind earlier bursts
};

class DramController {
 public:
  DramController(const DramConfig& dram, const ControllerConfig& config);

  struct ReadDone {
    uint64_t done = 0;    // the last burst has left the bus
    // What a latency-hidden reader (a prefetcher, shader threads) waits for: a slot in
    // its channels' read queues for each of its bursts. It issues ahead of need as far as
    // the queue lets it, so its latency and the bursts ahead of it cost it nothing until
    // the queue is full; from there it goes at the bus's pace, at most read_queue bursts
    // per channel ahead of its data.
    uint64_t queued = 0;
  };
  // `source`: the requester (its reads merge with its own in flight).
  ReadDone read(uint64_t at, uint64_t address, uint64_t bytes, int source = 0);
  // A posted write: when its last burst is in the write buffer (at, unless it was full).
  uint64_t write(uint64_t at, uint64_t address, uint64_t bytes);
  // Sends every buffered write (the frame's end), so that the counters hold every burst.
  void flush();

  // Bursts in a channel's write buffer at `at` (waiting, or sent but not yet on the bus).
  uint32_t write_occupancy(uint32_t channel, uint64_t at) const;
  const Dram& dram() const { return m_dram; }
  const ControllerConfig& config() const { return m_cfg; }
  const ControllerCounters& counters() const { return m_n; }

 private:
  struct Write {
    uint64_t address, arrived;
    Dram::Location where;
  };
  struct Read {
    uint64_t end, address;
    int source;
  };
  static constexpr size_t kKeyBits = 10, kKeys = size_t(1) << kKeyBits;
  struct Channel {
    std::vector<Write> pending;      // arrival order
    std::deque<uint64_t> sent;       // data times of sent writes not yet on the bus (ascending)
    std::deque<Read> reads;          // reads in the queue, by data end (ascending)
    // How many of each are in a slot keyed by the burst's address (a counting filter: a
    // zero spares the search for a burst to combine, forward or merge with).
    std::array<uint32_t, kKeys> pending_keys{}, read_keys{};
  };
  // The burst's address (burst-aligned), Fibonacci-hashed over all its bits: the regions
  // and the tiles' control streams (traffic.h) lie at power-of-two strides, so the burst
  // index's low 8 bits alone sent half of million's read bursts (auto, 32x32) to search the
  // pending writes in vain; hashed into 1,024 slots, 3 %.
  static size_t key(uint64_t address) { return size_t((address * 0x9E3779B97F4A7C15ull) >> (64 - kKeyBits)); }
  void advance(uint32_t c, uint64_t at);     // idle-gap drains before `at`
  size_t pick(uint32_t c) const;             // FR-FCFS among pending writes
  uint64_t send(uint32_t c, size_t index, uint64_t at);  // one write to the bus; its data time
  void retire(uint32_t c, uint64_t at);      // sent writes and reads done by `at` leave
  // One read burst arriving at `at`: its data's end, and (accepted) when it had a slot in
  // the read queue.
  uint64_t read_burst(uint64_t at, uint64_t address, int source, uint64_t& accepted);
  uint64_t write_burst(uint64_t at, uint64_t address);

  Dram m_dram;
  ControllerConfig m_cfg;
  uint64_t m_wl_ps;
  std::vector<Channel> m_ch;
  ControllerCounters m_n;
};

}  // namespace tilevis::sim
