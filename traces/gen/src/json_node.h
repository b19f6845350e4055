// Scene files are validated through the shared path-aware JSON node (traces/json);
// this adds the scene's vector forms and its exception type.
#pragma once

#include <string>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "tilevis/json_node.h"

namespace tilevis::scene {

using json::Node;

// Throws SceneError: the Raise of every node of a scene file.
[[noreturn]] void raise_scene_error(const std::string& message);

glm::dvec3 vec3(const Node& n);                 // [x, y, z]
glm::dvec3 vec3_or_scalar(const Node& n);       // [x, y, z] or s -> (s, s, s)
glm::dvec2 vec2_or_scalar(const Node& n);       // [x, y] or s -> (s, s)
glm::dvec3 vec3_or(const Node& n, const char* key, glm::dvec3 fallback);

}  // namespace tilevis::scene
