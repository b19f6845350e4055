// Formats of the on-chip tile buffer's contents when they go to memory: the resolved
// colour at the end of the frame, colour and depth per sample when a partial render has
// to store a tile for a later one.
#pragma once

#include <cstdint>

namespace tilevis::sim {

struct FramebufferConfig {
  uint32_t colour_bytes = 4;  // RGBA8 (assumption: the common mobile render target)
  uint32_t depth_bytes = 4;   // D24S8 (assumption)
};

}  // namespace tilevis::sim
