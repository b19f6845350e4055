#include "json_node.h"

#include "tilevis/scene.h"

namespace tilevis::scene {

namespace {
// A coordinate, scale or vector component: any finite number of at most 1e12 in magnitude.
double bounded_number(const Node& n) { return n.number(-1e12, 1e12); }
}  // namespace

void raise_scene_error(const std::string& message) { throw SceneError(message); }

glm::dvec3 vec3(const Node& n) {
  if (!n.is_array() || n.value().size() != 3) n.fail("expected an array of 3 numbers");
  return {bounded_number(n.at(size_t{0})), bounded_number(n.at(1)), bounded_number(n.at(2))};
}

glm::dvec3 vec3_or_scalar(const Node& n) {
  if (n.is_number()) {
    double s = bounded_number(n);
    return {s, s, s};
  }
  return vec3(n);
}

glm::dvec2 vec2_or_scalar(const Node& n) {
  if (n.is_number()) {
    double s = bounded_number(n);
    return {s, s};
  }
  if (!n.is_array() || n.value().size() != 2) n.fail("expected a number or an array of 2 numbers");
  return {bounded_number(n.at(size_t{0})), bounded_number(n.at(1))};
}

glm::dvec3 vec3_or(const Node& n, const char* key, glm::dvec3 fallback) {
  return n.has(key) ? vec3(n.at(key)) : fallback;
}

}  // namespace tilevis::scene
