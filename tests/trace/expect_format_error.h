// GoogleTest helpers asserting a FormatError's type, offset and message.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "tilevis/trace.h"

namespace tilevis::trace::test {

// Checks one FormatError; returns its message after "FILE: offset N: ".
inline std::string check_format_error(const FormatError& e, const std::string& file, uint64_t offset,
                                      const std::string& fragment) {
  const std::string what = e.what();
  const std::string prefix = file + ": offset " + std::to_string(offset) + ": ";
  EXPECT_EQ(e.file(), file) << what;
  EXPECT_EQ(e.offset(), offset) << what;
  EXPECT_EQ(what.rfind(prefix, 0), 0u) << what;
  EXPECT_NE(what.find(fragment), std::string::npos) << "message: " << what << "\nexpected to contain: " << fragment;
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  return what.size() >= prefix.size() ? what.substr(prefix.size()) : what;
}

// Decodes `bytes`, expecting a FormatError at `offset` whose message contains `fragment`.
inline std::string expect_rejected(const std::vector<uint8_t>& bytes, uint64_t offset, const std::string& fragment) {
  const std::string file = "traces/bad.tvt";
  try {
    decode(bytes.data(), bytes.size(), file);
  } catch (const FormatError& e) {
    return check_format_error(e, file, offset, fragment);
  }
  ADD_FAILURE() << "decode accepted the input; expected a FormatError at offset " << offset << " containing \""
                << fragment << "\"";
  return {};
}

}  // namespace tilevis::trace::test
