// The visible planar map as SVG: the resolution-independent output SVGPU was made for.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

namespace tilevis::vis {

struct PlanarPiece {
  uint32_t id;                          // original triangle
  uint32_t draw;
  float shade;                          // 0..1, e.g. from the triangle's facing angle or depth
  std::vector<double> xy;               // polygon vertices, window pixels (y down): x0, y0, x1, y1, ...
};

// Writes an SVG of width × height pixels, one <path> per visible piece, filled by draw
// and shade, with hairline outlines so the clipping is visible when zoomed in.
void write_svg(const std::filesystem::path& file, uint32_t width, uint32_t height,
               const std::vector<PlanarPiece>& pieces);

}  // namespace tilevis::vis
