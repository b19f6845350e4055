// Seeded random scenes for checking the golden pipeline against the CGAL oracle: small,
// non-penetrating, orthographic (w = 1) frames whose clip-space floats the pipeline's
// viewport transform snaps back EXACTLY to the integer window coordinates and depths
// chosen here, so pipeline and oracle see the same geometry with no rounding between.
#pragma once

#include <cstdint>
#include <vector>

#include "oracle.h"
#include "tilevis/trace.h"

namespace tilevis::oracle {

// The frame the generator writes: 256×256 pixels, 8 sub-pixel bits, 1 sample, depth
// range [0, 1], 24-bit depth.
inline constexpr uint32_t kSceneSize = 256;
inline constexpr int64_t kSubpixel = 256;
inline constexpr uint32_t kSceneDepthBits = 24;
// Window coordinates, in sub-pixel units, lie in [kCoordMin, kCoordMax]: up to 4 pixels
// beyond the viewport's left/top edge and 4 beyond its right/bottom edge.
inline constexpr int64_t kCoordMin = -4 * kSubpixel;
inline constexpr int64_t kCoordMax = 260 * kSubpixel;

struct SceneOptions {
  uint64_t seed = 1;
  uint32_t triangles = 12;          // triangles emitted, exactly (back-facing and degenerate included)
  uint32_t draws = 1;               // objects are spread over this many draws (each mesh stays in one)
  double huge_fraction = 0.1;       // single triangles over about half the viewport; meshes over most or all of it
  double sliver_fraction = 0.1;     // long triangles 1–32 sub-pixel units thick
  double tilted_fraction = 0.3;     // single triangles on a tilted plane instead of constant depth
  double back_fraction = 0.0;       // objects emitted back-facing
  double degenerate_fraction = 0.0; // single triangles with collinear vertices (zero area)
  bool meshes = false;              // objects are fans and strips sharing vertices (indexed)
};

// What the pipeline's snap must give for one trace vertex.
struct WindowVertex {
  int64_t x, y;  // sub-pixel units, y down
  uint32_t z;    // depth units of 2^-24 - 1
  bool operator==(const WindowVertex&) const = default;
};

struct RandomScene {
  trace::Frame frame;
  std::vector<std::vector<WindowVertex>> window;  // per draw, per vertex (parallel to draw.vertices)
  // Front-facing, non-degenerate triangles in frame order; id = index over the frame's
  // draws in order. Window orientation: orient2d(v0, v1, v2) < 0 (counter-clockwise in NDC).
  std::vector<Triangle> triangles;
};

// Deterministic for a seed (own integer PRNG; angles go through std::cos/std::sin, so a
// different libm could move a fan vertex by one unit). Throws std::invalid_argument for
// triangles == 0 or draws == 0, std::logic_error if a snap would not round-trip.
RandomScene random_scene(const SceneOptions& options);

// Clip-space coordinates (w = 1) that the viewport transform of a 256×256 frame, depth
// range [0, 1], snaps to the given window values. Each throws std::logic_error if it
// cannot (x, y: outside the range above; z: no float rounds there).
float clip_x_for(int64_t window_x);
float clip_y_for(int64_t window_y);
float clip_z_for(uint32_t window_z);

}  // namespace tilevis::oracle
