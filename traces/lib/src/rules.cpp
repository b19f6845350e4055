#include "rules.h"

#include <charconv>
#include <cmath>
#include <limits>

#include "tilevis/trace.h"

namespace tilevis::trace::detail {

namespace {

std::string hex(uint32_t value) {
  char buffer[16];
  auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value, 16);
  (void)ec;
  return "0x" + std::string(buffer, end);
}

}  // namespace

std::string format_float(float value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value < 0 ? "-inf" : "inf";
  char buffer[32];
  auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  (void)ec;
  return std::string(buffer, end);
}

size_t first_invalid_utf8(std::string_view bytes) {
  const size_t n = bytes.size();
  size_t i = 0;
  while (i < n) {
    const auto b0 = static_cast<uint8_t>(bytes[i]);
    if (b0 < 0x80) {
      ++i;
      continue;
    }
    size_t length = 0;
    uint8_t low = 0x80, high = 0xBF;  // allowed range of the second byte (RFC 3629 §4)
    if (b0 >= 0xC2 && b0 <= 0xDF) {
      length = 2;
    } else if (b0 >= 0xE0 && b0 <= 0xEF) {
      length = 3;
      if (b0 == 0xE0) low = 0xA0;   // overlong
      if (b0 == 0xED) high = 0x9F;  // UTF-16 surrogates
    } else if (b0 >= 0xF0 && b0 <= 0xF4) {
      length = 4;
      if (b0 == 0xF0) low = 0x90;   // overlong
      if (b0 == 0xF4) high = 0x8F;  // above U+10FFFF
    } else {
      return i;
    }
    for (size_t k = 1; k < length; ++k) {
      if (i + k >= n) return i;
      const auto b = static_cast<uint8_t>(bytes[i + k]);
      const uint8_t lo = k == 1 ? low : uint8_t{0x80};
      const uint8_t hi = k == 1 ? high : uint8_t{0xBF};
      if (b < lo || b > hi) return i;
    }
    i += length;
  }
  return kValidUtf8;
}

std::string frame_context(size_t frame) { return "frame " + std::to_string(frame) + ": "; }

std::string draw_context(size_t frame, size_t draw) {
  return "frame " + std::to_string(frame) + ", draw " + std::to_string(draw) + ": ";
}

std::string check_frame_count(uint64_t count) {
  if (count == 0) return "frame count 0, expected at least 1";
  return check_count_fits("frame count", count);
}

std::string check_source_length(uint64_t length) {
  if (length > kMaxSourceBytes)
    return "source length " + std::to_string(length) + ", expected at most " + std::to_string(kMaxSourceBytes);
  return {};
}

std::string check_utf8(const char* field, std::string_view bytes) {
  const size_t bad = first_invalid_utf8(bytes);
  if (bad == kValidUtf8) return {};
  return std::string(field) + " byte " + std::to_string(bad) + " breaks UTF-8, expected well-formed UTF-8";
}

std::string check_viewport(const char* axis, uint32_t pixels) {
  if (pixels == 0 || pixels > kMaxViewport)
    return std::string(axis) + " " + std::to_string(pixels) + ", expected 1.." + std::to_string(kMaxViewport);
  return {};
}

std::string check_depth(const char* field, float value) {
  // NaN fails both comparisons.
  if (!(value >= 0.0f && value <= 1.0f))
    return std::string(field) + " " + format_float(value) + ", expected a value in [0, 1]";
  return {};
}

std::string check_subpixel_bits(uint32_t bits) {
  // At least 1 so that the pixel centre, 2^(bits-1), is a representable sample position.
  if (bits == 0 || bits > kMaxSubpixelBits)
    return "subpixel bits " + std::to_string(bits) + ", expected 1.." + std::to_string(kMaxSubpixelBits);
  return {};
}

std::string check_sample_count(uint64_t count) {
  if (count == 1 || count == 2 || count == 4 || count == 8 || count == 16) return {};
  return "sample count " + std::to_string(count) + ", expected 1, 2, 4, 8 or 16";
}

std::string check_sample_coordinate(size_t sample, const char* axis, uint32_t value, uint32_t subpixel_bits) {
  const uint32_t limit = 1u << subpixel_bits;
  if (value >= limit)
    return "sample " + std::to_string(sample) + " " + axis + " " + std::to_string(value) + ", expected < " +
           std::to_string(limit) + " (2^subpixel bits)";
  return {};
}

std::string check_count_fits(const char* field, uint64_t count) {
  if (count > std::numeric_limits<uint32_t>::max())
    return std::string(field) + " " + std::to_string(count) + ", expected at most 4294967295";
  return {};
}

std::string check_name_length(uint64_t length) {
  if (length > kMaxNameBytes)
    return "name length " + std::to_string(length) + ", expected at most " + std::to_string(kMaxNameBytes);
  return {};
}

std::string check_flags(uint32_t flags, uint16_t major) {
  const uint32_t known = known_draw_flags(major);
  if ((flags & ~known) != 0)
    return "flags " + hex(flags) + " set unknown bits " + hex(flags & ~known) + ", expected only bits of " + hex(known) +
           " (version " + std::to_string(major) + ")";
  return {};
}

uint16_t major_for(const Trace& trace) {
  for (const Frame& frame : trace.frames)
    for (const Draw& draw : frame.draws)
      if (draw.sample_rate()) return 2;
  return kOldestMajor;
}

std::string check_shader_cost(float cycles) {
  if (!(cycles >= 0.0f) || std::isinf(cycles))
    return "shader cycles per fragment " + format_float(cycles) + ", expected a finite value >= 0";
  return {};
}

std::string check_index_count(uint64_t count) {
  if (count % 3 != 0) return "index count " + std::to_string(count) + ", expected a multiple of 3";
  return check_count_fits("index count", count);
}

std::string check_vertex_component(size_t vertex, const char* component, float value) {
  if (!std::isfinite(value))
    return "vertex " + std::to_string(vertex) + " " + component + " " + format_float(value) + ", expected a finite float";
  return {};
}

std::string check_index(size_t position, uint32_t index, uint64_t vertex_count) {
  if (index >= vertex_count)
    return "index " + std::to_string(index) + " >= vertex count " + std::to_string(vertex_count) + " (indices[" +
           std::to_string(position) + "])";
  return {};
}

}  // namespace tilevis::trace::detail
