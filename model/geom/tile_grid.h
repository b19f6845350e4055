// The screen's tile grid: one value type for every producer (golden, truth, the SystemC
// model, the CUDA host side) and the command line. It owns the one valid tile range, the
// rectangle of each tile (cut at the screen's right and bottom edges) and the tile-range
// rule of binning: a closed sub-pixel box touches the tiles whose closed rectangles it meets.
#pragma once

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "geom/fixed.h"

namespace tilevis::geom {

struct TileGrid {
  // Tiles from 4 to 256 pixels a side: at 4K and 8 sub-pixel bits a tile's rectangle and the
  // screen stay inside the guard band, and no tile holds more than 2^16 pixels.
  static constexpr uint32_t kMinTile = 4, kMaxTile = 256;

  uint32_t width = 0, height = 0;   // screen, pixels
  uint32_t tile_w = 32, tile_h = 32;
  uint32_t subpixel_bits = kSubpixelBits;

  static constexpr bool valid_tile(uint32_t n) { return n >= kMinTile && n <= kMaxTile; }
  static std::string valid_range() { return "4 <= N <= 256"; }

  // Throws std::invalid_argument naming the bad value and the valid range.
  static TileGrid make(uint32_t width, uint32_t height, uint32_t tile_w, uint32_t tile_h,
                       uint32_t subpixel_bits = kSubpixelBits) {
    if (!valid_tile(tile_w) || !valid_tile(tile_h))
      throw std::invalid_argument("tile " + std::to_string(tile_w) + "x" + std::to_string(tile_h) + ": expected " +
                                  valid_range() + " on each side");
    if (width == 0 || height == 0) throw std::invalid_argument("tile grid: empty screen");
    return {width, height, tile_w, tile_h, subpixel_bits};
  }

  constexpr uint32_t tiles_x() const { return (width + tile_w - 1) / tile_w; }
  constexpr uint32_t tiles_y() const { return (height + tile_h - 1) / tile_h; }
  constexpr uint32_t tile_count() const { return tiles_x() * tiles_y(); }
  constexpr uint32_t tile_x(uint32_t tile) const { return tile % tiles_x(); }
  constexpr uint32_t tile_y(uint32_t tile) const { return tile / tiles_x(); }
  constexpr uint32_t tile_at_pixel(uint32_t px, uint32_t py) const { return (py / tile_h) * tiles_x() + px / tile_w; }

  // The tile's rectangle in sub-pixel units, cut at the screen's right and bottom edges: the
  // last column and row of tiles may reach past the screen, and nothing there is visible.
  constexpr Rect rect(uint32_t tx, uint32_t ty) const {
    const int32_t sb = int32_t(subpixel_bits);
    return {int32_t(tx * tile_w) << sb, int32_t(ty * tile_h) << sb, int32_t(std::min((tx + 1) * tile_w, width)) << sb,
            int32_t(std::min((ty + 1) * tile_h, height)) << sb};
  }
  constexpr Rect rect(uint32_t tile) const { return rect(tile_x(tile), tile_y(tile)); }

  // The tile-range rule: the tiles whose closed sub-pixel rectangles a closed box touches,
  // clamped to the screen's tiles (empty when the box is off screen).
  struct Range {
    int64_t tx0, ty0, tx1, ty1;
    uint32_t count() const { return tx1 < tx0 || ty1 < ty0 ? 0u : uint32_t((tx1 - tx0 + 1) * (ty1 - ty0 + 1)); }
  };
  Range range(const Rect& box) const {
    const int64_t tw = int64_t(tile_w) << subpixel_bits, th = int64_t(tile_h) << subpixel_bits;
    auto floor_div = [](int64_t a, int64_t d) { return a >= 0 ? a / d : -((-a + d - 1) / d); };
    return {std::max<int64_t>(0, floor_div(box.x0, tw)), std::max<int64_t>(0, floor_div(box.y0, th)),
            std::min<int64_t>(int64_t(tiles_x()) - 1, floor_div(box.x1, tw)),
            std::min<int64_t>(int64_t(tiles_y()) - 1, floor_div(box.y1, th))};
  }

  // Calls fn(tile, rect) for every tile of range(box), in row-major order.
  template <typename Fn>
  void for_tiles(const Rect& box, Fn&& fn) const {
    const Range r = range(box);
    for (int64_t ty = r.ty0; ty <= r.ty1; ++ty)
      for (int64_t tx = r.tx0; tx <= r.tx1; ++tx) fn(uint32_t(ty * tiles_x() + tx), rect(uint32_t(tx), uint32_t(ty)));
  }
};

}  // namespace tilevis::geom
