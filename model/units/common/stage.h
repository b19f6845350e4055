// A pipeline stage: reads items, costs them (the unit's closed form: the same function
// the analytic level sums), spends that time beside its memory traffic and passes them
// on. A unit is a Stage plus a config struct and its cost function.
#pragma once

#include <functional>

#include "units/common/unit_base.h"
#include "units/memory/traffic.h"

namespace tilevis::sim {

struct Cost {
  uint64_t cycles = 0;
  Traffic reads, writes;  // through the unit's memory socket (after the unit's caches)
  Traffic pb_reads;       // from the parameter buffer (varyings for shading)
};

class Stage : public UnitBase {
 public:
  sc_core::sc_fifo_in<Item> in;
  sc_core::sc_fifo_out<Item> out;

  // Cycles and memory traffic of one item (render items: the tile is resolved first).
  virtual Cost cost(const Item& item) const = 0;
  // The analytic level: the same accounting without simulated time.
  void account(const Item& item, const Cost& c);
  TileUnit column() const { return m_column; }
  // Called once a tile's last item has passed (both levels).
  void on_tile_done(std::function<void(const TileWork&)> fn) { m_tile_done = std::move(fn); }
  void tile_done(const TileWork& w) {
    if (m_tile_done) m_tile_done(w);
  }
  bool resolves() const { return m_resolves; }

 protected:
  SC_HAS_PROCESS(Stage);
  Stage(const sc_core::sc_module_name& name, const UnitEnv& env, const std::string& help, TileUnit column,
        bool resolves);
  // A stage with memory traffic points this at its socket.
  tlm_utils::simple_initiator_socket<UnitBase>* m_mem = nullptr;
  tlm_utils::simple_initiator_socket<UnitBase>* m_pb = nullptr;
  bool m_latency_hidden = false;  // reads prefetched or latency-tolerant (see UnitBase::transfer)

 private:
  void run();
  TileUnit m_column;
  bool m_resolves;
  std::function<void(const TileWork&)> m_tile_done;
};

inline uint64_t ceil_div(uint64_t a, uint64_t b) { return (a + b - 1) / b; }

}  // namespace tilevis::sim
