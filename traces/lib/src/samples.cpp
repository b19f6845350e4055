#include <array>
#include <span>

#include "tilevis/trace.h"

namespace tilevis::trace {

namespace {

struct Offset16 {
  int x, y;
};

// D3D11 standard multisample patterns (D3D11_STANDARD_MULTISAMPLE_PATTERN), in the
// spec's units: 1/16 pixel relative to the pixel centre, x right, y down, -8..7.
// The 8- and 16-sample patterns put exactly one sample in each 1/16 row and column.
constexpr std::array<Offset16, 1> kPattern1 = {{{0, 0}}};
constexpr std::array<Offset16, 2> kPattern2 = {{{4, 4}, {-4, -4}}};
constexpr std::array<Offset16, 4> kPattern4 = {{{-2, -6}, {6, -2}, {-6, 2}, {2, 6}}};
constexpr std::array<Offset16, 8> kPattern8 = {
    {{1, -3}, {-1, 3}, {5, 1}, {-3, -5}, {-5, 5}, {-7, -1}, {3, 7}, {7, -7}}};
constexpr std::array<Offset16, 16> kPattern16 = {{{1, 1},
                                                  {-1, -3},
                                                  {-3, 2},
                                                  {4, -1},
                                                  {-5, -2},
                                                  {2, 5},
                                                  {5, 3},
                                                  {3, -5},
                                                  {-2, 6},
                                                  {0, -7},
                                                  {-4, -6},
                                                  {-6, 4},
                                                  {-8, 0},
                                                  {7, -4},
                                                  {6, 7},
                                                  {-7, -8}}};

std::span<const Offset16> pattern(uint32_t count) {
  switch (count) {
    case 1: return kPattern1;
    case 2: return kPattern2;
    case 4: return kPattern4;
    case 8: return kPattern8;
    case 16: return kPattern16;
    default: return {};
  }
}

// 1/16 pixel from the centre -> 1/2^bits pixel from the top-left corner.
uint16_t to_corner_units(int offset16, uint32_t subpixel_bits, uint32_t count) {
  const int from_corner16 = offset16 + 8;  // 0..15
  const int scaled = from_corner16 << subpixel_bits;
  if (scaled % 16 != 0)
    throw std::invalid_argument("standard_samples: the " + std::to_string(count) +
                                "-sample pattern is not exact at " + std::to_string(subpixel_bits) +
                                " subpixel bits");
  return static_cast<uint16_t>(scaled / 16);
}

}  // namespace

std::vector<SamplePos> standard_samples(uint32_t count, uint32_t subpixel_bits) {
  const std::span<const Offset16> offsets = pattern(count);
  if (offsets.empty())
    throw std::invalid_argument("standard_samples: sample count " + std::to_string(count) +
                                ", expected 1, 2, 4, 8 or 16");
  if (subpixel_bits == 0 || subpixel_bits > kMaxSubpixelBits)
    throw std::invalid_argument("standard_samples: subpixel bits " + std::to_string(subpixel_bits) +
                                ", expected 1.." + std::to_string(kMaxSubpixelBits));
  std::vector<SamplePos> samples;
  samples.reserve(offsets.size());
  for (const Offset16& o : offsets)
    samples.push_back({to_corner_units(o.x, subpixel_bits, count), to_corner_units(o.y, subpixel_bits, count)});
  return samples;
}

}  // namespace tilevis::trace
