#include "visibility/golden.h"

#include <algorithm>
#include <stdexcept>

namespace tilevis::vis {

GoldenTiler::GoldenTiler(const Setup& s, const GoldenConfig& cfg, GoldenResult& r)
    : m_cfg(cfg), m_r(r), m_frame(s, geom::TileGrid::make(s.width, s.height, cfg.tile_w, cfg.tile_h, s.subpixel_bits)) {
  ResolverOptions o = cfg.options;
  if (m_cfg.progress)
    o.work_done = [this](uint64_t w) {
      if (m_report_progress) m_cfg.progress(m_work_done += w, m_work_total);
    };
  m_resolver = make_tile_resolver(cfg.mode, o);
  std::vector<std::string> columns = TileCounters::columns();
  const std::vector<std::string> extra = m_resolver->extra_columns();
  m_falls_back = !extra.empty();
  columns.insert(columns.end(), extra.begin(), extra.end());
  m_r.ids.assign(size_t(s.width) * s.height * s.samples.size(), -1);
  m_r.visible_area.assign(s.triangle_draw.size(), 0.0);
  m_r.tiles.resize(cfg.tile_w, cfg.tile_h, s.width, s.height, columns);
}

void GoldenTiler::bin() {
  m_frame.bin();
  if (!m_cfg.progress) return;
  m_work_total = m_work_done = 0;
  for (uint32_t tile = 0; tile < tile_count(); ++tile) {
    const uint64_t t = m_frame.tile_triangles(tile).size();
    m_work_total += 1 + t * (m_frame.tile_edges(tile).size() + t);
  }
  m_cfg.progress(0, m_work_total);
}

std::vector<uint32_t> GoldenTiler::tile_triangles(uint32_t tile) const {
  std::vector<uint32_t> out;
  out.reserve(m_frame.tile_triangles(tile).size());
  for (uint32_t i : m_frame.tile_triangles(tile)) out.push_back(m_frame.triangles()[i].setup_index);
  return out;
}

struct GoldenTiler::Resolved {
  TileOutput out;
  TileCounters counters;
  TileVerdict verdict;
  std::vector<TileTriangleWork> per_triangle;
};

GoldenTiler::~GoldenTiler() = default;

void GoldenTiler::resolve(uint32_t tile, Resolved& r, TileResolver& resolver, bool per_triangle) {
  r.out = m_r.tile_output();
  r.counters.triangles = int64_t(m_frame.tile_triangles(tile).size());
  r.counters.edges = int64_t(m_frame.tile_edges(tile).size());
  if (r.counters.triangles > 0)
    r.verdict = resolver.resolve(m_frame, tile, r.out, r.counters, per_triangle ? &r.per_triangle : nullptr);
}

void GoldenTiler::resolve_ahead(const std::vector<uint32_t>& tiles, bool per_triangle) {
  if (!m_ahead) {
    const unsigned threads = host_threads() - 1;
    if (threads == 0) return;
    ResolverOptions o = m_cfg.options;
    o.work_done = nullptr;  // progress is the caller's, as tiles are taken
    // One per thread, and one for a tile the caller takes before any thread started it.
    for (unsigned t = 0; t <= threads; ++t) m_thread_resolvers.push_back(make_tile_resolver(m_cfg.mode, o));
    m_ahead_per_triangle = per_triangle;
    // A few tiles per thread waiting: enough to ride out uneven tiles, little memory.
    m_ahead = std::make_unique<Ahead<Resolved>>(threads, 8 * size_t(threads),
                                                [this](uint32_t tile, Resolved& r, unsigned worker) {
                                                  resolve(tile, r, *m_thread_resolvers[worker], m_ahead_per_triangle);
                                                });
  }
  if (per_triangle != m_ahead_per_triangle)
    throw std::logic_error("resolve_ahead: per-triangle records asked for and not, in one tiler");
  m_ahead->submit(tiles);
}

TileVerdict GoldenTiler::process_tile(uint32_t tile, std::vector<TileTriangleWork>* per_triangle, TileOutput* added) {
  Resolved r;
  m_report_progress = m_cfg.progress && !per_triangle;
  const bool ahead = m_ahead && m_ahead->take(tile, r);
  if (ahead && m_ahead_per_triangle != (per_triangle != nullptr))
    throw std::logic_error("process_tile: per-triangle records not as resolve_ahead() was told");
  if (!ahead) resolve(tile, r, *m_resolver, per_triangle != nullptr);
  TileCounters& c = r.counters;
  const TileVerdict& v = r.verdict;
  if (added) {
    added->areas = r.out.areas;
    added->visible_triangles = r.out.visible_triangles;
  }
  m_r.add(std::move(r.out));
  if (per_triangle) per_triangle->insert(per_triangle->end(), r.per_triangle.begin(), r.per_triangle.end());
  m_r.max_tile_triangles = std::max<uint64_t>(m_r.max_tile_triangles, uint64_t(c.triangles));
  m_r.max_tile_edges = std::max<uint64_t>(m_r.max_tile_edges, uint64_t(c.edges));
  auto& row = m_r.tiles.rows[tile];
  c.write(row.data());
  if (m_falls_back) {
    m_resolver->write_extra(v, row.data() + TileCounters::kCount);
    m_r.detection_screens += v.detection_screens;
    m_r.detection_tests += v.detection_tests;
    if (v.per_pixel_cause) {
      ++m_r.fallback_tiles;
      (v.per_pixel_cause == kPerPixelInterpenetration ? m_r.fallback_interpenetration
       : v.per_pixel_cause == kPerPixelNonOpaque      ? m_r.fallback_non_opaque
                                                      : m_r.fallback_budget) += 1;
      m_r.fallback_samples += uint64_t(c.samples_covered);
      m_r.fallback_triangles += uint64_t(c.triangles);
      m_r.fallback_crossing_triangles += v.crossing_triangles;
    }
  }
  // A tile resolved ahead reports its work here, as its resolve would have (golden.h: a tile
  // weighs 1 + triangles x (edges + triangles)).
  if (m_report_progress && ahead) m_work_done += uint64_t(c.triangles) * uint64_t(c.edges + c.triangles);
  if (m_report_progress) m_cfg.progress(m_work_done += 1, m_work_total);
  return v;
}

GoldenResult golden_visibility(const Setup& s, const GoldenConfig& cfg) {
  GoldenResult r;
  r.width = s.width;
  r.height = s.height;
  r.samples = uint32_t(s.samples.size());
  GoldenTiler tiler(s, cfg, r);
  tiler.bin();
  std::vector<uint32_t> tiles(tiler.tile_count());
  for (uint32_t tile = 0; tile < tiler.tile_count(); ++tile) tiles[tile] = tile;
  tiler.resolve_ahead(tiles, false);
  for (uint32_t tile = 0; tile < tiler.tile_count(); ++tile) tiler.process_tile(tile);
  sum_golden_totals(r);
  return r;
}

void sum_golden_totals(GoldenResult& r) {
  TileCounters sum;
  for (const auto& row : r.tiles.rows) sum += TileCounters::read(row);
  r.pair_tests = uint64_t(sum.pair_tests);
  r.candidate_pairs = uint64_t(sum.candidate_pairs);
  r.clip_polygons = uint64_t(sum.clip_polygons);
  r.pieces_total = uint64_t(sum.pieces);
  r.visible_pieces = uint64_t(sum.visible_pieces);
  r.occlusion_tests = uint64_t(sum.occlusion_tests);
  r.samples_covered = uint64_t(sum.samples_covered);
  r.fragments_generated = uint64_t(sum.fragments_generated);
}

}  // namespace tilevis::vis
