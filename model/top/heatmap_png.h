// A per-tile heatmap as PNG (libpng): one block of `scale` x `scale` pixels per tile, the
// viridis colour map from 0 (dark violet) to the largest value (yellow), linear. The
// largest value and the quantity's name go into tEXt chunks ("Title", "Maximum"), so the
// image states its own scale.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace tilevis::sim {

// Viridis at t in [0, 1] (clamped), interpolated between nine samples of the map.
std::array<uint8_t, 3> viridis(double t);

// The block size that makes the longer side about `target` pixels (at least 1).
uint32_t heatmap_scale(uint32_t tiles_x, uint32_t tiles_y, uint32_t target = 960);

// values: tiles_x * tiles_y, row-major from the top-left tile. Writes through a temporary
// file and a rename; throws std::runtime_error on failure.
void write_heatmap_png(const std::filesystem::path& file, const std::vector<double>& values, uint32_t tiles_x,
                       uint32_t tiles_y, const std::string& title);

}  // namespace tilevis::sim
