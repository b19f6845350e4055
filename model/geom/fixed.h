// Snapping of window coordinates to the fixed-point grid every exact predicate works on.
// Numbers (DESIGN.md): x,y in 16.8 fixed point (D3D11 §15.16), depth an unsigned D-bit integer.
#pragma once

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <optional>

namespace tilevis::geom {

inline constexpr int kSubpixelBits = 8;
inline constexpr int32_t kSubpixelScale = 1 << kSubpixelBits;

// Guard band: |x|,|y| < 2^15 pixels, i.e. |X| <= 2^23 - 1 sub-pixel units after snapping.
// The predicates accept |X| <= 2^23 (kCoordLimit) so that tile-rectangle corners on the
// band's edge are legal too; every bit bound in predicates.h/depth.h uses 2^23.
inline constexpr int kGuardBandBits = 23;
inline constexpr int32_t kGuardBandLimit = int32_t{1} << kGuardBandBits;
inline constexpr int32_t kCoordLimit = kGuardBandLimit;

inline constexpr int kDefaultDepthBits = 24;
inline constexpr int kMaxDepthBits = 32;

// A snapped 2-D point, also the type of a sample position (integer sub-pixel units).
struct Point {
  int32_t x = 0, y = 0;
  friend constexpr bool operator==(Point, Point) = default;
};

struct Vertex {
  int32_t x = 0, y = 0;
  uint32_t z = 0;
  constexpr Point xy() const { return {x, y}; }
  friend constexpr bool operator==(const Vertex&, const Vertex&) = default;
};

struct Triangle {
  std::array<Vertex, 3> v;
};

// Axis-aligned rectangle in sub-pixel units, x0 < x1, y0 < y1, corners within kCoordLimit.
// As a tile it owns the samples of [x0, x1) x [y0, y1) (the tie rule of predicates.h applied
// to its four edges); overlap tests treat it as a closed set and ignore zero-area contact.
struct Rect {
  int32_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  friend constexpr bool operator==(const Rect&, const Rect&) = default;
};

// Tile (tx, ty) of tile_w x tile_h pixels, in sub-pixel units.
constexpr Rect tile_rect(int32_t tx, int32_t ty, int32_t tile_w, int32_t tile_h) {
  return {tx * tile_w * kSubpixelScale, ty * tile_h * kSubpixelScale, (tx + 1) * tile_w * kSubpixelScale,
          (ty + 1) * tile_h * kSubpixelScale};
}

constexpr bool in_guard_band(int64_t coord) {
  return coord > -kGuardBandLimit && coord < kGuardBandLimit;
}

// Window coordinate in pixels -> 16.8, rounding to nearest, ties to even (as the hardware's
// float-to-fixed converter does), independent of the FPU rounding mode. Out of band, NaN
// and infinities give nullopt: the caller reports them, nothing wraps.
inline std::optional<int32_t> snap_coord(float window_coord) {
  // Exact: a float's 24-bit significand scaled by 2^8 is representable in a double.
  const double d = static_cast<double>(window_coord) * kSubpixelScale;
  if (!(std::fabs(d) < 2.0 * kGuardBandLimit)) return std::nullopt;
  const double fl = std::floor(d);
  const double frac = d - fl;  // exact: |d| < 2^24
  int64_t r = static_cast<int64_t>(fl);
  if (frac > 0.5 || (frac == 0.5 && (r & 1) != 0)) ++r;
  if (!in_guard_band(r)) return std::nullopt;
  return static_cast<int32_t>(r);
}

// Depth in [0,1] -> unsigned integer in [0, 2^D - 1]: clamp (NaN -> 0), then
// round(z * (2^D - 1)) to nearest, ties to even. Computed on the float's integer significand
// (m * (2^D - 1) < 2^24 * 2^32 = 2^56 fits uint64), so it is exact for D up to 32, where a
// double product would not be. Precondition: 1 <= depth_bits <= 32.
inline uint32_t snap_depth(float z, int depth_bits) {
  const uint64_t max_value = (uint64_t{1} << depth_bits) - 1;
  if (!(z > 0.0f)) return 0;
  if (z >= 1.0f) return static_cast<uint32_t>(max_value);
  const uint32_t bits = std::bit_cast<uint32_t>(z);
  const uint32_t biased_exp = (bits >> 23) & 0xffu;
  uint64_t significand = bits & 0x7fffffu;
  int shift;  // z = significand * 2^-shift
  if (biased_exp == 0) {
    shift = 149;
  } else {
    significand |= uint64_t{1} << 23;
    shift = 150 - static_cast<int>(biased_exp);  // z < 1 -> biased_exp <= 126 -> shift >= 24
  }
  const uint64_t product = significand * max_value;  // < 2^56
  if (shift >= 58) return 0;                         // product * 2^-shift < 2^-2
  uint64_t q = product >> shift;
  const uint64_t rem = product & ((uint64_t{1} << shift) - 1);
  const uint64_t half = uint64_t{1} << (shift - 1);
  if (rem > half || (rem == half && (q & 1) != 0)) ++q;
  return static_cast<uint32_t>(q);
}

inline std::optional<Vertex> snap_vertex(float x, float y, float z, int depth_bits) {
  const auto sx = snap_coord(x);
  const auto sy = snap_coord(y);
  if (!sx || !sy) return std::nullopt;
  return Vertex{*sx, *sy, snap_depth(z, depth_bits)};
}

}  // namespace tilevis::geom
