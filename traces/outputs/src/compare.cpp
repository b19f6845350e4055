#include <cmath>
#include <limits>
#include <stdexcept>

#include "tilevis/outputs.h"

namespace tilevis::outputs {

nlohmann::json Comparison::to_json() const {
  return {{"sample_agreement", sample_agreement},
          {"samples_compared", samples_compared},
          {"mismatched_samples", mismatched_samples},
          {"max_area_rel_error", std::isnan(max_area_rel_error) ? nlohmann::json(nullptr) : nlohmann::json(max_area_rel_error)},
          {"area_mismatches", area_mismatches},
          {"tile_counter_mismatches", tile_counter_mismatches},
          {"compared_tile_columns", compared_columns}};
}

Comparison compare(const Result& a, const Result& b) {
  Comparison c;
  if (a.ids.empty() || b.ids.empty())
    throw std::runtime_error(std::string(a.ids.empty() ? "the first" : "the second") +
                             " result has no ids.exr: compare needs both id buffers");
  if (a.width != b.width || a.height != b.height || a.samples != b.samples)
    throw std::runtime_error("results differ in size or samples: " + std::to_string(a.width) + "x" +
                             std::to_string(a.height) + "x" + std::to_string(a.samples) + " vs " +
                             std::to_string(b.width) + "x" + std::to_string(b.height) + "x" + std::to_string(b.samples));
  for (size_t i = 0; i < a.ids.size(); ++i) {
    if (a.ids[i] == kBackground && b.ids[i] == kBackground) continue;
    ++c.samples_compared;
    c.mismatched_samples += a.ids[i] != b.ids[i];
  }
  c.sample_agreement = c.samples_compared ? 1.0 - double(c.mismatched_samples) / double(c.samples_compared) : 1.0;

  if (a.visible_area.empty() || b.visible_area.empty() || a.visible_area.size() != b.visible_area.size()) {
    c.max_area_rel_error = std::numeric_limits<double>::quiet_NaN();
  } else {
    for (size_t i = 0; i < a.visible_area.size(); ++i) {
      double x = a.visible_area[i], y = b.visible_area[i];
      double scale = std::max(std::fabs(x), std::fabs(y));
      if (scale == 0) continue;
      double rel = std::fabs(x - y) / scale;
      c.max_area_rel_error = std::max(c.max_area_rel_error, rel);
      c.area_mismatches += rel > 1e-9;
    }
  }

  const TileTable &ta = a.tiles, &tb = b.tiles;
  if (!ta.rows.empty() && !tb.rows.empty() && ta.tiles_x == tb.tiles_x && ta.tiles_y == tb.tiles_y) {
    for (size_t ca = 0; ca < ta.columns.size(); ++ca) {
      size_t cb = tb.column(ta.columns[ca]);
      if (cb == std::string::npos) continue;
      c.compared_columns.push_back(ta.columns[ca]);
      for (size_t r = 0; r < ta.rows.size(); ++r) c.tile_counter_mismatches += ta.rows[r][ca] != tb.rows[r][cb];
    }
  }
  return c;
}

}  // namespace tilevis::outputs
