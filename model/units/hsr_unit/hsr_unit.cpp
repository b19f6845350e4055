#include "units/hsr_unit/hsr_unit.h"

namespace tilevis::sim {

HsrUnit::HsrUnit(const sc_core::sc_module_name& name, const UnitEnv& env, const HsrUnitConfig& config)
    : Stage(name, env, "per-pixel HSR: a depth test per covered sample, visible samples to shading", TileUnit::hsr,
            true),
      m_cfg(config),
      m_tests(m_stats.add("depth_tests", "samples", "per-sample depth tests")),
      m_tiles(m_stats.add("tiles", "tiles", "tiles resolved per pixel")) {
  on_tile_done([this](const TileWork& w) {
    if (m_work.mode() == Mode::hybrid && !w.per_pixel) return;
    ++m_tiles.value;
    for (const TriangleWork& t : w.tris) m_tests.value += t.depth_tests;
  });
}

Cost HsrUnit::cost(const Item& it) const {
  const TileWork& w = *it.tile;
  // Hybrid: tiles the EVU resolved pass through.
  if (m_work.mode() == Mode::hybrid && !w.per_pixel) return {};
  uint64_t tests = 0;
  for (uint32_t i = it.first; i < it.first + it.count; ++i) tests += w.tris[i].depth_tests;
  Cost c;
  c.cycles = std::max(ceil_div(it.count, m_cfg.triangles_per_clock), ceil_div(tests, m_cfg.samples_per_clock));
  if (it.last) c.cycles += m_cfg.latency_cycles;
  return c;
}

}  // namespace tilevis::sim
