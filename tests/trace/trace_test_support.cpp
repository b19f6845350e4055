#include "trace_test_support.h"

#include <bit>
#include <limits>

namespace tilevis::trace::test {

namespace {

class SpecWriter {
 public:
  SpecWriter(SpecFile& file) : m_file(file) {}

  void mark(const std::string& field) { m_file.offsets[field] = m_file.bytes.size(); }
  void u16(uint16_t v) { put(v, 2); }
  void u32(uint32_t v) { put(v, 4); }
  void u64(uint64_t v) { put(v, 8); }
  void f32(float v) { u32(std::bit_cast<uint32_t>(v)); }
  void raw(const std::string& s) { m_file.bytes.insert(m_file.bytes.end(), s.begin(), s.end()); }
  void raw(const std::vector<uint8_t>& b) { m_file.bytes.insert(m_file.bytes.end(), b.begin(), b.end()); }
  uint64_t size() const { return m_file.bytes.size(); }

  // Tag, then a u64 length patched by close(); returns where the length is.
  uint64_t open(const char* tag, const std::string& key) {
    mark(key);
    raw(std::string(tag, 4));
    mark(key + ".length");
    const uint64_t length_at = size();
    u64(0);
    return length_at;
  }
  void close(uint64_t length_at) { put_u64(m_file.bytes, length_at, size() - length_at - 8); }
  void unknown_chunk(const std::string& key) {
    const uint64_t at = open("XTRA", key);
    raw(std::string("hello"));
    close(at);
  }

 private:
  void put(uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) m_file.bytes.push_back(static_cast<uint8_t>(v >> (8 * i)));
  }
  SpecFile& m_file;
};

Vec4 v4(float x, float y, float z, float w) { return Vec4{x, y, z, w}; }

}  // namespace

void put_u16(std::vector<uint8_t>& bytes, uint64_t at, uint16_t value) {
  for (int i = 0; i < 2; ++i) bytes.at(at + i) = static_cast<uint8_t>(value >> (8 * i));
}
void put_u32(std::vector<uint8_t>& bytes, uint64_t at, uint32_t value) {
  for (int i = 0; i < 4; ++i) bytes.at(at + i) = static_cast<uint8_t>(value >> (8 * i));
}
void put_u64(std::vector<uint8_t>& bytes, uint64_t at, uint64_t value) {
  for (int i = 0; i < 8; ++i) bytes.at(at + i) = static_cast<uint8_t>(value >> (8 * i));
}
void put_f32(std::vector<uint8_t>& bytes, uint64_t at, float value) { put_u32(bytes, at, std::bit_cast<uint32_t>(value)); }
void fix_file_size(std::vector<uint8_t>& bytes) { put_u64(bytes, 16, bytes.size()); }

SpecFile spec_encode(const Trace& trace, const SpecOptions& options) {
  SpecFile file;
  SpecWriter w(file);
  w.mark("magic");
  w.raw(std::vector<uint8_t>{0x89, 'T', 'V', 'T', 0x0D, 0x0A, 0x1A, 0x0A});
  uint16_t major = options.major;
  if (major == 0) {
    major = 1;
    for (const Frame& frame : trace.frames)
      for (const Draw& draw : frame.draws)
        if (draw.flags & 0x20u) major = 2;
  }
  w.mark("major");
  w.u16(major);
  w.mark("minor");
  w.u16(options.minor);
  w.mark("bom");
  w.u32(0x01020304);
  w.mark("file_size");
  w.u64(0);
  w.mark("frame_count");
  w.u32(static_cast<uint32_t>(trace.frames.size()));
  w.mark("source_length");
  w.u32(static_cast<uint32_t>(trace.source.size()));
  w.mark("source");
  w.raw(trace.source);
  for (size_t f = 0; f < trace.frames.size(); ++f) {
    const Frame& frame = trace.frames[f];
    const std::string fk = "f" + std::to_string(f);
    if (options.unknown_chunk_in_file) w.unknown_chunk("xtra." + fk);
    const uint64_t frame_length_at = w.open("FRAM", fk);
    w.mark(fk + ".width");
    w.u32(frame.width);
    w.mark(fk + ".height");
    w.u32(frame.height);
    w.mark(fk + ".depth_near");
    w.f32(frame.depth_near);
    w.mark(fk + ".depth_far");
    w.f32(frame.depth_far);
    w.mark(fk + ".subpixel_bits");
    w.u32(frame.subpixel_bits);
    w.mark(fk + ".sample_count");
    w.u32(static_cast<uint32_t>(frame.samples.size()));
    for (size_t i = 0; i < frame.samples.size(); ++i) {
      const std::string sk = fk + ".s" + std::to_string(i);
      w.mark(sk + ".x");
      w.u16(frame.samples[i].x);
      w.mark(sk + ".y");
      w.u16(frame.samples[i].y);
    }
    w.mark(fk + ".draw_count");
    w.u32(static_cast<uint32_t>(frame.draws.size()));
    for (size_t d = 0; d < frame.draws.size(); ++d) {
      const Draw& draw = frame.draws[d];
      const std::string dk = fk + ".d" + std::to_string(d);
      if (options.unknown_chunk_in_frame) w.unknown_chunk("xtra." + dk);
      const uint64_t draw_length_at = w.open("DRAW", dk);
      w.mark(dk + ".name_length");
      w.u32(static_cast<uint32_t>(draw.name.size()));
      w.mark(dk + ".name");
      w.raw(draw.name);
      w.mark(dk + ".flags");
      w.u32(draw.flags);
      w.mark(dk + ".shader_cost");
      w.f32(draw.shader_cycles_per_fragment);
      w.mark(dk + ".varying");
      w.u32(draw.varying_bytes_per_vertex);
      w.mark(dk + ".texture");
      w.u32(draw.texture_bytes_per_fragment);
      w.mark(dk + ".vertex_count");
      w.u32(static_cast<uint32_t>(draw.vertices.size()));
      w.mark(dk + ".index_count");
      w.u32(static_cast<uint32_t>(draw.indices.size()));
      for (size_t i = 0; i < draw.vertices.size(); ++i) {
        const std::string vk = dk + ".v" + std::to_string(i);
        const Vec4& v = draw.vertices[i];
        w.mark(vk + ".x");
        w.f32(v.x);
        w.mark(vk + ".y");
        w.f32(v.y);
        w.mark(vk + ".z");
        w.f32(v.z);
        w.mark(vk + ".w");
        w.f32(v.w);
      }
      for (size_t i = 0; i < draw.indices.size(); ++i) {
        w.mark(dk + ".i" + std::to_string(i));
        w.u32(draw.indices[i]);
      }
      w.mark(dk + ".tail");
      w.raw(options.draw_tail);
      w.mark(dk + ".end");
      w.close(draw_length_at);
    }
    w.mark(fk + ".end");
    w.close(frame_length_at);
  }
  w.mark("end");
  fix_file_size(file.bytes);
  return file;
}

Trace triangle_trace() {
  Trace trace;
  trace.source = "t";
  Frame frame;
  frame.width = 16;
  frame.height = 8;
  frame.subpixel_bits = 8;
  frame.samples = {{128, 128}};
  Draw draw;
  draw.name = "d";
  draw.vertices = {v4(0, 0, 0, 1), v4(1, 0, 0, 1), v4(0, 1, 0, 1)};
  draw.indices = {0, 1, 2};
  frame.draws.push_back(draw);
  trace.frames.push_back(frame);
  return trace;
}

Trace multi_frame_trace() {
  Trace trace;
  trace.source = "tests/trace multi-frame seed";

  Frame f0;
  f0.width = 64;
  f0.height = 32;
  f0.samples = standard_samples(4, 8);
  Draw floor;
  floor.name = "floor";
  floor.shader_cycles_per_fragment = 4.0f;
  floor.varying_bytes_per_vertex = 16;
  floor.texture_bytes_per_fragment = 8;
  floor.vertices = {v4(-1, -1, 0.5f, 1), v4(1, -1, 0.5f, 1), v4(1, 1, 0.5f, 1), v4(-1, 1, 0.5f, 1)};
  floor.indices = {0, 1, 2, 0, 2, 3};
  Draw unnamed;
  unnamed.flags = kAlphaTested;
  unnamed.shader_cycles_per_fragment = 0.0f;
  unnamed.vertices = {v4(-0.5f, -0.5f, 0.25f, 1), v4(0.5f, -0.5f, 0.25f, 1), v4(0, 0.5f, 0.25f, 1)};
  unnamed.indices = {2, 1, 0};
  f0.draws = {floor, unnamed};

  Frame f1;
  f1.width = 1920;
  f1.height = 1080;
  f1.depth_near = 0.75f;
  f1.depth_far = 0.25f;
  f1.subpixel_bits = 4;
  f1.samples = standard_samples(16, 4);
  Draw glass;
  glass.name = "glass";
  glass.flags = kBlended | kTriangleSoup;
  glass.shader_cycles_per_fragment = 12.5f;
  glass.vertices = {v4(-2, -2, 1, 2),   v4(2, -2, 1, 2),    v4(0, 2, 1, 2),
                    v4(-1e-3f, 0, 0, 1), v4(3e6f, -3e6f, 0, 1), v4(0, 1e-30f, -0.0f, 1)};
  glass.indices = {0, 1, 2, 3, 4, 5};
  Draw screen;
  screen.name = "\xC3\xA9" "cran \xE2\x9C\x93 \xF0\x9F\x98\x80";  // "écran ✓ 😀"
  screen.flags = kKnownDrawFlags;
  screen.shader_cycles_per_fragment = 2.5f;
  screen.varying_bytes_per_vertex = 32;
  screen.texture_bytes_per_fragment = 64;
  screen.vertices = {v4(0, 0, -1, -1), v4(1, 0, 0.5f, 0.5f), v4(0, 1, 2, 3)};
  screen.indices = {0, 1, 2};
  Draw empty;
  empty.name = "empty";
  f1.draws = {glass, screen, empty};

  Frame f2;
  f2.width = 1;
  f2.height = 16384;
  f2.depth_near = 1.0f;
  f2.depth_far = 1.0f;
  f2.subpixel_bits = 1;
  f2.samples = standard_samples(1, 1);

  trace.frames = {f0, f1, f2};
  return trace;
}

Trace grid_trace(uint32_t n) {
  Trace trace;
  trace.source = "grid " + std::to_string(n) + "x" + std::to_string(n);
  Frame frame;
  frame.width = 256;
  frame.height = 256;
  frame.samples = standard_samples(8, 8);
  Draw draw;
  draw.name = "grid";
  for (uint32_t y = 0; y <= n; ++y)
    for (uint32_t x = 0; x <= n; ++x)
      draw.vertices.push_back(v4(2.0f * static_cast<float>(x) / static_cast<float>(n) - 1.0f,
                                 2.0f * static_cast<float>(y) / static_cast<float>(n) - 1.0f, 0.5f, 1.0f));
  for (uint32_t y = 0; y < n; ++y) {
    for (uint32_t x = 0; x < n; ++x) {
      const uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      draw.indices.insert(draw.indices.end(), {a, b, d, a, d, c});
    }
  }
  frame.draws.push_back(draw);
  trace.frames.push_back(frame);
  return trace;
}

std::vector<CorpusFile> seed_corpus() {
  std::vector<CorpusFile> corpus;
  corpus.push_back({"valid_triangle.tvt", spec_encode(triangle_trace()).bytes});
  corpus.push_back({"valid_multi_frame.tvt", spec_encode(multi_frame_trace()).bytes});
  corpus.push_back({"valid_grid.tvt", spec_encode(grid_trace(2)).bytes});
  SpecOptions later;
  later.minor = 1;
  later.unknown_chunk_in_file = true;
  later.unknown_chunk_in_frame = true;
  later.draw_tail = {0xAA, 0xBB};
  corpus.push_back({"valid_minor1_extensions.tvt", spec_encode(triangle_trace(), later).bytes});

  SpecFile bad_index = spec_encode(grid_trace(2));
  put_u32(bad_index.bytes, bad_index.at("f0.d0.i5"), 9);
  corpus.push_back({"bad_index.tvt", bad_index.bytes});

  SpecFile bad_nan = spec_encode(triangle_trace());
  put_f32(bad_nan.bytes, bad_nan.at("f0.d0.v1.y"), std::numeric_limits<float>::quiet_NaN());
  corpus.push_back({"bad_nan.tvt", bad_nan.bytes});

  SpecFile truncated = spec_encode(multi_frame_trace());
  truncated.bytes.resize(truncated.at("f1.d0.v2.x"));
  fix_file_size(truncated.bytes);
  corpus.push_back({"bad_truncated.tvt", truncated.bytes});

  SpecFile huge = spec_encode(triangle_trace());
  put_u32(huge.bytes, huge.at("f0.d0.vertex_count"), 0xFFFFFFFFu);
  corpus.push_back({"bad_huge_vertex_count.tvt", huge.bytes});
  return corpus;
}

}  // namespace tilevis::trace::test
