// Per-pixel hidden-surface removal in the tile (PowerVR ISP-like, mode hsr): every
// covered sample of every triangle is depth-tested against the on-chip depth buffer;
// only the samples visible at the end (the tag buffer) go on to shading. Functional
// work: FrameWork's per-tile z-buffer with exact depth (the z-buffer truth's).
#pragma once

#include "units/common/stage.h"

namespace tilevis::sim {

struct HsrUnitConfig {
  // Depth tests per clock: 32 (assumption; PowerVR's ISP rate is not public for current
  // cores — 32 matches a 4x8 sample block per clock).
  uint32_t samples_per_clock = 32;
  uint32_t triangles_per_clock = 1;  // triangle setup for the tile's rasteriser (assumption)
  uint32_t latency_cycles = 16;      // per tile (assumption)
};

class HsrUnit : public Stage {
 public:
  HsrUnit(const sc_core::sc_module_name& name, const UnitEnv& env, const HsrUnitConfig& config);
  Cost cost(const Item& item) const override;

 private:
  HsrUnitConfig m_cfg;
  Stat& m_tests;
  Stat& m_tiles;
};

}  // namespace tilevis::sim
