// The memory system at fidelity analytic and tile (memory.model=auto there, or =bandwidth):
// each channel's data bus as a server of bursts at a share of its peak rate, and nothing else.
// No banks, rows, refresh, queues or write drains: a transfer's bursts go to their channels
// (the DRAM's interleave: dram.h's address map), each channel sends them one after another
// from when it is free, at ccd / efficiency clocks a burst, and the transfer is done when its
// last burst has left. The efficiency stands for what the detailed model (dram_controller.h,
// dram.h) spends beyond the bursts themselves: row switches, refresh, write batches. Plain C++.
#pragma once

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "units/memory/dram.h"

namespace tilevis::sim {

class BandwidthModel {
 public:
  BandwidthModel(const DramConfig& d, double efficiency)
      : m_cfg(d), m_free(d.channels, 0) {
    if (!(efficiency > 0.0 && efficiency <= 1.0)) throw std::invalid_argument("memory: bandwidth efficiency must lie in (0, 1]");
    if (d.channels == 0 || d.burst_bytes == 0 || d.interleave_bytes % d.burst_bytes)
      throw std::invalid_argument("memory: channels, bursts and interleave must be whole");
    m_burst_ps = uint64_t(double(d.ccd) * double(d.tck_ps) / efficiency + 0.5);
  }

  // The ps at which the last burst of `bytes` at `address`, issued at `at_ps`, has left its
  // channel's bus. Every burst the span touches counts whole.
  uint64_t transfer(uint64_t at_ps, uint64_t address, uint64_t bytes) {
    if (bytes == 0) return at_ps;
    const uint64_t il = m_cfg.interleave_bytes, bb = m_cfg.burst_bytes;
    const uint64_t first_burst = address / bb, end_burst = (address + bytes - 1) / bb + 1;
    uint64_t done = at_ps;
    // Interleave blocks one at a time: a block's bursts all go to one channel.
    for (uint64_t b = first_burst; b < end_burst;) {
      const uint64_t block = b * bb / il;
      const uint64_t block_end = std::min(end_burst, (block + 1) * (il / bb));
      const uint64_t n = block_end - b;
      uint64_t& free = m_free[block % m_cfg.channels];
      free = std::max(free, at_ps) + n * m_burst_ps;
      done = std::max(done, free);
      m_bursts += n;
      m_busy_ps += n * m_burst_ps;
      b = block_end;
    }
    return done;
  }

  uint64_t burst_ps() const { return m_burst_ps; }
  uint64_t bursts() const { return m_bursts; }
  uint64_t busy_ps() const { return m_busy_ps; }  // summed over the channels
  uint64_t free_at(uint32_t channel) const { return m_free.at(channel); }

 private:
  DramConfig m_cfg;
  std::vector<uint64_t> m_free;  // per channel: when its bus is free
  uint64_t m_burst_ps = 0;
  uint64_t m_bursts = 0, m_busy_ps = 0;
};

}  // namespace tilevis::sim
