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

uint64_t FragmentUnit::texture_footprint(const TileWork& w, uint64_t fragments, double asked) const {
  if (asked <= 0) return 0;
  const uint64_t line = m_cfg.texture_line_bytes;
  const double texels = std::min(double(fragments), double(w.pixels)) * m_cfg.texels_per_pixel;
  const uint64_t footprint = ceil_div(uint64_t(std::ceil(texels * m_cfg.texel_bytes)), line) * line;
  return std::min<uint64_t>(footprint, ceil_div(uint64_t(std::ceil(asked)), line) * line);
}

Cost FragmentUnit::cost(const Item& it) const {
  TileWork& w = *it.tile;
  const Mode mode = m_work.mode();
  uint64_t raster = 0, tests = 0;
  double shade = 0;
  Cost c;
  // The draws' texture asked for so far in the tile, per triangle (list order keeps each
  // draw's triangles together): whether the tile goes as one item or a triangle at a time,
  // the texture cache holds what the tile read, so an item reads only the lines its
  // triangles add to their draw's footprint, and a tile reads the same bytes at every level.
  if (w.texture_before.size() != w.tris.size()) {
    w.texture_before.assign(w.tris.size(), {0, 0.0});
    for (size_t i = 1; i < w.tris.size(); ++i) {
      const TriangleWork& p = w.tris[i - 1];
      if (p.draw != w.tris[i].draw) continue;
      const double asked = double(p.fragments_shaded) * double(m_work.frame().draws[p.draw].texture_bytes_per_fragment);
      w.texture_before[i] = {w.texture_before[i - 1].first + p.fragments_shaded, w.texture_before[i - 1].second + asked};
    }
  }
  const uint64_t line = m_cfg.texture_line_bytes;
  const uint64_t tile_texels = uint64_t(std::ceil(double(m_work.config().tile_w) * m_work.config().tile_h *
                                                  m_cfg.texels_per_pixel));
  const uint64_t tile_stride = ceil_div(tile_texels * m_cfg.texel_bytes, line) * line;
  uint32_t run_first = it.first;  // the first triangle of the item's current run of one draw
  for (uint32_t i = it.first; i < it.first + it.count; ++i) {
    const TriangleWork& t = w.tris[i];
    const trace::Draw& d = m_work.frame().draws[t.draw];
    if (t.draw != w.tris[run_first].draw) run_first = i;
    raster += rasterised(t, mode);
    tests += fragment_depth_tests(t, mode, w);
    shade += double(t.fragments_shaded) * double(d.shader_cycles_per_fragment);
    if (t.fragments_shaded) {
      const uint32_t id = w.ids.empty() ? 0 : w.ids[i];
      c.pb_reads.add(m_buffer.address(w.segment, id) + m_buffer.position_record_bytes(), m_buffer.varying_bytes(t.draw));
    }
    // The end of a run of one draw inside the item: its texture lines beyond those read.
    const bool run_ends = i + 1 == it.first + it.count || w.tris[i + 1].draw != t.draw;
    if (!run_ends) continue;
    const auto [frag0, asked0] = w.texture_before[run_first];
    const uint64_t frag1 = w.texture_before[i].first + t.fragments_shaded;
    const double asked1 = w.texture_before[i].second + double(t.fragments_shaded) * double(d.texture_bytes_per_fragment);
    const uint64_t from = texture_footprint(w, frag0, asked0), to = texture_footprint(w, frag1, asked1);
    if (to > from)
      c.reads.add(region::textures + uint64_t(t.draw) * region::texture_stride + uint64_t(w.tile) * tile_stride + from,
                  to - from);
  }
  // Raster, depth test and shading overlap; the slowest sets the pace.
  c.cycles = std::max({ceil_div(raster, m_cfg.raster_samples_per_clock), ceil_div(tests, m_cfg.depth_tests_per_clock),
                       uint64_t(std::ceil(shade / double(m_cfg.shader_lanes))), uint64_t(it.count)});
  if (it.last) c.cycles += m_cfg.latency_cycles;
  return c;
}

}  // namespace tilevis::sim
