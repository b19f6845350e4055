// Where a unit's DRAM bytes lie: address ranges (spans), and the address map that places
// each stream of the tiler in its own region. Plain C++.
//
// The regions are an assumption of the model (a driver places buffers somewhere; what
// matters to the DRAM is that a stream is contiguous or scattered, and that two streams
// do not share rows): 1 GiB apart, and textures 256 MiB apart per draw.
#pragma once

#include <cstdint>
#include <vector>

namespace tilevis::sim {

namespace region {
constexpr uint64_t kGiB = uint64_t(1) << 30;
constexpr uint64_t vertices = 0 * kGiB;      // index and vertex buffers, in draw order
constexpr uint64_t parameters = 1 * kGiB;    // parameter buffer: primitive blocks, vertices, edges
constexpr uint64_t control = 2 * kGiB;       // parameter buffer: per-tile control streams
constexpr uint64_t spill = 3 * kGiB;         // silhouette hash entries spilled
constexpr uint64_t colour = 4 * kGiB;        // frame buffer (tile-linear)
constexpr uint64_t stored = 5 * kGiB;        // partial renders: colour and depth per sample
constexpr uint64_t control_per_tile = 1u << 20;  // control stream space per tile
constexpr uint64_t textures = 8 * kGiB;      // + draw x texture_stride
constexpr uint64_t texture_stride = uint64_t(256) << 20;
}  // namespace region

struct Span {
  uint64_t address = 0, bytes = 0;
};

// A list of spans; adding a span that continues the last one extends it.
struct Traffic {
  std::vector<Span> spans;
  void add(uint64_t address, uint64_t bytes) {
    if (!bytes) return;
    if (!spans.empty() && spans.back().address + spans.back().bytes == address) {
      spans.back().bytes += bytes;
      return;
    }
    spans.push_back({address, bytes});
  }
  void add(const Traffic& t) {
    for (const Span& s : t.spans) add(s.address, s.bytes);
  }
  uint64_t bytes() const {
    uint64_t n = 0;
    for (const Span& s : spans) n += s.bytes;
    return n;
  }
  bool empty() const { return spans.empty(); }
};

}  // namespace tilevis::sim
