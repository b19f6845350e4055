#include "json_node.h"

#include "tilevis/scene.h"

namespace tilevis::scene {

namespace {
constexpr double kBigCoordinate = 1e12;
}

void raise_scene_error(const std::string& message) { throw SceneError(message); }

glm::dvec3 vec3(const Node& n) {
  if (!n.is_array() || n.value().size() != 3) n.fail("expected an array of 3 numbers");
  return {n.at(size_t{0}).number(-kBigCoordinate, kBigCoordinate), n.at(1).number(-kBigCoordinate, kBigCoordinate), n.at(2).number(-kBigCoordinate, kBigCoordinate)};
}

glm::dvec3 vec3_or_scalar(const Node& n) {
  if (n.is_number()) {
    double s = n.number(-kBigCoordinate, kBigCoordinate);
    return {s, s, s};
  }
  return vec3(n);
}

glm::dvec2 vec2_or_scalar(const Node& n) {
  if (n.is_number()) {
    double s = n.number(-kBigCoordinate, kBigCoordinate);
    return {s, s};
  }
  if (!n.is_array() || n.value().size() != 2) n.fail("expected a number or an array of 2 numbers");
  return {n.at(size_t{0}).number(-kBigCoordinate, kBigCoordinate), n.at(1).number(-kBigCoordinate, kBigCoordinate)};
}

glm::dvec3 vec3_or(const Node& n, const char* key, glm::dvec3 fallback) {
  return n.has(key) ? vec3(n.at(key)) : fallback;
}

}  // namespace tilevis::scene
