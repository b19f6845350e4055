// DRAM behind a TLM-2.0 target socket: latency, bandwidth in bytes per cycle, and an
// occupancy-based contention model (the data bus is one resource; a transfer waits until
// the bus is free, holds it for bytes / bandwidth cycles). Every initiator binds to one
// multi-passthrough socket. Timing only: no data is stored. Streams (control streams,
// primitive records, tile write-outs) are contiguous, so a transfer is charged its bytes,
// not whole bursts: splitting a stream into per-primitive transactions costs no extra.
#pragma once

#include <systemc>
#include <tlm>
#include <tlm_utils/multi_passthrough_target_socket.h>

#include "units/common/stats.h"

namespace tilevis::sim {

struct MemoryConfig {
  // LPDDR4-3200 on a 64-bit bus: 3200 MT/s x 8 B = 25.6 GB/s (data rate: JEDEC JESD209-4;
  // the 64-bit bus is an assumption for a PowerVR-class SoC) = 32 B per 800 MHz GPU cycle.
  uint32_t bytes_per_cycle = 32;
  // Load-to-use latency of ~100 ns, typical of mobile LPDDR4 systems (assumption) = 80 cycles.
  uint32_t latency_cycles = 80;
};

class Memory : public sc_core::sc_module {
 public:
  tlm_utils::multi_passthrough_target_socket<Memory> socket;

  Memory(const sc_core::sc_module_name& name, const MemoryConfig& config, const sc_core::sc_time& period);
  StatsGroup& stats() { return m_stats; }
  uint64_t bytes() const { return uint64_t(m_read.value + m_written.value); }

  // Delay of a transfer of `bytes` issued at `at`, occupying the bus (what b_transport
  // annotates; also the closed form the analytic level uses for one transfer).
  sc_core::sc_time occupy(const sc_core::sc_time& at, uint64_t bytes, bool read);
  // Counts a transfer without simulated time (the analytic level); returns its bus cycles.
  uint64_t account(uint64_t bytes, bool read);
  uint32_t latency_cycles() const { return m_cfg.latency_cycles; }

 private:
  void b_transport(int id, tlm::tlm_generic_payload& p, sc_core::sc_time& delay);

  MemoryConfig m_cfg;
  sc_core::sc_time m_period, m_latency;
  sc_core::sc_time m_free_at;  // the data bus is busy until then
  StatsGroup m_stats;
  Stat& m_read;
  Stat& m_written;
  Stat& m_transactions;
  Stat& m_busy;
  Stat& m_queue;
};

}  // namespace tilevis::sim
