// Z-buffer truth (DESIGN.md "Accuracy measures"): every front-facing triangle of the
// snapped scene rasterised at the sample positions (top-left rule) with an exact depth
// comparison — or, as a variant, with depth quantised to N bits as hardware does.
// The same pass counts the fragment work of the per-pixel visibility modes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tilevis/outputs.h"
#include "visibility/setup.h"

namespace tilevis::vis {

struct TruthConfig {
  uint32_t tile_w = 32, tile_h = 32;   // only for the per-tile counters
  uint32_t quantized_depth_bits = 0;   // 0: exact depth; N: compare depth rounded down to N bits
};

// Fragments shaded under each visibility mode (DESIGN.md "Visibility modes"): shader
// invocations, one per pixel and triangle that shades any of the pixel's samples (MSAA:
// depth and visibility per sample, shading per pixel; at 1 sample the two are the same).
struct ModeCounts {
  uint64_t none = 0;            // every pixel a triangle covers
  uint64_t early_z = 0;         // some sample passes the depth test on arrival, submission order
  uint64_t early_z_sorted = 0;  // same, draws sorted front to back by their nearest depth
  uint64_t prepass = 0;         // some sample visible (after a depth pre-pass of opaque geometry)
  uint64_t hsr = 0;             // some sample visible (per-pixel HSR in the tile)
  uint64_t hsr_depth_tests = 0; // HSR cost: depth tests, one per covered sample
};

struct TruthResult {
  uint32_t width = 0, height = 0, samples = 1;
  std::vector<int32_t> ids;         // per sample: nearest opaque front-facing triangle id, -1 background
  std::vector<float> overdraw;      // per pixel: fragments generated, summed over samples
  std::vector<uint64_t> covered;    // per original triangle id: samples where it is visible
  uint64_t fragments_generated = 0;
  uint64_t samples_covered = 0;     // samples with a visible opaque triangle
  ModeCounts modes;
  outputs::TileTable tiles;         // fragments_generated, samples_covered per tile
};

TruthResult zbuffer_truth(const Setup& setup, const TruthConfig& config);

}  // namespace tilevis::vis
