// The memory system behind a TLM-2.0 target socket, shared by every requester: at
// memory.model=detailed the DRAM controller (dram_controller.h: read queue, write buffer with
// combining and watermark drains, FR-FCFS) in front of the DRAM timing model (dram.h:
// channels, banks, rows, refresh), plus the fabric and controller latency a read pays on top;
// at memory.model=bandwidth each channel's bus alone (bandwidth_model.h), with the same read
// latency and write buffer room. Each requester binds through attach() under a stream name, and the stats count its bytes. Timing only: no data is stored; the
// transaction's address says where the bytes lie (traffic.h's regions), its length how
// many.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <systemc>
#include <tlm>
#include <tlm_utils/multi_passthrough_target_socket.h>
#include <tlm_utils/simple_initiator_socket.h>

#include "units/common/stats.h"
#include "units/memory/bandwidth_model.h"
#include "units/memory/dram.h"
#include "units/memory/dram_controller.h"
#include "units/memory/traffic.h"

namespace tilevis::sim {

class UnitBase;

// On a read whose address was known ahead (prefetched from a control stream or an index
// stream) or whose latency the unit hides (shader threads waiting on texture): the reader
// keeps requests in flight, so it waits only for its data's place on the bus behind the
// reads queued ahead of it (and a forced write batch), not for the latency of each request
// (DramController::ReadDone::queued); row conflicts and refresh still cost it the bus time
// they take.
struct LatencyHidden : tlm::tlm_extension<LatencyHidden> {
  tlm::tlm_extension_base* clone() const override { return new LatencyHidden; }
  void copy_from(const tlm::tlm_extension_base&) override {}
};

// Which memory system serves the units: the DRAM controller and DRAM timing model
// (detailed), or each channel's bus as a server of bursts (bandwidth_model.h); automatic:
// bandwidth at fidelity analytic and tile, detailed at primitive, rtl and auto (the fidelity
// ladder: memory contention is the primitive level's).
enum class MemoryModel { automatic, detailed, bandwidth };
const char* to_string(MemoryModel m);

struct MemoryConfig {
  MemoryModel model = MemoryModel::automatic;
  // memory.model=bandwidth: the share of the buses' peak rate that bursts get. 0.9: on the 15
  // built-in scenes at fidelity tile, the frame cycles with it against the detailed model's
  // (reports/sim_bench: tile against tile (detailed memory)).
  double bandwidth_efficiency = 0.9;
  DramConfig dram;
  ControllerConfig controller;
  // Interconnect and controller latency of a read beyond the DRAM's own (assumption: a
  // mobile SoC's unloaded DRAM read takes ~100 ns; the LPDDR4 row miss, RCD + RL + a
  // burst, is ~39 ns of it).
  uint32_t controller_latency_ns = 60;
};

class Memory : public sc_core::sc_module {
 public:
  tlm_utils::multi_passthrough_target_socket<Memory> socket;

  // `config.model` automatic is taken as detailed here (the tiler resolves it by fidelity).
  Memory(const sc_core::sc_module_name& name, const MemoryConfig& config, const sc_core::sc_time& period);
  bool bandwidth_only() const { return m_bw != nullptr; }
  // Binds a requester's socket; its bytes are counted as `stream` (sockets may share a
  // stream). Returns the stream's index, for service().
  int attach(tlm_utils::simple_initiator_socket<UnitBase>& initiator, const std::string& stream);
  StatsGroup& stats() { return m_stats; }
  uint64_t bytes() const { return uint64_t(m_read.value + m_written.value); }

  // Delay of one transfer issued at `at` (what b_transport annotates). `port`: the socket
  // it came through (a requester's reads merge only with its own in flight; -1: none).
  sc_core::sc_time occupy(const sc_core::sc_time& at, uint64_t address, uint64_t bytes, bool read, int stream,
                          bool hidden = false, int port = -1);
  // The analytic level: `traffic` issued at cycle `at`, returns the cycles until it is done.
  uint64_t service(uint64_t at, const Traffic& traffic, bool read, int stream);
  // A read's unloaded latency (a row miss plus the controller), in cycles of the clock.
  uint64_t read_latency_cycles() const;
  // Copies the DRAM's counters into the stats (call once the frame is done).
  void finish(uint64_t frame_cycles);
  const Dram& dram() const { return m_ctrl.dram(); }
  const DramController& controller() const { return m_ctrl; }

 private:
  void b_transport(int id, tlm::tlm_generic_payload& p, sc_core::sc_time& delay);

  MemoryConfig m_cfg;
  DramController m_ctrl;
  std::unique_ptr<BandwidthModel> m_bw;  // memory.model=bandwidth: in place of m_ctrl
  sc_core::sc_time m_period;
  uint64_t m_period_ps, m_controller_ps;
  StatsGroup m_stats;
  Stat& m_read;
  Stat& m_written;
  Stat& m_transactions;
  Stat& m_bursts;
  Stat& m_row_hits;
  Stat& m_row_misses;
  Stat& m_row_conflicts;
  Stat& m_refreshes;
  Stat& m_refresh_wait;
  Stat& m_busy;
  Stat& m_utilisation;
  Stat& m_read_bursts;
  Stat& m_write_bursts;
  Stat& m_reads_forwarded;
  Stat& m_reads_merged;
  Stat& m_writes_combined;
  Stat& m_drains;
  Stat& m_drained_forced;
  Stat& m_drained_idle;
  Stat& m_full_stalls;
  Stat& m_write_stall;
  Stat& m_occupancy_mean;
  Stat& m_occupancy_peak;
  Stat& m_read_queue_full;
  Stat& m_read_bus_wait;
  std::vector<Stat*> m_streams;      // per stream
  std::vector<int> m_stream_of;      // per bound socket, in bind order: its stream
};

}  // namespace tilevis::sim
