// The reader: traces/FORMAT.md, applied byte by byte. Every count is checked against
// the bytes that remain in its enclosing chunk before anything is allocated for it.
#include <bit>
#include <cstring>
#include <string_view>

#include "layout.h"
#include "rules.h"
#include "tilevis/trace.h"

namespace tilevis::trace {

namespace {

using detail::Tag;

std::string hex_bytes(const uint8_t* bytes, size_t count) {
  static constexpr char kDigits[] = "0123456789ABCDEF";
  std::string text;
  for (size_t i = 0; i < count; ++i) {
    if (i != 0) text += ' ';
    text += kDigits[bytes[i] >> 4];
    text += kDigits[bytes[i] & 0xF];
  }
  return text;
}

std::string tag_text(const Tag& tag) {
  for (char c : tag)
    if (c < 0x20 || c > 0x7E) return hex_bytes(reinterpret_cast<const uint8_t*>(tag.data()), tag.size()) + " (hex)";
  return "'" + std::string(tag.data(), tag.size()) + "'";
}

struct ChunkHeader {
  Tag tag;
  uint64_t offset;  // of the tag
  uint64_t payload_begin;
  uint64_t payload_end;
};

class Reader {
 public:
  Reader(const uint8_t* data, size_t size, const std::string& name) : m_data(data), m_size(size), m_name(name) {}

  Trace read_trace();

 private:
  [[noreturn]] void fail(uint64_t offset, const std::string& what) const { throw FormatError(m_name, offset, what); }
  void check(uint64_t offset, const std::string& error) const {
    if (!error.empty()) fail(offset, m_context + error);
  }
  uint64_t remaining() const { return m_end - m_pos; }
  void need(uint64_t bytes, const char* field) const {
    if (bytes > remaining())
      fail(m_pos, m_context + "truncated: " + field + " needs " + std::to_string(bytes) + " bytes, " +
                      std::to_string(remaining()) + " remain in " + m_scope);
  }

  template <typename T>
  T read_le(const char* field) {
    need(sizeof(T), field);
    T value = 0;
    for (size_t i = 0; i < sizeof(T); ++i) value = static_cast<T>(value | T(m_data[m_pos + i]) << (8 * i));
    m_pos += sizeof(T);
    return value;
  }
  uint16_t u16(const char* field) { return read_le<uint16_t>(field); }
  uint32_t u32(const char* field) { return read_le<uint32_t>(field); }
  uint64_t u64(const char* field) { return read_le<uint64_t>(field); }
  float f32(const char* field) { return std::bit_cast<float>(read_le<uint32_t>(field)); }

  std::string read_string(const char* field, uint64_t length);
  ChunkHeader read_chunk_header();
  void enter(const ChunkHeader& chunk, const char* scope);
  void skip_or_reject_unknown(const ChunkHeader& chunk, const char* expected);
  void reject_trailing_bytes(const char* after);
  Frame read_frame(size_t frame_index);
  Draw read_draw(size_t frame_index, size_t draw_index);

  const uint8_t* m_data;
  uint64_t m_size;
  const std::string& m_name;
  uint64_t m_pos = 0;
  uint64_t m_end = 0;                 // end of the enclosing scope: file or chunk payload
  const char* m_scope = "file";
  std::string m_context;              // "frame F: " prefix of messages
  uint16_t m_major = 0, m_minor = 0;
};

std::string Reader::read_string(const char* field, uint64_t length) {
  need(length, field);
  std::string_view bytes(reinterpret_cast<const char*>(m_data + m_pos), length);
  const size_t bad = detail::first_invalid_utf8(bytes);
  if (bad != detail::kValidUtf8) check(m_pos + bad, detail::check_utf8(field, bytes));
  m_pos += length;
  return std::string(bytes);
}

ChunkHeader Reader::read_chunk_header() {
  ChunkHeader chunk{};
  chunk.offset = m_pos;
  need(detail::kChunkHeaderBytes, "chunk header");
  std::memcpy(chunk.tag.data(), m_data + m_pos, chunk.tag.size());
  m_pos += chunk.tag.size();
  const uint64_t length_offset = m_pos;
  const uint64_t length = u64("chunk payload length");
  if (length > remaining())
    fail(length_offset, m_context + "chunk " + tag_text(chunk.tag) + " payload length " + std::to_string(length) +
                            " exceeds the " + std::to_string(remaining()) + " bytes remaining in " + m_scope);
  chunk.payload_begin = m_pos;
  chunk.payload_end = m_pos + length;
  return chunk;
}

void Reader::enter(const ChunkHeader& chunk, const char* scope) {
  m_pos = chunk.payload_begin;
  m_end = chunk.payload_end;
  m_scope = scope;
}

// FORMAT.md "Compatibility": chunks a reader does not know are skipped only in files of a
// later minor version, whose additions this reader cannot know; in any other file they
// are corruption.
void Reader::skip_or_reject_unknown(const ChunkHeader& chunk, const char* expected) {
  if (m_minor > kVersionMinor) {
    m_pos = chunk.payload_end;
    return;
  }
  fail(chunk.offset, m_context + "unknown chunk tag " + tag_text(chunk.tag) + " in a version " +
                         std::to_string(m_major) + "." + std::to_string(m_minor) + " file, expected " + expected);
}

void Reader::reject_trailing_bytes(const char* after) {
  if (m_pos == m_end || m_minor > kVersionMinor) {
    m_pos = m_end;
    return;
  }
  fail(m_pos, m_context + std::to_string(remaining()) + " unexpected bytes after " + after + ", expected end of " +
                  m_scope);
}

Trace Reader::read_trace() {
  m_end = m_size;
  const size_t magic_bytes = m_size < detail::kMagic.size() ? static_cast<size_t>(m_size) : detail::kMagic.size();
  if (std::memcmp(m_data, detail::kMagic.data(), magic_bytes) != 0)
    fail(0, "bad magic " + hex_bytes(m_data, magic_bytes) + ", expected " +
                hex_bytes(detail::kMagic.data(), detail::kMagic.size()) + " (a TileVis trace)");
  need(detail::kMagic.size(), "magic");
  m_pos = detail::kMagic.size();

  m_major = u16("major version");
  if (m_major < kOldestMajor || m_major > kVersionMajor)
    fail(detail::kOffsetMajor, "major version " + std::to_string(m_major) + ", expected " +
                                   std::to_string(kOldestMajor) + " to " + std::to_string(kVersionMajor));
  m_minor = u16("minor version");
  const uint32_t byte_order = u32("byte-order mark");
  if (byte_order != detail::kByteOrderMark)
    fail(detail::kOffsetByteOrderMark, "byte-order mark " + hex_bytes(m_data + detail::kOffsetByteOrderMark, 4) +
                                           ", expected 04 03 02 01 (0x01020304 little-endian)");
  const uint64_t file_size = u64("file size");
  if (file_size != m_size)
    fail(detail::kOffsetFileSize, "file size field " + std::to_string(file_size) + ", expected the actual size " +
                                      std::to_string(m_size) + " (truncated or extended file)");
  const uint32_t frame_count = u32("frame count");
  check(detail::kOffsetFrameCount, detail::check_frame_count(frame_count));
  const uint32_t source_length = u32("source length");
  check(detail::kOffsetSourceLength, detail::check_source_length(source_length));

  Trace trace;
  trace.source = read_string("source", source_length);
  const uint64_t frames_need = uint64_t{frame_count} * detail::kMinFrameChunkBytes;
  if (frames_need > remaining())
    fail(detail::kOffsetFrameCount, "frame count " + std::to_string(frame_count) + " needs at least " +
                                        std::to_string(frames_need) + " bytes, " + std::to_string(remaining()) +
                                        " remain in file");
  trace.frames.reserve(frame_count);

  while (m_pos < m_end) {
    if (trace.frames.size() == frame_count && remaining() < detail::kChunkHeaderBytes)
      fail(m_pos, std::to_string(remaining()) + " trailing bytes after the last frame, expected end of file");
    const ChunkHeader chunk = read_chunk_header();
    if (chunk.tag != detail::kTagFrame) {
      skip_or_reject_unknown(chunk, trace.frames.size() == frame_count ? "end of file" : "FRAM");
      continue;
    }
    if (trace.frames.size() == frame_count)
      fail(chunk.offset, "FRAM chunk beyond the header's frame count " + std::to_string(frame_count) +
                             ", expected end of file");
    enter(chunk, "FRAM payload");
    trace.frames.push_back(read_frame(trace.frames.size()));
    m_context.clear();
    m_pos = chunk.payload_end;
    m_end = m_size;
    m_scope = "file";
  }
  if (trace.frames.size() != frame_count)
    fail(m_pos, "file ends after " + std::to_string(trace.frames.size()) + " of " + std::to_string(frame_count) +
                    " frames");
  // One encoding per trace: a file is of the lowest major that holds it.
  if (const uint16_t lowest = detail::major_for(trace); m_major != lowest)
    fail(detail::kOffsetMajor, "major version " + std::to_string(m_major) + " but no draw shades at sample rate, " +
                                   "expected " + std::to_string(lowest) + " (the lowest major that holds the trace)");
  return trace;
}

Frame Reader::read_frame(size_t frame_index) {
  m_context = detail::frame_context(frame_index);
  Frame frame;
  uint64_t at = m_pos;
  frame.width = u32("width");
  check(at, detail::check_viewport("width", frame.width));
  at = m_pos;
  frame.height = u32("height");
  check(at, detail::check_viewport("height", frame.height));
  at = m_pos;
  frame.depth_near = f32("depth_near");
  check(at, detail::check_depth("depth_near", frame.depth_near));
  at = m_pos;
  frame.depth_far = f32("depth_far");
  check(at, detail::check_depth("depth_far", frame.depth_far));
  at = m_pos;
  frame.subpixel_bits = u32("subpixel bits");
  check(at, detail::check_subpixel_bits(frame.subpixel_bits));
  at = m_pos;
  const uint32_t sample_count = u32("sample count");
  check(at, detail::check_sample_count(sample_count));
  need(uint64_t{sample_count} * detail::kSampleBytes, "sample positions");
  frame.samples.resize(sample_count);
  for (size_t i = 0; i < sample_count; ++i) {
    at = m_pos;
    frame.samples[i].x = u16("sample x");
    check(at, detail::check_sample_coordinate(i, "x", frame.samples[i].x, frame.subpixel_bits));
    at = m_pos;
    frame.samples[i].y = u16("sample y");
    check(at, detail::check_sample_coordinate(i, "y", frame.samples[i].y, frame.subpixel_bits));
  }
  const uint64_t draw_count_offset = m_pos;
  const uint32_t draw_count = u32("draw count");
  const uint64_t draws_need = uint64_t{draw_count} * detail::kMinDrawChunkBytes;
  if (draws_need > remaining())
    fail(draw_count_offset, m_context + "draw count " + std::to_string(draw_count) + " needs at least " +
                                std::to_string(draws_need) + " bytes, " + std::to_string(remaining()) +
                                " remain in FRAM payload");
  frame.draws.reserve(draw_count);

  const uint64_t frame_end = m_end;
  while (m_pos < frame_end) {
    const ChunkHeader chunk = read_chunk_header();
    if (chunk.tag != detail::kTagDraw) {
      skip_or_reject_unknown(chunk, frame.draws.size() == draw_count ? "end of FRAM payload" : "DRAW");
      continue;
    }
    if (frame.draws.size() == draw_count)
      fail(chunk.offset, m_context + "DRAW chunk beyond the frame's draw count " + std::to_string(draw_count) +
                             ", expected end of FRAM payload");
    enter(chunk, "DRAW payload");
    frame.draws.push_back(read_draw(frame_index, frame.draws.size()));
    m_context = detail::frame_context(frame_index);
    m_end = frame_end;
    m_scope = "FRAM payload";
  }
  if (frame.draws.size() != draw_count)
    fail(m_pos, m_context + "FRAM payload ends after " + std::to_string(frame.draws.size()) + " of " +
                    std::to_string(draw_count) + " draws");
  return frame;
}

Draw Reader::read_draw(size_t frame_index, size_t draw_index) {
  m_context = detail::draw_context(frame_index, draw_index);
  Draw draw;
  uint64_t at = m_pos;
  const uint32_t name_length = u32("name length");
  check(at, detail::check_name_length(name_length));
  draw.name = read_string("name", name_length);
  at = m_pos;
  draw.flags = u32("flags");
  check(at, detail::check_flags(draw.flags, m_major));
  at = m_pos;
  draw.shader_cycles_per_fragment = f32("shader cycles per fragment");
  check(at, detail::check_shader_cost(draw.shader_cycles_per_fragment));
  draw.varying_bytes_per_vertex = u32("varying bytes per vertex");
  draw.texture_bytes_per_fragment = u32("texture bytes per fragment");
  const uint64_t vertex_count_offset = m_pos;
  const uint32_t vertex_count = u32("vertex count");
  const uint64_t index_count_offset = m_pos;
  const uint32_t index_count = u32("index count");
  check(index_count_offset, detail::check_index_count(index_count));

  const uint64_t vertex_bytes = uint64_t{vertex_count} * detail::kVertexBytes;
  const uint64_t index_bytes = uint64_t{index_count} * detail::kIndexBytes;
  if (vertex_bytes > remaining())
    fail(vertex_count_offset, m_context + "vertex count " + std::to_string(vertex_count) + " needs " +
                                  std::to_string(vertex_bytes) + " bytes, " + std::to_string(remaining()) +
                                  " remain in DRAW payload");
  if (vertex_bytes + index_bytes > remaining())
    fail(index_count_offset, m_context + "index count " + std::to_string(index_count) + " needs " +
                                 std::to_string(index_bytes) + " bytes, " +
                                 std::to_string(remaining() - vertex_bytes) + " remain in DRAW payload");

  static_assert(sizeof(Vec4) == detail::kVertexBytes);
  draw.vertices.resize(vertex_count);
  const uint64_t vertices_offset = m_pos;
  if constexpr (std::endian::native == std::endian::little) {
    if (vertex_bytes != 0) std::memcpy(draw.vertices.data(), m_data + m_pos, vertex_bytes);  // data() may be null
    m_pos += vertex_bytes;
  } else {
    for (Vec4& v : draw.vertices) {
      v.x = f32("vertex x");
      v.y = f32("vertex y");
      v.z = f32("vertex z");
      v.w = f32("vertex w");
    }
  }
  for (size_t i = 0; i < vertex_count; ++i) {
    const Vec4& v = draw.vertices[i];
    const float components[4] = {v.x, v.y, v.z, v.w};
    static constexpr const char* kNames[4] = {"x", "y", "z", "w"};
    for (size_t c = 0; c < 4; ++c)
      check(vertices_offset + i * detail::kVertexBytes + c * 4,
            detail::check_vertex_component(i, kNames[c], components[c]));
  }

  draw.indices.resize(index_count);
  const uint64_t indices_offset = m_pos;
  if constexpr (std::endian::native == std::endian::little) {
    if (index_bytes != 0) std::memcpy(draw.indices.data(), m_data + m_pos, index_bytes);
    m_pos += index_bytes;
  } else {
    for (uint32_t& index : draw.indices) index = u32("index");
  }
  for (size_t i = 0; i < index_count; ++i)
    if (draw.indices[i] >= vertex_count)
      check(indices_offset + i * detail::kIndexBytes, detail::check_index(i, draw.indices[i], vertex_count));

  reject_trailing_bytes("the indices");
  return draw;
}

}  // namespace

Trace decode(const uint8_t* data, size_t size, const std::string& name) {
  static const uint8_t kNothing = 0;
  return Reader(data != nullptr ? data : &kNothing, data != nullptr ? size : 0, name).read_trace();
}

}  // namespace tilevis::trace
