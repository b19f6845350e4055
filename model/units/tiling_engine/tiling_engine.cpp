#include "units/tiling_engine/tiling_engine.h"

namespace tilevis::sim {

TilingEngine::TilingEngine(const sc_core::sc_module_name& name, const UnitEnv& env, const TilingEngineConfig& config,
                           const ParameterBuffer& buffer)
    : Stage(name, env, "tiling engine: exact binning of triangles and silhouette edges, tile lists", TileUnit::count,
            false),
      pb("pb"),
      m_cfg(config),
      m_buffer(buffer) {
  m_mem = &pb;
}

void TilingEngine::prepare() {
  m_work.run_binning();
  const vis::Setup& s = m_work.setup();
  const uint32_t n = m_work.trace_triangles();
  m_cycles.assign(size_t(n) + 1, 0);
  for (uint32_t id = 0; id < n; ++id) {
    uint64_t c = 0;
    for (uint32_t t = m_work.setup_begin(id); t < m_work.setup_begin(id + 1); ++t)
      if (s.triangles[t].front) c += std::max<uint64_t>(1, ceil_div(m_work.tile_tests(t), m_cfg.tile_tests_per_clock));
    const auto [e0, e1] = m_work.owned_edges(id);
    for (const uint32_t* e = e0; e != e1; ++e)
      c += std::max<uint64_t>(1, ceil_div(m_work.edge_tests(*e), m_cfg.tile_tests_per_clock));
    m_cycles[id + 1] = m_cycles[id] + c;
  }
}

Cost TilingEngine::cost(const Item& it) const {
  Cost c;
  c.cycles = m_cycles[it.first + it.count] - m_cycles[it.first] + (it.last ? m_cfg.latency_cycles : 0);
  c.writes.add(m_buffer.address(it.segment, it.first), m_buffer.bytes(it.first, it.first + it.count));
  return c;
}

}  // namespace tilevis::sim
