// What every SystemC unit of the tiler shares: its clock period (latencies are cycles in
// the unit's config, turned into sc_time once, here), its stats group (busy, stall,
// items, bytes), the busy signal traced to VCD, and the three ways a unit spends time:
// its own work, a memory transfer beside it, and a full output FIFO.
#pragma once

#include <cstdint>
#include <string>

#include <systemc>
#include <tlm>
#include <tlm_utils/simple_initiator_socket.h>

#include "units/common/frame_work.h"
#include "units/common/stats.h"
#include "units/common/work.h"
#include "units/memory/traffic.h"

namespace tilevis::sim {

// Cycles during which at least one unit waited on DRAM beyond its own work.
struct MemoryWaits {
  int waiting = 0;
  sc_core::sc_time since;
  sc_core::sc_time total;
  void enter() {
    if (waiting++ == 0) since = sc_core::sc_time_stamp();
  }
  void leave() {
    if (--waiting == 0) total += sc_core::sc_time_stamp() - since;
  }
};

struct UnitEnv {
  FrameWork* work = nullptr;
  sc_core::sc_time period;      // one cycle of the GPU clock
  bool trace = false;           // drive busy/occupancy signals (VCD)
  MemoryWaits* waits = nullptr;     // time some unit waited on DRAM (the memory-bound share)
};

// An sc_fifo that counts its occupancy for the VCD (sc_fifo traces contents, not fill).
// A plain variable, traced by reference: a signal would have two drivers (both ends).
template <typename T>
class OccupancyFifo : public sc_core::sc_fifo<T> {
 public:
  OccupancyFifo(const char* name, int depth) : sc_core::sc_fifo<T>(name, depth) {}
  void write(const T& v) override {
    sc_core::sc_fifo<T>::write(v);
    ++occupancy;
  }
  void read(T& v) override {
    sc_core::sc_fifo<T>::read(v);
    --occupancy;
  }
  T read() override {
    T v;
    read(v);
    return v;
  }
  int occupancy = 0;
};

class UnitBase : public sc_core::sc_module {
 public:
  StatsGroup& stats() { return m_stats; }
  const StatsGroup& stats() const { return m_stats; }
  uint64_t busy_cycles() const { return uint64_t(m_busy.value); }
  bool busy = false;  // true while the unit works (traced to the VCD by reference)

  // A parent (the EVU) counts as busy while any of its sub-units is.
  void set_parent(UnitBase* parent) { m_parent = parent; }

 protected:
  UnitBase(const sc_core::sc_module_name& name, const UnitEnv& env, const std::string& help);

  uint64_t cycles(const sc_core::sc_time& t) const { return uint64_t(t.value() / m_period.value()); }
  sc_core::sc_time time(uint64_t cycles) const { return sc_core::sc_time::from_value(m_period.value() * cycles); }

  // Works for `cycles` while a memory transfer taking `memory` runs beside it (streamed in
  // or out as the work proceeds): the unit is done at the later of the two; memory time
  // beyond the work is a stall. `tile`, when given, is charged the work cycles.
  void spend(uint64_t cycles, const sc_core::sc_time& memory, TileWork* tile, TileUnit column);
  void spend(uint64_t cycles) { spend(cycles, sc_core::SC_ZERO_TIME, nullptr, TileUnit::count); }
  // Writes to an output FIFO; time blocked on a full FIFO is a stall.
  void push(sc_core::sc_fifo_out<Item>& out, const Item& item);
  // One TLM-2.0 transaction per span of `traffic`, all issued now (timing only: the model
  // moves no data, the payload points at a one-byte dummy; its address and length say
  // where and how much). Returns the longest delay the target annotated; time the target
  // held the call (a full parameter buffer) counts as a stall. A read whose address was
  // known ahead (prefetched from a control stream) or whose latency the unit hides (shader
  // threads waiting on texture) carries LatencyHidden (memory.h): it waits only while the
  // DRAM is behind.
  sc_core::sc_time transfer(tlm_utils::simple_initiator_socket<UnitBase>& socket, tlm::tlm_command cmd,
                            const Traffic& traffic, bool latency_hidden = false);

  void enter_busy();
  void leave_busy();

  FrameWork& m_work;
  const sc_core::sc_time m_period;
  const bool m_trace;
  MemoryWaits* m_waits;
  StatsGroup m_stats;
  Stat& m_busy;
  Stat& m_stall;
  Stat& m_items;
  Stat& m_bytes;

 private:
  UnitBase* m_parent = nullptr;
  int m_active = 0;
  sc_core::sc_time m_active_since;
  unsigned char m_dummy = 0;
};

}  // namespace tilevis::sim
