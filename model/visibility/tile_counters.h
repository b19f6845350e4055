// A tile's visibility counters (SVGPU Table 2 and more), or one triangle's share of them: the
// one definition behind tiles.csv's first columns, stats.json's totals, the model's
// per-triangle work and the CUDA reference's tile rows. Plain C++ (no model types), so that
// cuda_ref/ can use it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace tilevis::vis {

struct TileCounters {
  int64_t triangles = 0;            // front-facing triangles binned to the tile
  int64_t edges = 0;                // silhouette edges binned to the tile
  int64_t pair_tests = 0;           // triangle × edge pairs examined (after the test-6 depth sort)
  int64_t candidate_pairs = 0;      // pairs surviving tests 1–6 against the triangle's tile polygon
  int64_t clip_polygons = 0;        // splits performed (each makes two polygons from one)
  int64_t pieces = 0;               // polygons after clipping
  int64_t visible_pieces = 0;       // pieces not occluded
  int64_t occlusion_tests = 0;      // piece × occluder exact containment tests
  int64_t samples_covered = 0;      // samples covered by visible pieces (per pixel: samples owned)
  int64_t fragments_generated = 0;  // samples covered by all pieces (= by the tile's triangles)

  // Every field with its tiles.csv / stats.json name, in column order.
  using Field = std::pair<const char*, int64_t TileCounters::*>;
  static constexpr std::array<Field, 10> kFields = {{{"triangles", &TileCounters::triangles},
                                                     {"edges", &TileCounters::edges},
                                                     {"pair_tests", &TileCounters::pair_tests},
                                                     {"candidate_pairs", &TileCounters::candidate_pairs},
                                                     {"clip_polygons", &TileCounters::clip_polygons},
                                                     {"pieces", &TileCounters::pieces},
                                                     {"visible_pieces", &TileCounters::visible_pieces},
                                                     {"occlusion_tests", &TileCounters::occlusion_tests},
                                                     {"samples_covered", &TileCounters::samples_covered},
                                                     {"fragments_generated", &TileCounters::fragments_generated}}};
  static constexpr size_t kCount = kFields.size();

  static const std::vector<std::string>& columns() {
    static const std::vector<std::string> cols = [] {
      std::vector<std::string> c;
      for (const Field& f : kFields) c.emplace_back(f.first);
      return c;
    }();
    return cols;
  }

  // A row of kCount values in column order (tiles.csv, the CUDA tile rows) and back.
  void write(int64_t* row) const {
    for (size_t i = 0; i < kCount; ++i) row[i] = this->*kFields[i].second;
  }
  static TileCounters read(const int64_t* row) {
    TileCounters c;
    for (size_t i = 0; i < kCount; ++i) c.*kFields[i].second = row[i];
    return c;
  }
  static TileCounters read(const std::vector<int64_t>& row) {
    if (row.size() < kCount) throw std::invalid_argument("tile row has fewer than the counters' columns");
    return read(row.data());
  }

  TileCounters& operator+=(const TileCounters& o) {
    for (const Field& f : kFields) this->*f.second += o.*f.second;
    return *this;
  }
  TileCounters& operator-=(const TileCounters& o) {
    for (const Field& f : kFields) this->*f.second -= o.*f.second;
    return *this;
  }
  friend TileCounters operator+(TileCounters a, const TileCounters& b) { return a += b; }
  friend TileCounters operator-(TileCounters a, const TileCounters& b) { return a -= b; }
  friend bool operator==(const TileCounters&, const TileCounters&) = default;
};

// The shape of one triangle's analytic work beyond its counters: what sets its clocks in the
// early-visibility unit's RTL (rtl_ref/units; the model's cost functions,
// model/units/early_visibility_unit). Zero in per-pixel tiles.
struct EvuShape {
  uint32_t test6_stop = 0;        // 1: the walk over the depth-sorted edges ended on test 6, 0: at the list's end
  uint64_t split_edges = 0;       // edges of the parent polygon, summed over the triangle's splits
  uint64_t crossing_edges = 0;    // the same over the splits whose line crosses the parent (both children kept)
  uint64_t piece_checks = 0;      // tests 1-3 re-run on a piece against a candidate edge while clipping
  uint64_t pieces_tested = 0;     // pieces with at least one occluder test
};

}  // namespace tilevis::vis
