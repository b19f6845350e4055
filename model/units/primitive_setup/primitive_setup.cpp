#include "units/primitive_setup/primitive_setup.h"

namespace tilevis::sim {

PrimitiveSetup::PrimitiveSetup(const sc_core::sc_module_name& name, const UnitEnv& env,
                               const PrimitiveSetupConfig& config)
    : Stage(name, env, "primitive setup: clip, cull, viewport transform, snap to 16.8 fixed point", TileUnit::count,
            false),
      m_cfg(config) {}

void PrimitiveSetup::prepare() {
  m_work.run_setup();
  const vis::Setup& s = m_work.setup();
  const uint32_t n = m_work.trace_triangles();
  m_cycles.assign(size_t(n) + 1, 0);
  for (uint32_t id = 0; id < n; ++id) {
    const uint32_t b = m_work.setup_begin(id), e = m_work.setup_begin(id + 1);
    const bool clipped = e > b && s.triangles[b].clipped;
    // A clipped triangle leaves as a fan: one setup slot per fan triangle.
    const uint64_t slots = std::max<uint64_t>(1, e - b);
    m_cycles[id + 1] = m_cycles[id] + ceil_div(slots, m_cfg.triangles_per_clock) + (clipped ? m_cfg.clip_cycles : 0);
  }
}

Cost PrimitiveSetup::cost(const Item& it) const {
  Cost c;
  c.cycles = m_cycles[it.first + it.count] - m_cycles[it.first] + (it.last ? m_cfg.latency_cycles : 0);
  return c;
}

}  // namespace tilevis::sim
