#include "tilevis/json_node.h"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

namespace tilevis::json {

void raise_runtime_error(const std::string& message) { throw std::runtime_error(message); }

namespace {

// "line L, column C" of a byte offset (1-based) in text.
std::string place_of(const std::string& text, size_t byte) {
  size_t line = 1, col = 1;
  for (size_t i = 0; i + 1 < byte && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  return fmt::format("line {}, column {}", line, col);
}

}  // namespace

nlohmann::json parse_file(const std::string& file, Raise raise) {
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) {
    raise(fmt::format("{}: is a directory, expected a JSON file", file));
    throw std::logic_error("json::parse_file: the Raise function returned");
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    raise(fmt::format("{}: cannot open: {}", file, std::strerror(errno)));
    throw std::logic_error("json::parse_file: the Raise function returned");
  }
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Duplicate keys: nlohmann::json keeps the last silently; its parser callback sees every key.
  // One frame per open container: how it is reached from its parent, its keys so far.
  struct Open {
    bool array = false;
    size_t next = 0;          // arrays: index of the next element
    std::string label, key;   // label: ".key" or "[i]" from the parent; key: the object's current key
    std::set<std::string> keys;
  };
  std::vector<Open> open;
  std::string duplicate;
  auto callback = [&](int, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    using E = nlohmann::json::parse_event_t;
    switch (event) {
      case E::object_start:
      case E::array_start: {
        Open o;
        o.array = event == E::array_start;
        if (!open.empty()) o.label = open.back().array ? fmt::format("[{}]", open.back().next++) : "." + open.back().key;
        open.push_back(std::move(o));
        break;
      }
      case E::object_end:
      case E::array_end: open.pop_back(); break;
      case E::key: {
        Open& o = open.back();
        o.key = parsed.get<std::string>();
        if (!o.keys.insert(o.key).second && duplicate.empty()) {
          duplicate = "$";
          for (const Open& f : open) duplicate += f.label;
          duplicate += "." + o.key;
        }
        break;
      }
      case E::value:
        if (!open.empty() && open.back().array) ++open.back().next;
        break;
    }
    return true;
  };
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text, callback);
  } catch (const nlohmann::json::parse_error& e) {
    raise(fmt::format("{}: {}: invalid JSON: {}", file, place_of(text, e.byte), e.what()));
  } catch (const nlohmann::json::exception& e) {  // e.g. out_of_range 406: number overflow
    std::string where;
    const std::string what = e.what();
    const size_t q = what.find('\''), q2 = q == std::string::npos ? q : what.find('\'', q + 1);
    if (q2 != std::string::npos) {
      const size_t at = text.find(what.substr(q + 1, q2 - q - 1));
      if (at != std::string::npos) where = place_of(text, at + 1) + ": ";
    }
    raise(fmt::format("{}: {}expected a number within double's range ({})", file, where, what));
  }
  if (!duplicate.empty()) raise(fmt::format("{}: {}: key given twice in one object (expected each once)", file, duplicate));
  return j;
}

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
