// Generated near-eye scenes (issue: hostile input): triangles with vertices at or just behind
// w = 0, whose projections pass through infinity, over a background quad at the far plane.
// Depths are exact in float (z = c w with c a power of two or zero), so triangles at
// different depths cannot interpenetrate and triangles at one depth are exactly coplanar:
// the exact truth is well defined and golden must equal it at every tile size.
#pragma once

#include <cstdint>

#include "tilevis/trace.h"

namespace tilevis::near_eye {

// Two triangles, each with one vertex at w = 0.001 and two at w = -1, at one constant depth
// each (NDC depth c_a and c_b), drawn before a full-screen quad at the far plane.
trace::Frame two_triangles(uint32_t width, uint32_t height, float c_a, float c_b);

// `count` such triangles with random positions, depths from {0, +-1/4, +-1/2} and the front
// vertex at w = 2^-k (k in 4..20), then the background quad.
trace::Frame random_near_eye(uint64_t seed, uint32_t count, uint32_t width, uint32_t height);

// One triangle with a vertex at a tiny |w| (down to 2^-126, either sign, or exactly the eye
// (0, 0, 0, 0) for every 50th seed), the others in front of the eye.
trace::Frame near_zero_w(uint64_t seed, uint32_t width, uint32_t height);

}  // namespace tilevis::near_eye
