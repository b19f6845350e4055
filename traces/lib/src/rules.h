// The validation rules of traces/FORMAT.md, shared by the reader (decode) and by
// validate(), so that both reject the same defects with the same words.
// Each check returns an empty string for an acceptable value, else one line saying
// what was found and what was expected.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace tilevis::trace {
struct Trace;
}

namespace tilevis::trace::detail {

inline constexpr size_t kValidUtf8 = static_cast<size_t>(-1);

// Index of the first byte of the first sequence that is not well-formed UTF-8
// (RFC 3629: no overlong forms, no surrogates, nothing above U+10FFFF), or kValidUtf8.
size_t first_invalid_utf8(std::string_view bytes);

std::string frame_context(size_t frame);
std::string draw_context(size_t frame, size_t draw);

std::string check_frame_count(uint64_t count);
std::string check_source_length(uint64_t length);
std::string check_utf8(const char* field, std::string_view bytes);
std::string check_viewport(const char* axis, uint32_t pixels);
std::string check_depth(const char* field, float value);
std::string check_subpixel_bits(uint32_t bits);
std::string check_sample_count(uint64_t count);
std::string check_sample_coordinate(size_t sample, const char* axis, uint32_t value, uint32_t subpixel_bits);
std::string check_count_fits(const char* field, uint64_t count);
std::string check_name_length(uint64_t length);
std::string check_flags(uint32_t flags, uint16_t major);
// The lowest major that holds the trace (FORMAT.md "Compatibility"): what the writer writes.
uint16_t major_for(const Trace& trace);
std::string check_shader_cost(float cycles);
std::string check_index_count(uint64_t count);
std::string check_vertex_component(size_t vertex, const char* component, float value);
std::string check_index(size_t position, uint32_t index, uint64_t vertex_count);

// Shortest decimal that reads back as the same float ("nan", "inf" for those).
std::string format_float(float value);

}  // namespace tilevis::trace::detail
