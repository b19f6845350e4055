// Primitive setup (DESIGN.md "The modelled pipeline"): near/far and guard-band
// clipping in clip space, viewport transform, snapping to 16.8 fixed point and
// N-bit depth, facing after the snap, and silhouette extraction (SVGPU §3.1).
// Everything after this stage is exact integer geometry.
#pragma once

#include <cstdint>
#include <vector>

#include "geom/fixed.h"
#include "tilevis/trace.h"

namespace tilevis::vis {

inline constexpr uint32_t kNoVertex = 0xffffffffu;

struct SetupConfig {
  uint32_t depth_bits = 24;
};

// One snapped triangle. A trace triangle becomes zero (culled by the frustum), one,
// or — when clipping cuts it — several (a fan); all carry the trace triangle's id.
struct SetupTriangle {
  geom::Vertex v[3];
  uint32_t id = 0;        // original triangle: index over the frame's draws in order
  uint32_t draw = 0;
  bool front = false;     // counter-clockwise in NDC (clockwise in y-down window space) in clip space
                          // (geom/homogeneous.h), and so after the snap, with non-zero area
  bool opaque = true;     // may occlude (opaque draw, no shader depth/discard)
  bool sample_rate = false;  // its draw shades once per covered sample (trace::kSampleRateShading)
  bool clipped = false;   // produced by clipping (its edges are treated as boundaries)
};

// A silhouette edge (SVGPU §3.1): an edge of an opaque draw with at least one
// front-facing triangle and either an adjacent triangle facing the other way or
// other than two adjacent triangles.
struct SilhouetteEdge {
  geom::Vertex a, b;
  uint32_t draw = 0;
};

struct SetupStats {
  uint64_t triangles_in = 0;
  uint64_t frustum_culled = 0;   // wholly outside a clip plane
  uint64_t clipped = 0;          // trace triangles cut by a clip plane
  uint64_t setup_triangles = 0;  // after clipping
  uint64_t edge_on = 0;          // trace triangles whose plane holds the eye: projected to a line, culled
  uint64_t degenerate = 0;       // pieces with zero area after the snap, or turned against their facing
  uint64_t back_facing = 0;
  uint64_t front_facing = 0;
  uint64_t silhouette_edges = 0;
};

struct Setup {
  uint32_t width = 0, height = 0;
  std::vector<trace::SamplePos> samples;
  uint32_t subpixel_bits = 8, depth_bits = 24;
  std::vector<SetupTriangle> triangles;   // canonical order: by id, then fan position
  std::vector<SilhouetteEdge> silhouettes;  // canonical order: by draw, then edge key
  std::vector<uint32_t> triangle_draw;    // per original triangle id, its draw
  SetupStats stats;
};

// Guard band half-width in NDC units for a viewport dimension: keeps every clipped,
// snapped coordinate inside |x| < 2^15 pixels (geom::kGuardBandPixels).
double guard_band_ndc(uint32_t pixels);

Setup primitive_setup(const trace::Frame& frame, const SetupConfig& config);

}  // namespace tilevis::vis
