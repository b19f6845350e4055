// Small test frames built in-process, without the scene generator (so the cuda tests also
// build in TILEVIS_MINIMAL configurations on GPU machines): boxes, spheres, quads and a ground
// plane through a perspective camera, as clip-space trace draws.
#pragma once

#include <string>
#include <vector>

#include "tilevis/trace.h"

namespace tilevis::cudatest {

struct Mat4 {
  float m[16];  // column-major, OpenGL conventions
};

Mat4 look_at_perspective(const float eye[3], const float target[3], float fov_y_deg, float aspect, float near, float far);

struct MeshBuilder {
  std::vector<float> pos;        // xyz
  std::vector<uint32_t> index;   // counter-clockwise seen from outside
  void box(const float c[3], const float half[3], float rot_y_deg);
  void sphere(const float c[3], float r, int segments, int rings);
  void quad(const float c[3], float w, float h);  // facing +z
  void plane(float y, float half, int subdivisions);  // facing +y
};

trace::Draw make_draw(const std::string& name, const MeshBuilder& m, const Mat4& mvp, uint32_t flags = 0);

// Named test scenes (320x240 unless said otherwise). Each exercises something:
//   "cubes"      boxes, a sphere and cards over a floor (clips, occlusion, silhouettes)
//   "ground"     a ground plane through the near plane (clip-space clipping, fans, boundaries)
//   "stack"      cards one behind another, back to front (many edges per tile, the test-6 break)
//   "mixed"      a blended draw, a depth-writing draw and a soup draw among opaque ones
//   "coplanar"   two coplanar overlapping cards (equal-depth ties: the earlier triangle wins)
//   "folded"     a card whose faces are all given twice over a floor (edges shared from one side
//                are silhouettes)
//   "near_eye"   60 triangles through w = 0 at five exact depths over a far-plane quad (clipping
//                next to the eye, clip-space facing, coplanar ties; tests/visibility/near_eye)
//   "near_eye_pair"  two such triangles at one depth (the tile-size-dependent case)
trace::Frame scene(const std::string& name, uint32_t samples = 1);
std::vector<std::string> scene_names();
// Frames small, big, small, big: "cubes", and "cubes" shrunk about the screen's centre (the same
// counts of vertices and triangles, fewer (tile, triangle) pairs): a device-sized run's bounds
// learned from the small frame do not hold the big one.
std::vector<trace::Frame> small_big_sequence();

}  // namespace tilevis::cudatest
