// DRAM timing, plain C++ (no SystemC): channels, banks with one open row each, the
// command timings that decide row hits, misses and conflicts, the data bus per channel
// and all-bank refresh. This is the device: it serves each burst it is given in the order
// it is given (issue()), open page; which burst goes when is the controller's choice
// (dram_controller.h: read queue, write buffer, FR-FCFS). access() serves a request's
// bursts in arrival order with no controller in front, for the device's own tests. A
// request is cut into bursts that go to their channel and bank by the address map below,
// so a stream spreads over the channels and a scattered one pays row misses. Times are
// picoseconds.
//
// Defaults: JEDEC LPDDR4-4266 (JESD209-4; LPDDR4X has the same core timings at a lower
// I/O voltage, JESD209-4-1), the values in tCK of DRAMSys's memspec
// configs/memspec/JEDEC_1Gbx16_LPDDR4-4266.json: tCK 469 ps, BL16 on a x16 channel
// (32 bytes per burst), 8 banks, 1,024 columns of 16 bits (2 KiB rows), CCD 8, RCD 39,
// RPpb 39, RAS 90, RL 36, WL 18, REFI 8,341, RFCab 812. Four x16 channels (a 64-bit
// interface, as in most phone SoCs) and the 256-byte channel interleave are assumptions.
// Not modelled: read/write turnaround (WTR), tFAW/tRRD, per-bank refresh, power-down,
// command-bus conflicts.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace tilevis::sim {

struct DramConfig {
  uint32_t channels = 4;            // x16 channels (assumption: a 64-bit LPDDR4X interface)
  uint32_t banks = 8;               // per channel (JESD209-4)
  uint32_t row_bytes = 2048;        // 1,024 columns x 16 bits (JESD209-4, 16 Gb x16 die)
  uint32_t burst_bytes = 32;        // BL16 x 16 bits
  uint32_t interleave_bytes = 256;  // consecutive addresses per channel before the next (assumption)
  uint32_t tck_ps = 469;            // LPDDR4-4266
  // Timings in tCK (DRAMSys JEDEC_1Gbx16_LPDDR4-4266).
  uint32_t ccd = 8;    // column to column: one BL16 burst on the bus
  uint32_t rcd = 39;   // activate to column command
  uint32_t rp = 39;    // precharge (per bank)
  uint32_t ras = 90;   // activate to precharge
  uint32_t rl = 36;    // read latency
  uint32_t wl = 18;    // write latency
  uint32_t refi = 8341;  // all-bank refresh interval (3.9 us)
  uint32_t rfc = 812;    // all-bank refresh cycle time

  // Peak bandwidth, bytes per second.
  double peak_bytes_per_second() const {
    return double(channels) * double(burst_bytes) / (double(ccd) * double(tck_ps) * 1e-12);
  }
};

struct DramCounters {
  uint64_t bursts = 0;
  uint64_t row_hits = 0;       // the row was open
  uint64_t row_misses = 0;     // the bank was closed (after refresh, or never opened)
  uint64_t row_conflicts = 0;  // another row was open: precharge first
  uint64_t refreshes = 0;      // all-bank refreshes that closed a channel's rows
  uint64_t refresh_wait_ps = 0;  // time bursts waited for a refresh to end
  uint64_t bus_busy_ps = 0;      // data-bus time, summed over channels
};

// When one burst goes: its column command and its data on the bus (data .. data + burst).
struct BurstSlot {
  uint64_t column = 0;
  uint64_t data = 0;
  uint64_t bus_wait = 0;  // data time lost to the bus being busy with earlier bursts
};

class Dram {
 public:
  explicit Dram(const DramConfig& config);

  // Where an address goes (row:bank:column within a channel, channels interleaved, the
  // bank permuted by the row).
  struct Location {
    uint32_t channel, bank;
    uint64_t row;
  };
  Location locate(uint64_t address) const;

  // A request of `bytes` at `address` arriving at time `at`, its bursts issued at once in
  // address order. A read: the time its last burst has left the data bus. A write: the
  // time the DRAM takes its first burst's column command.
  uint64_t access(uint64_t at, uint64_t address, uint64_t bytes, bool read);
  // One burst (`address` burst-aligned), not before `at` and after every command issued
  // before it to its bank; its data takes the first idle stretch of its channel's bus it
  // fits in (a bank that is ready early fills the bus while another opens a row): where
  // it would go (plan) and sending it (issue).
  // `where`: locate(address), for a caller that has it.
  BurstSlot plan(uint64_t at, uint64_t address, bool read) const { return plan_burst(at, locate(address), read).slot; }
  BurstSlot plan(uint64_t at, const Location& where, bool read) const { return plan_burst(at, where, read).slot; }
  BurstSlot issue(uint64_t at, uint64_t address, bool read) { return issue(at, locate(address), read); }
  BurstSlot issue(uint64_t at, const Location& where, bool read);
  // When the channel's data bus is free of every burst issued so far.
  uint64_t bus_free(uint32_t channel) const { return m_channels[channel].bus_free; }
  // The earliest time a burst's data could start on the channel's bus (its first idle
  // stretch, or bus_free).
  uint64_t bus_first_idle(uint32_t channel) const {
    const Channel& ch = m_channels[channel];
    return ch.gaps.empty() ? ch.bus_free : ch.gaps.front().start;
  }
  // Time of one burst on the bus (CCD).
  uint64_t burst_ps() const { return m_burst_ps; }
  // The row open in a bank (-1: closed), as the last burst issued left it.
  int64_t open_row(uint32_t channel, uint32_t bank) const { return m_banks[size_t(channel) * m_cfg.banks + bank].open_row; }

  const DramConfig& config() const { return m_cfg; }
  const DramCounters& counters() const { return m_n; }

 private:
  struct Bank {
    int64_t open_row = -1;
    uint64_t activated = 0;  // last activate
    uint64_t ready = 0;      // earliest next column command
  };
  struct Gap {
    uint64_t start, end;
  };
  struct Channel {
    uint64_t bus_free = 0;
    uint64_t refreshed = 0;  // refresh windows already applied (count)
    // Idle stretches of the data bus before bus_free (ascending, at most kGaps): a burst
    // whose bank is ready early takes the first one it fits in, ahead of bursts issued
    // before it on other banks (first ready), without moving any of them.
    std::vector<Gap> gaps;
  };
  static constexpr size_t kGaps = 32;
  enum class RowState { hit, miss, conflict };
  struct Plan {
    BurstSlot slot;
    Location where;
    RowState row = RowState::hit;
    uint64_t window = 0;        // the refresh window the command falls in
    uint64_t refresh_wait = 0;  // time waited for a refresh to end
    uint64_t activate = 0;      // when the row was opened (miss, conflict)
  };
  Plan plan_burst(uint64_t at, const Location& where, bool read) const;

  DramConfig m_cfg;
  uint64_t m_tck, m_burst_ps, m_refi, m_rfc;
  uint32_t m_bank_bits = 0;  // log2(banks) where that is a whole number above 0, else 0
  // Every size of the address map a power of two: locate() by shifts (same map).
  bool m_shift_map = false;
  uint32_t m_il_bits = 0, m_channel_bits = 0, m_row_bits = 0;
  std::vector<Channel> m_channels;
  std::vector<Bank> m_banks;  // channel-major
  DramCounters m_n;
};

}  // namespace tilevis::sim
