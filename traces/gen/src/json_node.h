// A JSON value with its path, for scene validation: every accessor checks type and
// range and fails with "FILE: $.path: expected ...".
#pragma once

#include <cstdint>
#include <initializer_list>
#include <string>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

namespace tilevis::scene {

class Node {
 public:
  Node(const nlohmann::json& value, std::string path, const std::string& file)
      : m_value(value), m_path(std::move(path)), m_file(file) {}

  [[noreturn]] void fail(const std::string& expected) const;
  const std::string& path() const { return m_path; }

  bool has(const char* key) const;
  Node at(const char* key) const;          // required member
  Node at(size_t index) const;             // array element
  size_t array_size() const;               // fails unless an array
  void expect_object() const;
  void allow_only(std::initializer_list<const char*> keys) const;  // unknown keys are an error

  double number(double lo, double hi) const;            // finite, in [lo, hi]
  uint32_t integer(uint32_t lo, uint32_t hi) const;
  bool boolean() const;
  std::string string() const;
  glm::dvec3 vec3() const;
  glm::dvec3 vec3_or_scalar() const;                    // [x,y,z] or s -> (s,s,s)
  glm::dvec2 vec2_or_scalar() const;                    // [x,y] or s -> (s,s)

  double number_or(const char* key, double fallback, double lo, double hi) const;
  uint32_t integer_or(const char* key, uint32_t fallback, uint32_t lo, uint32_t hi) const;
  glm::dvec3 vec3_or(const char* key, glm::dvec3 fallback) const;

 private:
  const nlohmann::json& m_value;
  std::string m_path;
  const std::string& m_file;
};

}  // namespace tilevis::scene
