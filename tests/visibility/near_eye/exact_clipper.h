// An independent exact clipper for checking primitive setup near the eye: the trace's
// clip-space floats taken as exact rationals, clipped against the same six planes as
// setup (near, far, guard band) in rational arithmetic, then projected and snapped with
// exact round-half-even. It shares no code with model/visibility/setup.cpp.
#pragma once

#include <cstdint>
#include <vector>

#include "geom/fixed.h"
#include "tilevis/trace.h"

namespace tilevis::near_eye {

struct ExactTriangle {
  uint32_t id = 0;                   // trace triangle: index over the frame's draws in order
  int facing = 0;                    // sign of det[x y w] of the trace vertices: > 0 front (CCW in NDC)
  std::vector<geom::Vertex> polygon; // the clipped polygon, snapped exactly; empty if culled
};

// Every trace triangle of the frame, in id order. depth_bits as in SetupConfig.
std::vector<ExactTriangle> exact_clip(const trace::Frame& frame, uint32_t depth_bits = 24);

}  // namespace tilevis::near_eye
