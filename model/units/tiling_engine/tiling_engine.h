// Tiling engine: bins front-facing triangles (and, in analytic mode, silhouette edges)
// into the tiles they overlap, exactly (PowerVR bins "tile accurate", not by bounding
// box), and writes primitive blocks and control streams into the parameter buffer.
#pragma once

#include <vector>

#include "units/common/stage.h"
#include "units/parameter_buffer/parameter_buffer.h"

namespace tilevis::sim {

struct TilingEngineConfig {
  uint32_t tile_tests_per_clock = 4;  // exact triangle/tile overlap tests per clock (assumption)
  uint32_t latency_cycles = 16;       // pipeline depth, once per segment (assumption)
};

class TilingEngine : public Stage {
 public:
  tlm_utils::simple_initiator_socket<UnitBase> pb;  // to the parameter buffer

  TilingEngine(const sc_core::sc_module_name& name, const UnitEnv& env, const TilingEngineConfig& config,
               const ParameterBuffer& buffer);
  // The functional step: FrameWork::run_binning(), then per-triangle cycles.
  void prepare();
  Cost cost(const Item& item) const override;

 private:
  TilingEngineConfig m_cfg;
  const ParameterBuffer& m_buffer;
  std::vector<uint64_t> m_cycles;  // prefix over trace triangles
};

}  // namespace tilevis::sim
