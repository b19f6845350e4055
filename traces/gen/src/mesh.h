// Object-space triangle meshes: what importers and procedural primitives produce.
// Front faces are counter-clockwise seen from outside (OpenGL convention).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace tilevis::scene {

struct Mesh {
  std::vector<glm::dvec3> positions;
  std::vector<uint32_t> indices;  // 3 per triangle
  // The meshes of a multi-mesh file, each a range of `indices` (empty: one part). Each becomes
  // its own draw, as the file's author made them separate objects.
  struct Part {
    std::string name;
    size_t first = 0, count = 0;  // in indices
  };
  std::vector<Part> parts;

  size_t triangle_count() const { return indices.size() / 3; }
  void append(const Mesh& other);
  // Centre the bounding box at the origin and scale its largest extent to 1.
  void fit_unit();
};

// assimp import (OBJ, PLY, OFF, STL, 3DS, ...): triangulated, identical vertices
// joined (so shared edges share indices), node transforms applied.
// Throws std::runtime_error naming the file on failure.
Mesh import_mesh(const std::filesystem::path& file);

Mesh make_box(glm::dvec3 size);
Mesh make_plane(glm::dvec2 size, uint32_t subdivisions);          // XZ plane, facing +Y
Mesh make_sphere(double radius, uint32_t segments, uint32_t rings);
// `count` quads of `size` in planes parallel to XY facing +Z, the first centred at
// `origin`, each next one moved by `step`.
Mesh make_quads(uint32_t count, glm::dvec2 size, glm::dvec3 origin, glm::dvec3 step);
// Five inward-facing walls of an axis-aligned box, open towards +Z.
Mesh make_cornell_box(glm::dvec3 size);

}  // namespace tilevis::scene
