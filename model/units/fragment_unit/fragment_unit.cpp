#include "units/fragment_unit/fragment_unit.h"

#include <algorithm>
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
                                  false)),
      m_texture_requested(m_stats.add("texture_bytes_requested", "bytes",
                                      "texture bytes the shaders asked for (DRAM reads its footprint: bytes)")) {
  m_mem = &mem;
  m_pb = &pb;
  m_latency_hidden = true;  // shader threads switch while texture reads are in flight
  on_tile_done([this](const TileWork& w) {
    const Mode mode = m_work.mode();
    for (const TriangleWork& t : w.tris) {
      m_rasterised.value += double(rasterised(t, mode));
      m_tests.value += double(fragment_depth_tests(t, mode, w));
      m_shaded.value += t.fragments_shaded;
      m_texture_requested.value += double(t.fragments_shaded) * double(m_work.frame().draws[t.draw].texture_bytes_per_fragment);
      m_shader_cycles.value +=
          double(t.fragments_shaded) * double(m_work.frame().draws[t.draw].shader_cycles_per_fragment);
    }
  });
}

Cost FragmentUnit::cost(const Item& it) const {
  const TileWork& w = *it.tile;
  const Mode mode = m_work.mode();
  uint64_t raster = 0, tests = 0;
  double shade = 0;
  Cost c;
  // Per draw (in list order, as the shader switches): fragments shaded, texture asked for.
  std::vector<std::pair<uint32_t, std::pair<uint64_t, double>>> per_draw;
  for (uint32_t i = it.first; i < it.first + it.count; ++i) {
    const TriangleWork& t = w.tris[i];
    const trace::Draw& d = m_work.frame().draws[t.draw];
    raster += rasterised(t, mode);
    tests += fragment_depth_tests(t, mode, w);
    shade += double(t.fragments_shaded) * double(d.shader_cycles_per_fragment);
    if (!t.fragments_shaded) continue;
    const uint32_t id = w.ids.empty() ? 0 : w.ids[i];
    c.pb_reads.add(m_buffer.address(w.segment, id) + m_buffer.position_record_bytes(), m_buffer.varying_bytes(t.draw));
    if (per_draw.empty() || per_draw.back().first != t.draw) per_draw.push_back({t.draw, {0, 0.0}});
    per_draw.back().second.first += t.fragments_shaded;
    per_draw.back().second.second += double(t.fragments_shaded) * double(d.texture_bytes_per_fragment);
  }
  // Texture footprint: the draw's texels under the tile, whole lines, at most what was asked.
  const uint64_t line = m_cfg.texture_line_bytes;
  const uint64_t tile_texels = uint64_t(std::ceil(double(m_work.config().tile_w) * m_work.config().tile_h *
                                                  m_cfg.texels_per_pixel));
  for (const auto& [draw, work] : per_draw) {
    const auto [fragments, asked] = work;
    if (asked <= 0) continue;
    const double texels = std::min(double(fragments), double(w.pixels)) * m_cfg.texels_per_pixel;
    const uint64_t footprint = ceil_div(uint64_t(std::ceil(texels * m_cfg.texel_bytes)), line) * line;
    const uint64_t bytes = std::min<uint64_t>(footprint, ceil_div(uint64_t(std::ceil(asked)), line) * line);
    c.reads.add(region::textures + uint64_t(draw) * region::texture_stride +
                    uint64_t(w.tile) * ceil_div(tile_texels * m_cfg.texel_bytes, line) * line,
                bytes);
  }
  // Raster, depth test and shading overlap; the slowest sets the pace.
  c.cycles = std::max({ceil_div(raster, m_cfg.raster_samples_per_clock), ceil_div(tests, m_cfg.depth_tests_per_clock),
                       uint64_t(std::ceil(shade / double(m_cfg.shader_lanes))), uint64_t(it.count)});
  if (it.last) c.cycles += m_cfg.latency_cycles;
  return c;
}

}  // namespace tilevis::sim
