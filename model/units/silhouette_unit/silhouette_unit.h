// Silhouette unit (SVGPU §3.1): pairs the edges of each draw's triangles in an on-chip
// hash keyed by vertex index (position for triangle soup); an edge whose partner faces the
// other way, or that has none, is a silhouette. The silhouettes themselves come from
// model/visibility/setup (exact); this unit models the hash: its capacity, and the spill
// traffic when the open edges of a draw outgrow it. Off in the per-pixel modes.
#pragma once

#include <vector>

#include "units/common/stage.h"

namespace tilevis::sim {

struct SilhouetteUnitConfig {
  // 4096 entries x 16 B = 64 KiB of SRAM (assumption: a budget like a tile buffer's).
  uint32_t hash_entries = 4096;
  uint32_t entry_bytes = 16;       // two 32-bit vertex keys, triangle reference, facing (assumption)
  uint32_t edges_per_clock = 3;    // one triangle's three edges per clock (assumption)
  uint32_t latency_cycles = 8;     // hash pipeline depth, once per segment (assumption)
};

class SilhouetteUnit : public Stage {
 public:
  tlm_utils::simple_initiator_socket<UnitBase> mem;

  SilhouetteUnit(const sc_core::sc_module_name& name, const UnitEnv& env, const SilhouetteUnitConfig& config);
  // Runs the hash over the frame in submission order (after setup).
  void prepare();
  Cost cost(const Item& item) const override;

 private:
  SilhouetteUnitConfig m_cfg;
  std::vector<uint64_t> m_cycles, m_spill_write, m_spill_read;  // prefix over trace triangles
  Stat& m_lookups;
  Stat& m_paired;
  Stat& m_spills;
  Stat& m_probes;
  Stat& m_readback;
  Stat& m_peak;
};

}  // namespace tilevis::sim
