// Primitive setup: near/far and guard-band clipping, culling, viewport transform and
// snapping (model/visibility/setup.h does the arithmetic; this unit adds its time).
#pragma once

#include <vector>

#include "units/common/stage.h"

namespace tilevis::sim {

struct PrimitiveSetupConfig {
  uint32_t triangles_per_clock = 1;  // one triangle set up per clock (assumption, usual for one setup pipe)
  uint32_t clip_cycles = 8;          // extra cycles for a triangle a clip plane cuts (assumption)
  uint32_t latency_cycles = 24;      // pipeline depth, once per segment (assumption)
};

class PrimitiveSetup : public Stage {
 public:
  PrimitiveSetup(const sc_core::sc_module_name& name, const UnitEnv& env, const PrimitiveSetupConfig& config);
  // The functional step: FrameWork::run_setup(), then per-triangle cycles.
  void prepare();
  Cost cost(const Item& item) const override;

 private:
  PrimitiveSetupConfig m_cfg;
  std::vector<uint64_t> m_cycles;  // prefix over trace triangles
};

}  // namespace tilevis::sim
