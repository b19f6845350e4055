#include "tilevis/json_node.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace tilevis::json {

void raise_runtime_error(const std::string& message) { throw std::runtime_error(message); }

void Node::fail(const std::string& expected) const {
  m_raise(fmt::format("{}: {}: {}", m_file, m_path, expected));
  throw std::logic_error("json::Node: the Raise function returned");  // Raise must throw
}

void Node::expect_object() const {
  if (!m_value.is_object()) fail("expected an object");
}

bool Node::has(const char* key) const {
  expect_object();
  return m_value.contains(key);
}

Node Node::at(const char* key) const {
  expect_object();
  auto it = m_value.find(key);
  if (it == m_value.end()) fail(fmt::format("missing required member \"{}\"", key));
  return Node(*it, m_path + "." + key, m_file, m_raise);
}

size_t Node::array_size() const {
  if (!m_value.is_array()) fail("expected an array");
  return m_value.size();
}

Node Node::at(size_t index) const {
  if (index >= array_size()) fail(fmt::format("expected at least {} elements", index + 1));
  return Node(m_value[index], fmt::format("{}[{}]", m_path, index), m_file, m_raise);
}

std::vector<std::string> Node::keys() const {
  expect_object();
  std::vector<std::string> names;
  for (const auto& [key, value] : m_value.items()) names.push_back(key);
  return names;
}

void Node::allow_only(std::initializer_list<const char*> keys) const {
  expect_object();
  for (const auto& [key, value] : m_value.items()) {
    bool known = false;
    for (const char* k : keys) known = known || key == k;
    if (!known) {
      std::string list;
      for (const char* k : keys) list += (list.empty() ? "" : ", ") + std::string(k);
      Node(value, m_path + "." + key, m_file, m_raise).fail(fmt::format("unknown member (expected one of: {})", list));
    }
  }
}

double Node::number(double lo, double hi) const {
  if (!m_value.is_number()) fail(fmt::format("expected a number in [{}, {}]", lo, hi));
  double v = m_value.get<double>();
  if (!std::isfinite(v) || v < lo || v > hi) fail(fmt::format("expected a number in [{}, {}], got {}", lo, hi, v));
  return v;
}

uint32_t Node::integer(uint32_t lo, uint32_t hi) const {
  if (!m_value.is_number_integer() && !m_value.is_number_unsigned())
    fail(fmt::format("expected an integer in [{}, {}]", lo, hi));
  int64_t v = m_value.get<int64_t>();
  if (v < lo || v > hi) fail(fmt::format("expected an integer in [{}, {}], got {}", lo, hi, v));
  return static_cast<uint32_t>(v);
}

bool Node::boolean() const {
  if (!m_value.is_boolean()) fail("expected true or false");
  return m_value.get<bool>();
}

std::string Node::string() const {
  if (!m_value.is_string()) fail("expected a string");
  return m_value.get<std::string>();
}

double Node::number_or(const char* key, double fallback, double lo, double hi) const {
  return has(key) ? at(key).number(lo, hi) : fallback;
}

uint32_t Node::integer_or(const char* key, uint32_t fallback, uint32_t lo, uint32_t hi) const {
  return has(key) ? at(key).integer(lo, hi) : fallback;
}

bool Node::boolean_or(const char* key, bool fallback) const { return has(key) ? at(key).boolean() : fallback; }

std::string Node::string_or(const char* key, const std::string& fallback) const {
  return has(key) ? at(key).string() : fallback;
}

}  // namespace tilevis::json
