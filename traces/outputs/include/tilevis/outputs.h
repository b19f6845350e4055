// Canonical outputs (DESIGN.md): what golden, truth, the SystemC model and the CUDA
// reference all write, so that `tilevis compare` works on any two of them.
//
//   OUT/stats.json        {"tool", "trace", "frame", "config", "totals", "host_seconds", ...}
//   OUT/ids.exr           per sample, the id of the visible original triangle (UINT channels
//                         "id" or "id.s0".."id.sN"; 0xFFFFFFFF = background, i.e. -1)
//   OUT/overdraw.exr      per pixel, fragments generated (FLOAT channel "overdraw", summed over samples)
//   OUT/visible_area.bin  per original triangle, its exact visible area in pixels², as f64
//   OUT/tiles.csv         per tile counters, one row per tile, header row names the columns
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace tilevis::outputs {

inline constexpr int32_t kBackground = -1;

// A per-tile table: fixed leading columns (tx, ty) and named integer counters.
struct TileTable {
  uint32_t tile_w = 32, tile_h = 32, tiles_x = 0, tiles_y = 0;
  std::vector<std::string> columns;          // counter names, in order
  std::vector<std::vector<int64_t>> rows;    // tiles_x * tiles_y rows, row-major by (ty, tx)

  size_t column(const std::string& name) const;  // index or npos
  void resize(uint32_t tw, uint32_t th, uint32_t width, uint32_t height, std::vector<std::string> names);
  int64_t& at(uint32_t tile, size_t col) { return rows[tile][col]; }
};

struct Result {
  nlohmann::json stats;                      // stats.json as written (tool, trace, frame, config, totals, ...)
  uint32_t width = 0, height = 0, samples = 1;
  std::vector<int32_t> ids;                  // (y * width + x) * samples + s
  std::vector<float> overdraw;               // y * width + x (empty: not written)
  std::vector<double> visible_area;          // per original triangle (empty: not written)
  TileTable tiles;                           // (no rows: not written)
};

// Writes every present part into `dir` (created if needed). Each file is written to a
// temporary name and renamed, and stats.json last: a directory whose stats.json exists
// holds a complete result.
void write_result(const Result& result, const std::filesystem::path& dir);
// Reads what is present; throws std::runtime_error naming the file on bad content.
Result read_result(const std::filesystem::path& dir);

struct Comparison {
  uint64_t samples_compared = 0;             // samples where either producer covers
  uint64_t mismatched_samples = 0;
  double sample_agreement = 1.0;             // 1 - mismatched / compared (1 when nothing is covered)
  double max_area_rel_error = 0.0;           // over triangles with area in either (NaN if not both have areas)
  uint64_t area_mismatches = 0;              // triangles whose areas differ by more than 1e-9 relative
  uint64_t tile_counter_mismatches = 0;      // (tile, counter) cells that differ, over shared columns
  std::vector<std::string> compared_columns;
  nlohmann::json to_json() const;
};

// Throws std::runtime_error if the two results are not comparable (size, samples).
Comparison compare(const Result& a, const Result& b);

}  // namespace tilevis::outputs
