// Per-tile visibility, one home for every mode (DESIGN.md "Visibility modes").
//
// A TileFrame is a snapped scene prepared for tiles: its front-facing triangles and
// silhouette edges as the tile stage sees them, and their exact binning into the TileGrid.
// A TileResolver decides one tile of it: which triangle owns each sample of the tile, and
// the tile's counters (TileCounters). Resolvers are registered by mode name:
//   analytic   SVGPU §3.2-3.3: culling tests, clipping, occlusion of pieces (analytic_resolver.cpp)
//   per_pixel  the exact z-buffer (zbuffer.h) over the tile's triangles (per_pixel_resolver.cpp)
//   hybrid     per_pixel where the analytic answer can be wrong, else analytic (hybrid_resolver.cpp)
// A new mode is one file with a factory plus one line in the registry (tile_resolver.cpp).
//
// Producers drive them: golden_visibility() over every tile in row-major order, the SystemC
// model's EVU per tile as its units ask.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "geom/tile_grid.h"
#include "visibility/setup.h"
#include "visibility/svg.h"
#include "visibility/svgpu.h"
#include "visibility/tile_counters.h"

namespace tilevis::vis {

// A front-facing setup triangle as the tile stage sees it.
struct FrontTriangle : svgpu::Triangle {
  const SetupTriangle* t = nullptr;
  uint32_t setup_index = 0;  // index into Setup::triangles
};

class TileFrame {
 public:
  // `setup` must outlive the frame. Prepares the front-facing triangles and the edges.
  TileFrame(const Setup& setup, const geom::TileGrid& grid);

  // Bins front-facing triangles and silhouette edges into tiles (exact overlap).
  void bin();

  const Setup& setup() const { return m_s; }
  const geom::TileGrid& grid() const { return m_grid; }
  const std::vector<FrontTriangle>& triangles() const { return m_tris; }  // setup order
  const std::vector<svgpu::Edge>& edges() const { return m_edges; }       // Setup::silhouettes order
  // After bin(): the tile's triangles (ascending index into triangles()) and silhouette
  // edges (ascending index into edges()).
  const std::vector<uint32_t>& tile_triangles(uint32_t tile) const { return m_tile_tris[tile]; }
  const std::vector<uint32_t>& tile_edges(uint32_t tile) const { return m_tile_edges[tile]; }
  // The tile's opaque triangles (its possible occluders), nearest z_min first, ties in index order.
  void occluders(uint32_t tile, std::vector<uint32_t>& out) const;
  // The tile's triangle-edge pairs that test 6 lets through: per triangle, the edges whose
  // z_min is not beyond its z_max. From the binning alone: the analytic resolver's pair_tests
  // for the tile but for a triangle whose clipped polygon is empty (it tests none).
  uint64_t pair_tests(uint32_t tile) const;

 private:
  const Setup& m_s;
  geom::TileGrid m_grid;
  std::vector<FrontTriangle> m_tris;
  std::vector<svgpu::Edge> m_edges;
  std::vector<std::vector<uint32_t>> m_tile_tris, m_tile_edges;
};

// One binned triangle's share of its tile's counters (triangles and edges stay 0).
struct TileTriangleWork {
  uint32_t triangle = 0;  // index into Setup::triangles
  TileCounters counters;
  uint64_t shader_invocations = 0;  // pixels where it shades a sample, or samples at sample rate (zbuffer::PixelShades)
  EvuShape shape;
};

// The clip of one (tile, triangle) item whose chain of dependent steps is the longest when each
// piece is walked on its own (svgpu::WalkChain, 32 candidates a step): what bounds cuda_ref's
// k_clip_long on the frame's longest item. steps: that chain; work: all its walks' steps;
// chain_splits and splits: the steps of each that split a piece.
struct LongestWalk {
  uint64_t steps = 0, work = 0, candidates = 0, pieces = 0, chain_splits = 0, splits = 0;
  uint32_t tile = 0, setup_index = 0;  // the item: its tile, its triangle (setup order)
};

// What one tile's resolve produces besides its counters. The tile's samples go straight into
// the frame's ids (no two tiles share a sample, so tiles may be resolved on several threads at
// once); the rest waits here, in the order it was produced, until FrameOutput::add() takes it
// in the frame's tile order: a visible area is a sum of doubles, whose bits depend on its order.
struct TileOutput {
  int32_t* ids = nullptr;                          // the frame's ids (FrameOutput::ids)
  std::vector<std::pair<uint32_t, double>> areas;  // (original triangle id, pixels²) as produced
  std::vector<PlanarPiece> pieces;                 // visible pieces (ResolverOptions::keep_pieces)
  uint64_t visible_triangles = 0, shader_invocations = 0, max_tile_pieces = 0;
  LongestWalk longest_walk;  // of the tile's analytic items
};

// Where resolvers' tiles end up: frame-sized outputs shared by all tiles.
struct FrameOutput {
  std::vector<int32_t> ids;            // per sample, original triangle id; -1 background
  std::vector<double> visible_area;    // per original triangle id, pixels²
  std::vector<PlanarPiece> pieces;     // visible pieces as polygons (analytic tiles, ResolverOptions::keep_pieces)
  uint64_t visible_triangles = 0;      // visible pieces fan-triangulated (per-pixel tiles: none)
  uint64_t shader_invocations = 0;     // summed over triangles: the pixels where each shades some sample (MSAA)
  uint64_t max_tile_pieces = 0;        // most pieces of one triangle in one tile
  LongestWalk longest_walk;            // the analytic item with the longest clip chain (first in tile order)

  // An empty TileOutput writing into these ids.
  TileOutput tile_output() {
    TileOutput t;
    t.ids = ids.data();
    return t;
  }
  // Adds a resolved tile's areas, pieces and sums (its ids are already in place).
  void add(TileOutput&& tile);
};

// What a resolver reports about a tile besides its counters.
struct TileVerdict {
  // 0: resolved analytically; else why the tile went per pixel: kPerPixel* below.
  int per_pixel_cause = 0;
  // Interpenetration: how many of the tile's triangles cross another (the ones a fallback of
  // triangle granularity would send per pixel).
  uint32_t crossing_triangles = 0;
  // Hybrid's detector: triangle pairs screened (depth ranges and boxes compared), and those
  // past the screen whose planes it compared over their overlap.
  uint64_t detection_screens = 0, detection_tests = 0;
};
inline constexpr int kPerPixelInterpenetration = 1;  // two opaque triangles' planes cross inside their overlap
inline constexpr int kPerPixelNonOpaque = 2;         // a non-opaque triangle (it never occludes)
inline constexpr int kPerPixelBudget = 3;            // over the on-chip lists or the pair budget
inline constexpr int kPerPixelMode = 4;              // the per_pixel mode: every tile

struct ResolverOptions {
  // analytic: finer occlusion bins (SVGPU §4.1) of this many pixels, at most the tile (0: one
  // bin per tile). Only the scanning of occluders shrinks; results and counters are those of
  // one bin. 8: the host's fastest on the built-in scenes (million golden 1.44 -> 1.05 s of CPU).
  uint32_t occlusion_bin_w = 8, occlusion_bin_h = 8;
  bool keep_pieces = false;  // analytic: collect visible pieces (SVG)
  // hybrid: a tile whose triangles x edges exceed this goes per pixel (0: no budget).
  uint64_t pair_budget = 0;
  // hybrid: a tile with more triangles or silhouette edges than the early-visibility unit's
  // on-chip lists hold goes per pixel (0: no limit). Defaults: the model's evu.*_list_entries.
  uint32_t list_triangles = 512, list_edges = 256;
  // hybrid: the detector compares triangle pairs within square bins of this many pixels
  // (0: the whole tile). Only its work changes, not its verdict.
  uint32_t detection_bin = 8;
  // Called with units of work done as the tile proceeds (a triangle of an analytic tile
  // weighs edges + triangles of the tile), so one overloaded tile still shows progress.
  std::function<void(uint64_t)> work_done;
};

class TileResolver {
 public:
  virtual ~TileResolver() = default;
  // Decides tile `tile` of `frame` (after bin()): writes the tile's samples of out.ids and
  // appends its triangles' visible areas to out.areas, adds the tile's work to `counters` (triangles and edges
  // are the caller's), and with `per_triangle` appends one record per binned triangle, in
  // processing order, whose counters sum to what was added.
  // A resolver holds scratch: one per thread.
  virtual TileVerdict resolve(const TileFrame& frame, uint32_t tile, TileOutput& out, TileCounters& counters,
                              std::vector<TileTriangleWork>* per_triangle) = 0;
  // tiles.csv columns the mode adds after TileCounters::columns() (hybrid: per_pixel, per_pixel_cause).
  virtual std::vector<std::string> extra_columns() const { return {}; }
  // Writes those columns' values for a tile with `verdict` at row + 0, 1, ...
  virtual void write_extra(const TileVerdict&, int64_t* /*row*/) const {}
};

// The registered modes, in registration order.
const std::vector<std::string>& tile_resolver_modes();
// A resolver for `mode`; throws std::invalid_argument naming the registered modes.
std::unique_ptr<TileResolver> make_tile_resolver(std::string_view mode, const ResolverOptions& options);

// Factories of the registered modes (one per file).
std::unique_ptr<TileResolver> make_analytic_resolver(const ResolverOptions&);
std::unique_ptr<TileResolver> make_per_pixel_resolver(const ResolverOptions&);
std::unique_ptr<TileResolver> make_hybrid_resolver(const ResolverOptions&);

}  // namespace tilevis::vis
