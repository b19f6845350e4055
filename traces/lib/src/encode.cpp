// The writer side: validate() applies the reader's rules to a Trace in memory, and
// encode() lays out only what validate() accepts (traces/FORMAT.md, "Layout").
#include <bit>
#include <cstring>

#include "encode.h"
#include "layout.h"
#include "rules.h"
#include "tilevis/trace.h"

namespace tilevis::trace {

FormatError::FormatError(const std::string& file, uint64_t offset, const std::string& what)
    : std::runtime_error(file + ": offset " + std::to_string(offset) + ": " + what), m_file(file), m_offset(offset) {}

size_t Frame::triangle_count() const {
  size_t count = 0;
  for (const Draw& draw : draws) count += draw.triangle_count();
  return count;
}

size_t Frame::vertex_count() const {
  size_t count = 0;
  for (const Draw& draw : draws) count += draw.vertices.size();
  return count;
}

namespace {

class Validator {
 public:
  // `major`: the file the trace would be (detail::major_for), whose flags the reader checks.
  Validator(const std::string& name, uint16_t major) : m_name(name), m_major(major) {}

  void check(const std::string& context, const std::string& error) const {
    if (!error.empty()) throw FormatError(m_name, 0, context + error);
  }

  void frame(const Frame& frame, size_t f) const {
    const std::string context = detail::frame_context(f);
    check(context, detail::check_viewport("width", frame.width));
    check(context, detail::check_viewport("height", frame.height));
    check(context, detail::check_depth("depth_near", frame.depth_near));
    check(context, detail::check_depth("depth_far", frame.depth_far));
    check(context, detail::check_subpixel_bits(frame.subpixel_bits));
    check(context, detail::check_sample_count(frame.samples.size()));
    for (size_t i = 0; i < frame.samples.size(); ++i) {
      check(context, detail::check_sample_coordinate(i, "x", frame.samples[i].x, frame.subpixel_bits));
      check(context, detail::check_sample_coordinate(i, "y", frame.samples[i].y, frame.subpixel_bits));
    }
    check(context, detail::check_count_fits("draw count", frame.draws.size()));
    for (size_t d = 0; d < frame.draws.size(); ++d) draw(frame.draws[d], f, d);
  }

  void draw(const Draw& draw, size_t f, size_t d) const {
    const std::string context = detail::draw_context(f, d);
    check(context, detail::check_name_length(draw.name.size()));
    check(context, detail::check_utf8("name", draw.name));
    check(context, detail::check_flags(draw.flags, m_major));
    check(context, detail::check_shader_cost(draw.shader_cycles_per_fragment));
    check(context, detail::check_count_fits("vertex count", draw.vertices.size()));
    check(context, detail::check_index_count(draw.indices.size()));
    for (size_t i = 0; i < draw.vertices.size(); ++i) {
      const Vec4& v = draw.vertices[i];
      check(context, detail::check_vertex_component(i, "x", v.x));
      check(context, detail::check_vertex_component(i, "y", v.y));
      check(context, detail::check_vertex_component(i, "z", v.z));
      check(context, detail::check_vertex_component(i, "w", v.w));
    }
    const uint64_t vertex_count = draw.vertices.size();
    for (size_t i = 0; i < draw.indices.size(); ++i)
      if (draw.indices[i] >= vertex_count) check(context, detail::check_index(i, draw.indices[i], vertex_count));
  }

 private:
  const std::string& m_name;
  uint16_t m_major;
};

class ByteWriter {
 public:
  explicit ByteWriter(std::vector<uint8_t>& out) : m_out(out) {}

  template <typename T>
  void put(T value) {
    for (size_t i = 0; i < sizeof(T); ++i) m_out.push_back(static_cast<uint8_t>(value >> (8 * i)));
  }
  void u16(uint16_t v) { put(v); }
  void u32(uint32_t v) { put(v); }
  void u64(uint64_t v) { put(v); }
  void f32(float v) { put(std::bit_cast<uint32_t>(v)); }
  void bytes(const void* data, size_t size) {
    if (size == 0) return;  // data() of an empty vector may be null
    const auto* p = static_cast<const uint8_t*>(data);
    m_out.insert(m_out.end(), p, p + size);
  }
  void string(const std::string& s) {
    u32(static_cast<uint32_t>(s.size()));
    bytes(s.data(), s.size());
  }
  // Writes a chunk header whose length is filled in by end_chunk().
  size_t begin_chunk(const detail::Tag& tag) {
    bytes(tag.data(), tag.size());
    const size_t length_at = m_out.size();
    u64(0);
    return length_at;
  }
  void end_chunk(size_t length_at) { patch_u64(length_at, m_out.size() - (length_at + 8)); }
  void patch_u64(size_t at, uint64_t value) {
    for (size_t i = 0; i < 8; ++i) m_out[at + i] = static_cast<uint8_t>(value >> (8 * i));
  }

 private:
  std::vector<uint8_t>& m_out;
};

uint64_t encoded_size(const Trace& trace) {
  uint64_t size = detail::kHeaderFixedBytes + trace.source.size();
  for (const Frame& frame : trace.frames) {
    size += detail::kChunkHeaderBytes + detail::kFrameFixedBytes + frame.samples.size() * detail::kSampleBytes;
    for (const Draw& draw : frame.draws)
      size += detail::kChunkHeaderBytes + detail::kDrawFixedBytes + draw.name.size() +
              draw.vertices.size() * detail::kVertexBytes + draw.indices.size() * detail::kIndexBytes;
  }
  return size;
}

}  // namespace

void validate(const Trace& trace, const std::string& name) {
  const Validator validator(name, detail::major_for(trace));
  validator.check({}, detail::check_frame_count(trace.frames.size()));
  validator.check({}, detail::check_source_length(trace.source.size()));
  validator.check({}, detail::check_utf8("source", trace.source));
  for (size_t f = 0; f < trace.frames.size(); ++f) validator.frame(trace.frames[f], f);
}

namespace detail {

std::vector<uint8_t> encode_valid(const Trace& trace) {
  std::vector<uint8_t> out;
  out.reserve(encoded_size(trace));
  ByteWriter w(out);
  w.bytes(kMagic.data(), kMagic.size());
  w.u16(major_for(trace));
  w.u16(kVersionMinor);
  w.u32(kByteOrderMark);
  w.u64(0);  // file size, patched below
  w.u32(static_cast<uint32_t>(trace.frames.size()));
  w.string(trace.source);
  for (const Frame& frame : trace.frames) {
    const size_t frame_length_at = w.begin_chunk(kTagFrame);
    w.u32(frame.width);
    w.u32(frame.height);
    w.f32(frame.depth_near);
    w.f32(frame.depth_far);
    w.u32(frame.subpixel_bits);
    w.u32(static_cast<uint32_t>(frame.samples.size()));
    for (const SamplePos& s : frame.samples) {
      w.u16(s.x);
      w.u16(s.y);
    }
    w.u32(static_cast<uint32_t>(frame.draws.size()));
    for (const Draw& draw : frame.draws) {
      const size_t draw_length_at = w.begin_chunk(kTagDraw);
      w.string(draw.name);
      w.u32(draw.flags);
      w.f32(draw.shader_cycles_per_fragment);
      w.u32(draw.varying_bytes_per_vertex);
      w.u32(draw.texture_bytes_per_fragment);
      w.u32(static_cast<uint32_t>(draw.vertices.size()));
      w.u32(static_cast<uint32_t>(draw.indices.size()));
      if constexpr (std::endian::native == std::endian::little) {
        w.bytes(draw.vertices.data(), draw.vertices.size() * sizeof(Vec4));
        w.bytes(draw.indices.data(), draw.indices.size() * sizeof(uint32_t));
      } else {
        for (const Vec4& v : draw.vertices) {
          w.f32(v.x);
          w.f32(v.y);
          w.f32(v.z);
          w.f32(v.w);
        }
        for (uint32_t index : draw.indices) w.u32(index);
      }
      w.end_chunk(draw_length_at);
    }
    w.end_chunk(frame_length_at);
  }
  w.patch_u64(kOffsetFileSize, out.size());
  return out;
}

}  // namespace detail

std::vector<uint8_t> encode(const Trace& trace) {
  validate(trace);
  return detail::encode_valid(trace);
}

}  // namespace tilevis::trace
