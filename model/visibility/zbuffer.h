// The exact z-buffer rule, the one definition every per-pixel producer shares: the z-buffer
// truth, the per_pixel tile resolver (hybrid's fallback tiles) and the model's HSR, early-Z
// and immediate paths. A triangle covers a sample by the top-left rule at the sample's
// snapped position; it passes the depth test where it is strictly nearer than the sample's
// owner (exact plane comparison), so at equal depth the earlier-submitted triangle keeps
// the sample, as under a less-than depth test.
#pragma once

#include <algorithm>
#include <cstdint>

#include "geom/depth.h"
#include "geom/predicates.h"
#include "geom/tile_grid.h"
#include "visibility/setup.h"
#include "visibility/svgpu.h"

namespace tilevis::vis::zbuffer {

// A half-open rectangle of pixels: [x0, x1) x [y0, y1).
struct PixelRect {
  uint32_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

inline PixelRect whole_frame(const Setup& s) { return {0, 0, s.width, s.height}; }
// The pixels of a tile, cut at the screen's right and bottom edges.
inline PixelRect tile_pixels(const geom::TileGrid& g, uint32_t tile) {
  const uint32_t x0 = g.tile_x(tile) * g.tile_w, y0 = g.tile_y(tile) * g.tile_h;
  return {x0, y0, std::min(x0 + g.tile_w, g.width), std::min(y0 + g.tile_h, g.height)};
}

// Sample k of pixel (px, py), in sub-pixel units.
inline geom::Point sample_point(const Setup& s, int64_t px, int64_t py, uint32_t k) {
  return {int32_t((px << s.subpixel_bits) + s.samples[k].x), int32_t((py << s.subpixel_bits) + s.samples[k].y)};
}

// Index of sample k of pixel (px, py) in a frame-sized per-sample array.
inline size_t sample_index(const Setup& s, uint32_t px, uint32_t py, uint32_t k) {
  return (size_t(py) * s.width + px) * s.samples.size() + k;
}

// Calls visit(px, py, k, point) for every sample k of a pixel (px, py) of `region` that the
// triangle covers, in row-major pixel order and sample order within a pixel.
template <typename Visit>
void for_covered_samples(const Setup& s, const svgpu::Triangle& t, PixelRect region, Visit&& visit) {
  const int32_t sb = int32_t(s.subpixel_bits);
  const uint32_t ns = uint32_t(s.samples.size());
  const int64_t px0 = std::max<int64_t>(region.x0, t.bbox.x0 >> sb);
  const int64_t px1 = std::min<int64_t>(int64_t(std::min(region.x1, s.width)) - 1, t.bbox.x1 >> sb);
  const int64_t py0 = std::max<int64_t>(region.y0, t.bbox.y0 >> sb);
  const int64_t py1 = std::min<int64_t>(int64_t(std::min(region.y1, s.height)) - 1, t.bbox.y1 >> sb);
  for (int64_t py = py0; py <= py1; ++py)
    for (int64_t px = px0; px <= px1; ++px)
      for (uint32_t k = 0; k < ns; ++k) {
        const geom::Point p = sample_point(s, px, py, k);
        if (t.edges.covers(p)) visit(uint32_t(px), uint32_t(py), k, p);
      }
}

// Shader invocations under MSAA: a triangle's fragment shader runs once per pixel in which
// it shades any sample (the coverage mask says which samples take the result), as MSAA
// hardware does. Counts the distinct pixels of one triangle's samples visited pixel by pixel
// (for_covered_samples' order); start a new count for every triangle.
struct PixelShades {
  explicit PixelShades(bool sample_rate = false) : per_sample(sample_rate) {}
  bool per_sample;  // a draw shading at sample rate (trace::kSampleRateShading) runs per sample
  uint64_t count = 0;
  size_t last = SIZE_MAX;
  void add(uint32_t px, uint32_t py, uint32_t width) {
    const size_t pixel = size_t(py) * width + px;
    if (per_sample || pixel != last) ++count, last = pixel;
  }
};

// The shader invocations a pixel's owners cost, from the first n entries of its samples
// (n <= 16), skipping `none`: fn(owner) once per distinct owner, or once per sample it owns
// where sample_rate(owner) (its draw shades at sample rate).
template <typename T, typename Rate, typename Fn>
void for_invocations(const T* samples, uint32_t n, T none, Rate&& sample_rate, Fn&& fn) {
  for (uint32_t k = 0; k < n; ++k) {
    if (samples[k] == none) continue;
    bool seen = false;
    if (!sample_rate(samples[k]))
      for (uint32_t j = 0; j < k && !seen; ++j) seen = samples[j] == samples[k];
    if (!seen) fn(samples[k]);
  }
}

// The depth test: does a triangle with plane `t` pass against the sample's owner `owner`?
inline bool passes(const geom::DepthPlane& t, const geom::DepthPlane& owner, geom::Point p) {
  return geom::depth_order(t, owner, p) < 0;
}

}  // namespace tilevis::vis::zbuffer
