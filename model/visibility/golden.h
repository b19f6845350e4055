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
#include <vector>

#include "tilevis/outputs.h"
#include "visibility/setup.h"
#include "visibility/svg.h"

namespace tilevis::vis {

struct GoldenConfig {
  uint32_t tile_w = 32, tile_h = 32;
  // Finer occlusion bins (SVGPU §4.1): each tile's occluder list split over bins of this many
  // pixels (0: one bin per tile). A piece scans only the bin of its interior point, whose
  // list holds every occluder whose bounding-box test could pass there, in the same order:
  // results and counters are those of one bin per tile; only the scanning shrinks.
  uint32_t occlusion_bin_w = 0, occlusion_bin_h = 0;
  bool keep_pieces = false;  // collect visible pieces as polygons (for SVG)
  // Hybrid visibility (DESIGN.md "Visibility modes"): a tile goes per pixel (an exact
  // z-buffer over its triangles, the truth's rule) where the analytic answer can be wrong:
  // two opaque triangles whose planes cross inside their overlap (interpenetration, found
  // with exact predicates), a non-opaque or per-pixel-only triangle (they never occlude, so
  // their samples are the z-buffer's), or estimated work over `hybrid_pair_budget` pair
  // tests (triangles x edges; 0: no budget). The other tiles are resolved analytically.
  bool hybrid = false;
  uint64_t hybrid_pair_budget = 0;
  // Called after binning with (0, total), then after every triangle of every tile with
  // (done, total), in units of estimated work: a tile weighs 1 + triangles x (edges +
  // triangles), its pair tests and occlusion tests, so a frame whose work sits in one
  // overloaded tile still reports steady progress. (Not called with per-triangle records.)
  std::function<void(uint64_t done, uint64_t total)> progress;
};

// A tile's counters (SVGPU Table 2 and more), or one triangle's share of them: the one
// definition behind tiles.csv's first columns, the model's per-triangle work and stats.json.
struct TileCounters {
  int64_t triangles = 0;            // front-facing triangles binned to the tile
  int64_t edges = 0;                // silhouette edges binned to the tile
  int64_t pair_tests = 0;           // triangle × edge pairs examined (after the test-6 depth sort)
  int64_t candidate_pairs = 0;      // pairs surviving tests 1–6 against the triangle's tile polygon
  int64_t clip_polygons = 0;        // splits performed (each makes two polygons from one)
  int64_t pieces = 0;               // polygons after clipping
  int64_t visible_pieces = 0;       // pieces not occluded
  int64_t occlusion_tests = 0;      // piece × occluder exact containment tests
  int64_t samples_covered = 0;      // samples covered by visible pieces
  int64_t fragments_generated = 0;  // samples covered by all pieces (= by the tile's triangles)

  static constexpr size_t kCount = 10;
  // Column names in member order (tiles.csv).
  static const std::vector<std::string>& columns() {
    static const std::vector<std::string> cols = {"triangles",      "edges",           "pair_tests",
                                                  "candidate_pairs", "clip_polygons",   "pieces",
                                                  "visible_pieces",  "occlusion_tests", "samples_covered",
                                                  "fragments_generated"};
    return cols;
  }
  void add_to(int64_t* row) const {
    const int64_t v[kCount] = {triangles,      edges,          pair_tests,      candidate_pairs, clip_polygons,
                               pieces,         visible_pieces, occlusion_tests, samples_covered, fragments_generated};
    for (size_t i = 0; i < kCount; ++i) row[i] += v[i];
  }
  static TileCounters from(const int64_t* row) {
    return {row[0], row[1], row[2], row[3], row[4], row[5], row[6], row[7], row[8], row[9]};
  }
  // Member-wise sum and difference (a triangle's share is the tile's counters after it minus before).
  friend TileCounters operator+(const TileCounters& a, const TileCounters& b) { return combine(a, b, 1); }
  friend TileCounters operator-(const TileCounters& a, const TileCounters& b) { return combine(a, b, -1); }

 private:
  static TileCounters combine(const TileCounters& a, const TileCounters& b, int64_t sign) {
    int64_t ra[kCount] = {}, rb[kCount] = {};
    a.add_to(ra);
    b.add_to(rb);
    for (size_t i = 0; i < kCount; ++i) ra[i] += sign * rb[i];
    return from(ra);
  }
};

inline const std::vector<std::string>& golden_tile_columns() { return TileCounters::columns(); }

struct GoldenResult {
  uint32_t width = 0, height = 0, samples = 1;
  std::vector<int32_t> ids;                 // per sample, -1 background
  std::vector<double> visible_area;         // per original triangle id, pixels²
  outputs::TileTable tiles;
  std::vector<PlanarPiece> pieces;          // visible pieces, when keep_pieces
  uint64_t pair_tests = 0, candidate_pairs = 0, clip_polygons = 0, pieces_total = 0, visible_pieces = 0,
           occlusion_tests = 0, samples_covered = 0, fragments_generated = 0;
  uint64_t visible_triangles = 0;  // visible pieces fan-triangulated (SVGPU Fig. 6 counts output triangles)
  uint64_t max_tile_triangles = 0, max_tile_edges = 0, max_tile_pieces = 0;
  // Hybrid: tiles resolved per pixel, by cause, and the samples they cover.
  uint64_t fallback_tiles = 0, fallback_interpenetration = 0, fallback_non_opaque = 0, fallback_budget = 0,
           fallback_samples = 0;
};

// Extra tiles.csv columns of hybrid runs, after golden_tile_columns(): 1 where the tile
// went per pixel, and why (1 interpenetration, 2 non-opaque content, 3 work budget).
inline const std::vector<std::string>& hybrid_tile_columns() {
  static const std::vector<std::string> cols = {"per_pixel", "per_pixel_cause"};
  return cols;
}

GoldenResult golden_visibility(const Setup& setup, const GoldenConfig& config);

// One front-facing triangle's share of a tile's counters (triangles and edges stay 0).
struct TileTriangleWork {
  uint32_t triangle = 0;  // index into Setup::triangles
  TileCounters counters;
};

// The golden pipeline in reusable pieces, for producers that add time to it (the SystemC
// model): bin() once, then process_tile() for any tile in any order. process_tile()
// writes the tile's row of `result.tiles`, its samples of `result.ids` and its triangles'
// visible areas exactly as golden_visibility() does; golden_visibility() is this class
// run over every tile in row-major order followed by sum_totals().
class GoldenTiler {
 public:
  // Sizes result.ids, result.visible_area and result.tiles; `setup`, `config` and
  // `result` must outlive the tiler.
  GoldenTiler(const Setup& setup, const GoldenConfig& config, GoldenResult& result);
  ~GoldenTiler();
  GoldenTiler(const GoldenTiler&) = delete;
  GoldenTiler& operator=(const GoldenTiler&) = delete;

  // Bins front-facing triangles and silhouette edges into tiles (exact overlap).
  void bin();
  uint32_t tiles_x() const;
  uint32_t tiles_y() const;
  uint32_t tile_count() const { return tiles_x() * tiles_y(); }
  // After bin(): the tile's triangles (ascending Setup::triangles index) and silhouette
  // edges (ascending Setup::silhouettes index).
  std::vector<uint32_t> tile_triangles(uint32_t tile) const;
  const std::vector<uint32_t>& tile_edges(uint32_t tile) const;
  // Number of the tile's triangles without building the list.
  size_t tile_triangle_count(uint32_t tile) const;

  // Runs SVGPU §3.2–3.3 on one tile. With `per_triangle`, appends one record per binned
  // triangle (in processing order) whose counters sum to the tile's row. Returns 0, or with
  // GoldenConfig::hybrid the cause of the tile's per-pixel fallback (hybrid_tile_columns()),
  // whose records count covered and owned samples only.
  int process_tile(uint32_t tile, std::vector<TileTriangleWork>* per_triangle = nullptr);

 private:
  class Impl;
  std::unique_ptr<Impl> m_impl;
};

// Frame totals of `result` (pair_tests .. fragments_generated) from its tile rows.
void sum_golden_totals(GoldenResult& result);

}  // namespace tilevis::vis
