// Snapping of window coordinates to the fixed-point grid every exact predicate works on.
// Numbers (DESIGN.md): x,y in 16.8 fixed point (D3D11 §15.16), depth an unsigned D-bit integer.
#pragma once

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <optional>

#include "geom/wide_int.h"

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

// Window coordinate in pixels -> fixed point with `subpixel_bits` fractional bits (16.8 by
// default), rounding to nearest, ties to even (as the hardware's float-to-fixed converter
// does), independent of the FPU rounding mode. Out of band, NaN and infinities give nullopt:
// the caller reports them, nothing wraps. Float inputs convert to double exactly, so a
// float window coordinate snaps as it would on its own.
inline std::optional<int32_t> snap_coord(double window_coord, int subpixel_bits = kSubpixelBits) {
  // Exact: scaling by a power of two.
  const double d = window_coord * static_cast<double>(int64_t{1} << subpixel_bits);
  if (!(std::fabs(d) < 2.0 * kGuardBandLimit)) return std::nullopt;
  const double fl = std::floor(d);
  const double frac = d - fl;  // exact: |d| < 2^24
  int64_t r = static_cast<int64_t>(fl);
  if (frac > 0.5 || (frac == 0.5 && (r & 1) != 0)) ++r;
  if (!in_guard_band(r)) return std::nullopt;
  return static_cast<int32_t>(r);
}

// Depth in [0,1] -> unsigned integer in [0, 2^D - 1]: clamp (NaN -> 0), then
// round(z * (2^D - 1)) to nearest, ties to even, of the EXACT product: z's 53-bit integer
// significand times 2^D - 1 is < 2^53 * 2^32 = 2^85, taken in 128 bits. A double product
// would round first. Precondition: 1 <= depth_bits <= 32.
inline uint32_t snap_depth(double z, int depth_bits) {
  const uint64_t max_value = (uint64_t{1} << depth_bits) - 1;
  if (!(z > 0.0)) return 0;
  if (z >= 1.0) return static_cast<uint32_t>(max_value);
  int exponent = 0;
  const double m = std::frexp(z, &exponent);  // z = m 2^exponent, m in [0.5, 1), exponent <= 0
  const auto significand = static_cast<uint64_t>(std::ldexp(m, 53));  // exact, < 2^53
  const int shift = 53 - exponent;                                       // z = significand 2^-shift, >= 53
  if (shift >= 86) return 0;                                             // value < 2^85 2^-86 = 1/2
  const UInt128 product = UInt128{significand} * max_value;              // < 2^85
  UInt128 q = product >> shift;
  const UInt128 rem = product & ((UInt128{1} << shift) - 1);
  const UInt128 half = UInt128{1} << (shift - 1);
  if (rem > half || (rem == half && (q & 1) != 0)) ++q;
  return static_cast<uint32_t>(q);
}

inline std::optional<Vertex> snap_vertex(double x, double y, double z, int depth_bits) {
  const auto sx = snap_coord(x);
  const auto sy = snap_coord(y);
  if (!sx || !sy) return std::nullopt;
  return Vertex{*sx, *sy, snap_depth(z, depth_bits)};
}

}  // namespace tilevis::geom
