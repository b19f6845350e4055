// The golden, untimed SVGPU visibility pipeline (SVGPU §3.2–3.3) over a snapped scene:
// binning of front-facing triangles and silhouette edges into tiles, per-tile culling
// tests 1–6, clipping with both sides kept and the re-check of child polygons, occlusion
// of pieces by original opaque triangles, visible pieces rasterised into the id buffer.
//
// Canonical order (reproduced by every other producer): tiles in row-major order; in a
// tile, triangles in ascending setup order; a triangle's candidate edges in ascending
// silhouette id; the pieces of a triangle in the order split() leaves them (inside part
// before outside part, in place of their parent).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "tilevis/outputs.h"
#include "visibility/parallel.h"
#include "visibility/setup.h"
#include "visibility/svg.h"
#include "visibility/tile_resolver.h"

namespace tilevis::vis {

struct GoldenConfig {
  uint32_t tile_w = 32, tile_h = 32;
  // The tile resolver (tile_resolver.h): analytic, hybrid or per_pixel.
  std::string mode = "analytic";
  // The resolver's own options (occlusion bins, kept pieces, hybrid's budgets and detection
  // bins); their work_done is set by the tiler from `progress`.
  ResolverOptions options;
  // Called after binning with (0, total), then as tiles proceed with (done, total), in units
  // of estimated work: a tile weighs 1 + triangles x (edges + triangles), its pair tests and
  // occlusion tests, so a frame whose work sits in one overloaded tile still reports steady
  // progress. (Not called with per-triangle records.)
  std::function<void(uint64_t done, uint64_t total)> progress;
};

struct GoldenResult : FrameOutput {
  uint32_t width = 0, height = 0, samples = 1;
  outputs::TileTable tiles;  // TileCounters::columns(), then the resolver's extra columns
  uint64_t pair_tests = 0, candidate_pairs = 0, clip_polygons = 0, pieces_total = 0, visible_pieces = 0,
           occlusion_tests = 0, samples_covered = 0, fragments_generated = 0;
  uint64_t max_tile_triangles = 0, max_tile_edges = 0;
  // Tiles resolved per pixel by a mode that can fall back (hybrid), by cause, and the samples they cover.
  uint64_t fallback_tiles = 0, fallback_interpenetration = 0, fallback_non_opaque = 0, fallback_budget = 0,
           fallback_samples = 0;
  // Triangles binned to per-pixel tiles, and, in tiles that went for interpenetration, those
  // that cross another (what a fallback of triangle granularity would resolve per pixel).
  uint64_t fallback_triangles = 0, fallback_crossing_triangles = 0;
  uint64_t detection_screens = 0, detection_tests = 0;  // hybrid's detector, every tile (TileVerdict)
};

GoldenResult golden_visibility(const Setup& setup, const GoldenConfig& config);

// The golden pipeline in reusable pieces, for producers that add time to it (the SystemC
// model): bin() once, then process_tile() for any tile in any order. process_tile()
// writes the tile's row of `result.tiles`, its samples of `result.ids` and its triangles'
// visible areas exactly as golden_visibility() does; golden_visibility() is this class
// run over every tile in row-major order followed by sum_golden_totals().
class GoldenTiler {
 public:
  // Sizes result.ids, result.visible_area and result.tiles; `setup`, `config` and
  // `result` must outlive the tiler. Throws std::invalid_argument for an unknown mode.
  GoldenTiler(const Setup& setup, const GoldenConfig& config, GoldenResult& result);
  ~GoldenTiler();
  GoldenTiler(const GoldenTiler&) = delete;
  GoldenTiler& operator=(const GoldenTiler&) = delete;

  // Bins front-facing triangles and silhouette edges into tiles (exact overlap).
  void bin();
  const TileFrame& frame() const { return m_frame; }
  // tiles.csv columns the mode adds after TileCounters::columns().
  std::vector<std::string> extra_columns() const { return m_resolver->extra_columns(); }
  uint32_t tile_count() const { return m_frame.grid().tile_count(); }
  // After bin(): the tile's triangles as Setup::triangles indices, ascending.
  std::vector<uint32_t> tile_triangles(uint32_t tile) const;

  // Resolves one tile with the configured mode. With `per_triangle`, appends one record per
  // binned triangle (in processing order) whose counters sum to the tile's row. Returns the
  // verdict: with a mode that can fall back (hybrid), why the tile went per pixel (0: it did
  // not); per-pixel tiles' records count covered and owned samples only. With `added`, it
  // also gets the visible areas and triangles the tile adds to the result (as produced).
  TileVerdict process_tile(uint32_t tile, std::vector<TileTriangleWork>* per_triangle = nullptr,
                           TileOutput* added = nullptr);

  // Tiles process_tile() will be asked for, in about that order: resolved meanwhile on
  // host_threads() - 1 other threads (none: nothing happens), with per-triangle records or
  // without (as process_tile() will be asked). The result is the same bits: process_tile()
  // adds each tile's areas, pieces and counters to the result in the order it is called.
  void resolve_ahead(const std::vector<uint32_t>& tiles, bool per_triangle);

 private:
  struct Resolved;  // one tile's resolve, waiting for process_tile()
  void resolve(uint32_t tile, Resolved& r, TileResolver& resolver, bool per_triangle);

  GoldenConfig m_cfg;
  GoldenResult& m_r;
  TileFrame m_frame;
  std::unique_ptr<TileResolver> m_resolver;
  bool m_falls_back = false;  // the resolver adds per-pixel columns (hybrid)
  uint64_t m_work_done = 0, m_work_total = 0;
  bool m_report_progress = false;  // GoldenConfig::progress, not with per-triangle records
  // resolve_ahead(): a resolver per thread and one for the caller, and the threads (last:
  // stopped first).
  std::vector<std::unique_ptr<TileResolver>> m_thread_resolvers;
  bool m_ahead_per_triangle = false;
  std::unique_ptr<Ahead<Resolved>> m_ahead;
};

// Frame totals of `result` (pair_tests .. fragments_generated) from its tile rows.
void sum_golden_totals(GoldenResult& result);

}  // namespace tilevis::vis
