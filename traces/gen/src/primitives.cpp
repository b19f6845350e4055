#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <glm/common.hpp>

#include "mesh.h"

namespace tilevis::scene {

void Mesh::append(const Mesh& other) {
  auto base = static_cast<uint32_t>(positions.size());
  positions.insert(positions.end(), other.positions.begin(), other.positions.end());
  for (uint32_t i : other.indices) indices.push_back(base + i);
}

void Mesh::fit_unit() {
  if (positions.empty()) return;
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  for (const auto& p : positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  glm::dvec3 extent = hi - lo;
  double largest = std::max({extent.x, extent.y, extent.z});
  double scale = largest > 0 ? 1.0 / largest : 1.0;
  glm::dvec3 centre = (lo + hi) * 0.5;
  for (auto& p : positions) p = (p - centre) * scale;
}

namespace {
// Appends quad a-b-c-d (counter-clockwise seen from its front) as two triangles.
void add_quad(Mesh& m, uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
  m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
}
}  // namespace

Mesh make_box(glm::dvec3 size) {
  Mesh m;
  glm::dvec3 h = size * 0.5;
  for (int i = 0; i < 8; ++i)
    m.positions.push_back({(i & 1) ? h.x : -h.x, (i & 2) ? h.y : -h.y, (i & 4) ? h.z : -h.z});
  add_quad(m, 0, 4, 6, 2);  // -x
  add_quad(m, 1, 3, 7, 5);  // +x
  add_quad(m, 0, 1, 5, 4);  // -y
  add_quad(m, 2, 6, 7, 3);  // +y
  add_quad(m, 0, 2, 3, 1);  // -z
  add_quad(m, 4, 5, 7, 6);  // +z
  return m;
}

Mesh make_plane(glm::dvec2 size, uint32_t n) {
  Mesh m;
  for (uint32_t j = 0; j <= n; ++j)
    for (uint32_t i = 0; i <= n; ++i)
      m.positions.push_back({(i / double(n) - 0.5) * size.x, 0.0, (j / double(n) - 0.5) * size.y});
  auto at = [n](uint32_t i, uint32_t j) { return j * (n + 1) + i; };
  for (uint32_t j = 0; j < n; ++j)
    for (uint32_t i = 0; i < n; ++i) add_quad(m, at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
  return m;
}

Mesh make_sphere(double radius, uint32_t segments, uint32_t rings) {
  Mesh m;
  m.positions.push_back({0, radius, 0});   // north pole
  for (uint32_t r = 1; r < rings; ++r) {
    double theta = std::numbers::pi * r / rings;
    for (uint32_t s = 0; s < segments; ++s) {
      double phi = 2 * std::numbers::pi * s / segments;
      m.positions.push_back({radius * std::sin(theta) * std::cos(phi), radius * std::cos(theta),
                             -radius * std::sin(theta) * std::sin(phi)});
    }
  }
  auto south = static_cast<uint32_t>(m.positions.size());
  m.positions.push_back({0, -radius, 0});
  auto ring = [segments](uint32_t r, uint32_t s) { return 1 + (r - 1) * segments + s % segments; };
  for (uint32_t s = 0; s < segments; ++s) m.indices.insert(m.indices.end(), {0, ring(1, s), ring(1, s + 1)});
  for (uint32_t r = 1; r + 1 < rings; ++r)
    for (uint32_t s = 0; s < segments; ++s) add_quad(m, ring(r, s), ring(r + 1, s), ring(r + 1, s + 1), ring(r, s + 1));
  for (uint32_t s = 0; s < segments; ++s)
    m.indices.insert(m.indices.end(), {south, ring(rings - 1, s + 1), ring(rings - 1, s)});
  return m;
}

Mesh make_quads(uint32_t count, glm::dvec2 size, glm::dvec3 origin, glm::dvec3 step) {
  Mesh m;
  glm::dvec2 h = size * 0.5;
  for (uint32_t q = 0; q < count; ++q) {
    glm::dvec3 c = origin + step * double(q);
    auto base = static_cast<uint32_t>(m.positions.size());
    m.positions.insert(m.positions.end(),
                       {c + glm::dvec3(-h.x, -h.y, 0), c + glm::dvec3(h.x, -h.y, 0), c + glm::dvec3(h.x, h.y, 0),
                        c + glm::dvec3(-h.x, h.y, 0)});
    add_quad(m, base, base + 1, base + 2, base + 3);
  }
  return m;
}

Mesh make_cornell_box(glm::dvec3 size) {
  Mesh m = make_box(size);
  // Turn the box inside out and drop the +z wall: the camera looks in through it.
  m.indices.resize(m.indices.size() - 6);
  for (size_t t = 0; t < m.indices.size(); t += 3) std::swap(m.indices[t + 1], m.indices[t + 2]);
  return m;
}

}  // namespace tilevis::scene
