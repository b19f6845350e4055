// cuda_ref against the golden pipeline: what differs, counted.
#pragma once

#include <cstdint>
#include <string>

#include <gtest/gtest.h>

#include "tilevis/cuda_ref.h"
#include "visibility/truth.h"
#include "visibility/golden.h"
#include "visibility/setup.h"

namespace tilevis::cudatest {

struct Diff {
  uint64_t samples_compared = 0, id_mismatches = 0, tile_cells = 0, tile_cell_mismatches = 0, area_bit_mismatches = 0,
           area_mismatches = 0;  // > 1e-9 relative
  std::string first_tile_mismatch;
  bool totals_equal = true;
  std::string totals;
  double agreement() const { return samples_compared ? 1.0 - double(id_mismatches) / double(samples_compared) : 1.0; }
};

// Equal to golden bit for bit: ids, every tile cell, every area, the totals.
inline void expect_bit_identical(const Diff& d) {
  EXPECT_GT(d.samples_compared, 0u);
  EXPECT_EQ(d.id_mismatches, 0u);
  EXPECT_EQ(d.tile_cell_mismatches, 0u) << d.first_tile_mismatch;
  EXPECT_EQ(d.area_bit_mismatches, 0u);
  EXPECT_TRUE(d.totals_equal) << d.totals;
}

// The z-buffer truth's ids (exact depth), for the CUDA z-buffer rasterisers.
inline std::vector<int32_t> truth_ids_of(const trace::Frame& f) {
  const vis::Setup s = vis::primitive_setup(f, {});
  return vis::zbuffer_truth(s, {}).ids;
}

inline vis::GoldenResult golden_of(const trace::Frame& f, uint32_t tile_w, uint32_t tile_h,
                                   const std::string& mode = "analytic", const cuda::CudaConfig* budget = nullptr) {
  vis::Setup s = vis::primitive_setup(f, {});
  vis::GoldenConfig gc;
  gc.tile_w = tile_w;
  gc.tile_h = tile_h;
  gc.mode = mode;
  if (budget) {  // hybrid's budget and lists as the CUDA run's
    gc.options.pair_budget = budget->pair_budget;
    gc.options.list_triangles = budget->list_triangles;
    gc.options.list_edges = budget->list_edges;
  }
  return vis::golden_visibility(s, gc);
}

// Hybrid with lists small enough that the built-in scenes' busier tiles go per pixel for the
// budget (cause 3), which culling then skips.
inline void small_lists(cuda::CudaConfig& cfg) {
  cfg.list_triangles = 6;
  cfg.list_edges = 4;
  cfg.pair_budget = 20;
}

inline Diff diff(const vis::GoldenResult& g, const cuda::CudaResult& c) {
  Diff d;
  for (size_t i = 0; i < g.ids.size() && i < c.ids.size(); ++i) {
    if (g.ids[i] < 0 && c.ids[i] < 0) continue;
    ++d.samples_compared;
    d.id_mismatches += g.ids[i] != c.ids[i];
  }
  if (g.ids.size() != c.ids.size()) d.id_mismatches += 1000000000;
  for (size_t t = 0; t < g.tiles.rows.size(); ++t)
    for (size_t k = 0; k < g.tiles.rows[t].size(); ++k) {
      ++d.tile_cells;
      int64_t cv = t < c.tiles.size() && k < vis::TileCounters::kCount ? c.tiles[t].*vis::TileCounters::kFields[k].second : -1;
      // Hybrid's columns (per_pixel, per_pixel_cause, detection_screens, detection_tests).
      const std::string& col = g.tiles.columns[k];
      if (k >= vis::TileCounters::kCount && t < c.per_pixel_cause.size()) {
        if (col == "per_pixel") cv = c.per_pixel_cause[t] != 0;
        if (col == "per_pixel_cause") cv = c.per_pixel_cause[t];
        if (col == "detection_screens") cv = int64_t(c.detection_screens[t]);
        if (col == "detection_tests") cv = int64_t(c.detection_tests[t]);
      }
      if (g.tiles.rows[t][k] == cv) continue;
      if (!d.tile_cell_mismatches)
        d.first_tile_mismatch = "tile " + std::to_string(t) + " " + g.tiles.columns[k] + ": golden " +
                                std::to_string(g.tiles.rows[t][k]) + ", cuda " + std::to_string(cv);
      ++d.tile_cell_mismatches;
    }
  for (size_t i = 0; i < g.visible_area.size() && i < c.visible_area.size(); ++i) {
    const double x = g.visible_area[i], y = c.visible_area[i];
    d.area_bit_mismatches += x != y;
    const double scale = std::max(std::abs(x), std::abs(y));
    if (scale > 0 && std::abs(x - y) / scale > 1e-9) ++d.area_mismatches;
  }
  auto both = [&](const char* name, uint64_t a, uint64_t b) {
    if (a != b) {
      d.totals_equal = false;
      d.totals += std::string(name) + " " + std::to_string(a) + " vs " + std::to_string(b) + "; ";
    }
  };
  both("pair_tests", g.pair_tests, c.pair_tests);
  both("candidate_pairs", g.candidate_pairs, c.candidate_pairs);
  both("clip_polygons", g.clip_polygons, c.clip_polygons);
  both("pieces", g.pieces_total, c.pieces);
  both("visible_pieces", g.visible_pieces, c.visible_pieces);
  both("visible_triangles", g.visible_triangles, c.visible_triangles);
  both("occlusion_tests", g.occlusion_tests, c.occlusion_tests);
  both("samples_covered", g.samples_covered, c.samples_covered);
  both("fragments_generated", g.fragments_generated, c.fragments_generated);
  if (c.samples == 1) both("fragments_shaded", g.shader_invocations, c.fragments_shaded);
  both("max_tile_triangles", g.max_tile_triangles, c.max_tile_triangles);
  both("max_tile_edges", g.max_tile_edges, c.max_tile_edges);
  both("max_tile_pieces", g.max_tile_pieces, c.max_tile_pieces);
  if (!c.per_pixel_cause.empty()) {
    uint64_t tiles = 0, crossing = 0, screens = 0, tests = 0, by_cause[4] = {0, 0, 0, 0}, samples = 0, triangles = 0;
    for (size_t t = 0; t < c.per_pixel_cause.size(); ++t) {
      tiles += c.per_pixel_cause[t] != 0;
      if (c.per_pixel_cause[t] != 0 && c.per_pixel_cause[t] < 4) ++by_cause[c.per_pixel_cause[t]];
      if (c.per_pixel_cause[t] != 0 && t < c.tiles.size()) {
        samples += uint64_t(c.tiles[t].samples_covered);
        triangles += uint64_t(c.tiles[t].triangles);
      }
      crossing += c.crossing_triangles[t];
      screens += c.detection_screens[t];
      tests += c.detection_tests[t];
    }
    both("fallback_tiles", g.fallback_tiles, tiles);
    both("fallback_interpenetration", g.fallback_interpenetration, by_cause[vis::kPerPixelInterpenetration]);
    both("fallback_non_opaque", g.fallback_non_opaque, by_cause[vis::kPerPixelNonOpaque]);
    both("fallback_budget", g.fallback_budget, by_cause[vis::kPerPixelBudget]);
    both("fallback_samples", g.fallback_samples, samples);
    both("fallback_triangles", g.fallback_triangles, triangles);
    both("fallback_crossing_triangles", g.fallback_crossing_triangles, crossing);
    both("detection_screens", g.detection_screens, screens);
    both("detection_tests", g.detection_tests, tests);
  }
  return d;
}

inline cuda::CudaConfig config(cuda::Device device, cuda::Precision precision, uint32_t tile_w, uint32_t tile_h) {
  cuda::CudaConfig c;
  c.device = device;
  c.precision = precision;
  c.tile_w = tile_w;
  c.tile_h = tile_h;
  c.runs = 1;
  c.warmup = 1;
  return c;
}

}  // namespace tilevis::cudatest
