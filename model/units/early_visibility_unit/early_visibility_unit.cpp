#include "units/early_visibility_unit/early_visibility_unit.h"

#include <algorithm>

namespace tilevis::sim {
namespace {

// A triangle with no operations for the detector passes through in one cycle.
uint64_t issue_cycles(uint64_t ops, const EvuStageConfig& s) { return ops ? ceil_div(ops, s.lanes) * s.ii : 1; }

// Is triangle i the last of its pass's triangle list (nothing read ahead after it)?
bool last_of_pass(const TileWork& w, uint32_t i, const EarlyVisibilityConfig& c) {
  return i + 1 == w.tris.size() || (i + 1) % c.triangle_list_entries == 0;
}

// Clocks spread over a sub-unit's independent lanes.
uint64_t on_lanes(uint64_t clocks, const EvuStageConfig& s) { return ceil_div(clocks, s.lanes); }

}  // namespace

uint64_t reject_rows(uint64_t pairs, bool test6_stop, uint64_t edges, bool last, const EarlyVisibilityConfig& c) {
  // Edge chunks of the on-chip list, one pass each: a triangle walks every edge of a chunk it
  // does not stop in; in the chunk where test 6 stops it (and on the first edge of every later
  // one) it reads the rows through the stopping edge and one more, read ahead and dropped,
  // unless it is the pass's last triangle or that was the chunk's last row.
  const uint64_t lanes = c.reject.lanes, cap = c.edge_list_entries;
  uint64_t rows = 0;
  for (uint64_t e0 = 0; e0 == 0 || e0 < edges; e0 += cap) {
    const uint64_t en = std::min(cap, edges - e0);
    const uint64_t chunk_rows = std::max<uint64_t>(1, ceil_div(en, lanes));
    if (!test6_stop || pairs >= e0 + en) {
      rows += chunk_rows;
    } else {
      const uint64_t p = pairs > e0 ? pairs - e0 : 0;
      rows += std::min(p / lanes + 1 + (last ? 0 : c.reject_readahead_rows), chunk_rows);
    }
    if (edges == 0) break;
  }
  return rows;
}

uint64_t reject_clocks(const TriangleWork& t, uint64_t edges, bool last, const EarlyVisibilityConfig& c) {
  if (t.rtl) return t.rtl_reject;
  return reject_rows(uint64_t(t.pair_tests), t.shape.test6_stop != 0, edges, last, c) * c.reject.ii;
}

uint64_t clip_clocks(const TriangleWork& t, const EarlyVisibilityConfig& c) {
  const uint64_t checks = t.shape.piece_checks * c.clip_check_cycles;
  if (t.rtl) return t.rtl_clip + checks;
  return uint64_t(t.clip_polygons) * c.clip_split_cycles + t.shape.split_edges * c.clip.ii +
         t.shape.crossing_edges * c.clip_emit_per_edge + checks;
}

uint64_t occlude_clocks(const TriangleWork& t, const EarlyVisibilityConfig& c) {
  if (t.rtl) return t.rtl_occlude;
  return uint64_t(t.pieces) * c.occlude_piece_cycles + uint64_t(t.occlusion_tests) * c.occlude.ii +
         t.shape.pieces_tested * c.occlude_drain_cycles;
}

uint64_t reject_tile_clocks(const TileWork& w, const EarlyVisibilityConfig& c) {
  if (w.per_pixel) return 0;
  if (!w.tris.empty() && w.tris.front().rtl) return w.rtl_reject_tile;
  // Passes as the TileSequencer makes them: triangle chunks outer, edge chunks inner; each
  // loads both lists through their write ports, then starts and ends.
  const uint64_t tris = w.tris.size(), edges = w.edges;
  const uint64_t tc = c.triangle_list_entries, ec = c.edge_list_entries;
  uint64_t clocks = 0;
  for (uint64_t t0 = 0; t0 < tris; t0 += tc)
    for (uint64_t e0 = 0; e0 == 0 || e0 < edges; e0 += ec) {
      const uint64_t load = std::max(std::min(tc, tris - t0), edges ? std::min(ec, edges - e0) : 0);
      clocks += ceil_div(load, c.list_load_per_cycle) + c.reject_pass_cycles;
      if (!edges) break;
    }
  return clocks + c.reject.latency_cycles;
}

EvuReject::EvuReject(const sc_core::sc_module_name& name, const UnitEnv& env, const EarlyVisibilityConfig& config)
    : Stage(name, env, "EVU reject: SVGPU tests 1-6 on triangle x silhouette-edge pairs", TileUnit::reject, true),
      m_cfg(config) {}

Cost EvuReject::cost(const Item& it) const {
  Cost c;
  const TileWork& w = *it.tile;
  if (!w.per_pixel)
    for (uint32_t i = it.first; i < it.first + it.count; ++i)
      c.cycles += reject_clocks(w.tris[i], w.edges, last_of_pass(w, i, m_cfg), m_cfg);
  if (it.first_of_tile) c.cycles += reject_tile_clocks(w, m_cfg);
  // Hybrid: before a tile is committed to the EVU or the HSR unit, its triangle pairs are
  // screened (depth ranges and boxes: integer compares at the reject rate) and those past the
  // screen compared over their overlaps (polygon clipping and depth compares: evu.detect).
  // With evu.detect.beside the detector has its own datapath and works while reject does
  // (the tile commits when both are done): only its time beyond the tile's reject work shows.
  if (it.first_of_tile && (w.detection_screens || w.detection_tests)) {
    uint64_t detect = 0;
    if (w.detection_screens) detect += issue_cycles(w.detection_screens, m_cfg.reject);
    if (w.detection_tests) detect += issue_cycles(w.detection_tests, m_cfg.detect);
    uint64_t reject = 0;
    if (m_cfg.detect_beside && !w.per_pixel)
      for (uint32_t i = 0; i < w.tris.size(); ++i) reject += reject_clocks(w.tris[i], w.edges, last_of_pass(w, i, m_cfg), m_cfg);
    c.cycles += detect > reject ? detect - reject : 0;
  }
  return c;
}

EvuClip::EvuClip(const sc_core::sc_module_name& name, const UnitEnv& env, const EarlyVisibilityConfig& config)
    : Stage(name, env, "EVU clip: splits by candidate edges, both sides kept, re-checked (SVGPU 3.2.2)",
            TileUnit::clip, false),
      m_cfg(config) {}

Cost EvuClip::cost(const Item& it) const {
  Cost c;
  const TileWork& w = *it.tile;
  for (uint32_t i = it.first; i < it.first + it.count; ++i) c.cycles += on_lanes(clip_clocks(w.tris[i], m_cfg), m_cfg.clip);
  if (it.last) c.cycles += m_cfg.clip.latency_cycles;
  return c;
}

EvuOcclude::EvuOcclude(const sc_core::sc_module_name& name, const UnitEnv& env, const EarlyVisibilityConfig& config)
    : Stage(name, env, "EVU occlude: interior point of each piece against the tile's opaque triangles (SVGPU 3.3)",
            TileUnit::occlude, false),
      m_cfg(config) {}

Cost EvuOcclude::cost(const Item& it) const {
  Cost c;
  const TileWork& w = *it.tile;
  for (uint32_t i = it.first; i < it.first + it.count; ++i)
    c.cycles += on_lanes(occlude_clocks(w.tris[i], m_cfg), m_cfg.occlude);
  if (it.last) c.cycles += m_cfg.occlude.latency_cycles;
  return c;
}

EarlyVisibilityUnit::EarlyVisibilityUnit(const sc_core::sc_module_name& name, const UnitEnv& env,
                                         const EarlyVisibilityConfig& config, int fifo_depth)
    : UnitBase(name, env, "early-visibility unit: busy while any sub-unit is"),
      in("in"),
      out("out"),
      m_cfg(config),
      m_pairs(m_stats.add("pair_tests", "pairs", "triangle x edge pairs examined")),
      m_candidates(m_stats.add("candidate_pairs", "pairs", "pairs surviving tests 1-6")),
      m_clips(m_stats.add("clip_polygons", "splits", "polygon splits")),
      m_pieces(m_stats.add("pieces", "polygons", "pieces after clipping")),
      m_visible(m_stats.add("visible_pieces", "polygons", "pieces not occluded")),
      m_occlusion_tests(m_stats.add("occlusion_tests", "tests", "piece x occluder containment tests")),
      m_detection_screens(m_stats.add("detection_screens", "pairs", "hybrid: triangle pairs screened (depth ranges, boxes)")),
      m_detection_tests(m_stats.add("detection_tests", "tests", "hybrid: pairs past the screen compared over their overlap")),
      m_tiles(m_stats.add("tiles", "tiles", "tiles resolved")),
      m_multi_pass(m_stats.add("multi_pass_tiles", "tiles", "tiles over the on-chip list capacity")) {
  m_reject = std::make_unique<EvuReject>("reject", env, m_cfg);
  m_clip = std::make_unique<EvuClip>("clip", env, m_cfg);
  m_occlude = std::make_unique<EvuOcclude>("occlude", env, m_cfg);
  m_reject_to_clip = std::make_unique<OccupancyFifo<Item>>("reject_to_clip", fifo_depth);
  m_clip_to_occlude = std::make_unique<OccupancyFifo<Item>>("clip_to_occlude", fifo_depth);
  m_reject->in(in);
  m_reject->out(*m_reject_to_clip);
  m_clip->in(*m_reject_to_clip);
  m_clip->out(*m_clip_to_occlude);
  m_occlude->in(*m_clip_to_occlude);
  m_occlude->out(out);
  for (UnitBase* u : {static_cast<UnitBase*>(m_reject.get()), static_cast<UnitBase*>(m_clip.get()),
                      static_cast<UnitBase*>(m_occlude.get())})
    u->set_parent(this);
  m_occlude->on_tile_done([this](const TileWork& w) { count_tile(w); });
}

void EarlyVisibilityUnit::count_tile(const TileWork& w) {
  for (const TriangleWork& t : w.tris) {
    m_pairs.value += double(t.pair_tests);
    m_candidates.value += double(t.candidate_pairs);
    m_clips.value += double(t.clip_polygons);
    m_pieces.value += double(t.pieces);
    m_visible.value += double(t.visible_pieces);
    m_occlusion_tests.value += double(t.occlusion_tests);
  }
  m_detection_screens.value += double(w.detection_screens);
  m_detection_tests.value += double(w.detection_tests);
  m_tiles.value += 1;
  m_multi_pass.value += w.passes > 1;
  m_items.value += 1;
}

}  // namespace tilevis::sim
