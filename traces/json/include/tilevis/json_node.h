// A JSON value with its path, for input validation: every accessor checks type and
// range and fails with "FILE: $.path: expected ...". The exception type is the caller's
// (a scene file throws SceneError, a sweep file SweepError): pass a Raise function.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace tilevis::json {

// Throws the caller's exception with `message` ("FILE: PATH: expected ..."); never returns.
using Raise = void (*)(const std::string& message);

// Throws std::runtime_error.
[[noreturn]] void raise_runtime_error(const std::string& message);

// Reads and parses a JSON file strictly: a missing file, a directory, invalid JSON (with its
// line and column), a number out of double's range, and a key that appears twice in one object
// (with its JSON path) all end in raise("FILE: ...").
nlohmann::json parse_file(const std::string& file, Raise raise = &raise_runtime_error);

class Node {
 public:
  // `value` and `file` must outlive the node and every node reached from it.
  Node(const nlohmann::json& value, std::string path, const std::string& file, Raise raise = &raise_runtime_error)
      : m_value(value), m_path(std::move(path)), m_file(file), m_raise(raise) {}

  [[noreturn]] void fail(const std::string& expected) const;
  const std::string& path() const { return m_path; }
  const nlohmann::json& value() const { return m_value; }

  bool is_string() const { return m_value.is_string(); }
  bool is_number() const { return m_value.is_number(); }
  bool is_array() const { return m_value.is_array(); }
  bool is_object() const { return m_value.is_object(); }

  bool has(const char* key) const;
  Node at(const char* key) const;          // required member
  Node at(size_t index) const;             // array element
  size_t array_size() const;               // fails unless an array
  std::vector<std::string> keys() const;   // an object's member names (sorted: nlohmann::json is a map)
  void expect_object() const;
  void allow_only(std::initializer_list<const char*> keys) const;  // unknown keys are an error

  double number(double lo, double hi) const;            // finite, in [lo, hi]
  uint32_t integer(uint32_t lo, uint32_t hi) const;
  bool boolean() const;
  std::string string() const;

  double number_or(const char* key, double fallback, double lo, double hi) const;
  uint32_t integer_or(const char* key, uint32_t fallback, uint32_t lo, uint32_t hi) const;
  bool boolean_or(const char* key, bool fallback) const;
  std::string string_or(const char* key, const std::string& fallback) const;

 private:
  const nlohmann::json& m_value;
  std::string m_path;
  const std::string& m_file;
  Raise m_raise;
};

}  // namespace tilevis::json
