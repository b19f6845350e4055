#include "units/fragment_unit/fragment_unit.h"

#include <cmath>

namespace tilevis::sim {
namespace {

// Samples the fragment unit rasterises: the visible ones after a visibility unit, every
// covered one otherwise. Shading (fragments_shaded) is per pixel and triangle (MSAA).
uint64_t rasterised(const TriangleWork& t, Mode m) {
  return m == Mode::analytic || m == Mode::hybrid || m == Mode::hsr ? uint64_t(t.samples_covered)
                                                                    : uint64_t(t.fragments_generated);
}

// Early depth tests in the fragment path: early-Z's, or the partial-render merge's (the HSR
// unit's own tests, in hsr mode and in the hybrid's per-pixel tiles, are not the fragment's).
uint64_t fragment_depth_tests(const TriangleWork& t, Mode m, const TileWork& w) {
  return m == Mode::hsr || w.per_pixel ? 0 : t.depth_tests;
}

}  // namespace

FragmentUnit::FragmentUnit(const sc_core::sc_module_name& name, const UnitEnv& env, const FragmentUnitConfig& config,
                           const ParameterBuffer& buffer)
    : Stage(name, env, "fragment unit: raster, early depth test (early_z), shading, texture fetch", TileUnit::fragment,
            true),
      mem("mem"),
      pb("pb"),
      m_cfg(config),
      m_buffer(buffer),
      m_rasterised(m_stats.add("samples_rasterised", "samples", "samples the rasteriser produced")),
      m_tests(m_stats.add("depth_tests", "samples", "early depth tests in the fragment path")),
      m_shaded(m_stats.add("fragments_shaded", "fragments", "fragments shaded")),
      m_shader_cycles(m_stats.add("shader_lane_cycles", "lane-cycles", "trace cycles per fragment x fragments shaded",
                                  false)) {
  m_mem = &mem;
  m_pb = &pb;
  m_latency_hidden = true;  // shader threads switch while texture reads are in flight
  on_tile_done([this](const TileWork& w) {
    const Mode mode = m_work.mode();
    for (const TriangleWork& t : w.tris) {
      m_rasterised.value += double(rasterised(t, mode));
      m_tests.value += double(fragment_depth_tests(t, mode, w));
      m_shaded.value += t.fragments_shaded;
      m_shader_cycles.value +=
          double(t.fragments_shaded) * double(m_work.frame().draws[t.draw].shader_cycles_per_fragment);
    }
  });
}

Cost FragmentUnit::cost(const Item& it) const {
  const TileWork& w = *it.tile;
  const Mode mode = m_work.mode();
  uint64_t raster = 0, tests = 0;
  double shade = 0, texture = 0;
  Cost c;
  for (uint32_t i = it.first; i < it.first + it.count; ++i) {
    const TriangleWork& t = w.tris[i];
    const trace::Draw& d = m_work.frame().draws[t.draw];
    raster += rasterised(t, mode);
    tests += fragment_depth_tests(t, mode, w);
    shade += double(t.fragments_shaded) * double(d.shader_cycles_per_fragment);
    texture += double(t.fragments_shaded) * double(d.texture_bytes_per_fragment);
    if (t.fragments_shaded) c.pb_read_bytes += m_buffer.varying_bytes(t.draw);
  }
  // Raster, depth test and shading overlap; the slowest sets the pace.
  c.cycles = std::max({ceil_div(raster, m_cfg.raster_samples_per_clock), ceil_div(tests, m_cfg.depth_tests_per_clock),
                       uint64_t(std::ceil(shade / double(m_cfg.shader_lanes))), uint64_t(it.count)});
  if (it.last) c.cycles += m_cfg.latency_cycles;
  c.read_bytes = uint64_t(std::ceil(texture * (1.0 - m_cfg.texture_hit_rate)));
  return c;
}

}  // namespace tilevis::sim
