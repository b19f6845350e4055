// TileVis trace format: the one reader/writer every implementation uses.
// The byte layout is specified in traces/FORMAT.md.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace tilevis::trace {

// FORMAT.md "Compatibility": this library reads majors 1 and 2 and writes the lowest that
// holds a trace (2 only where a draw shades at sample rate, a flag major 1 lacks).
inline constexpr uint16_t kVersionMajor = 2;  // the newest major
inline constexpr uint16_t kOldestMajor = 1;
inline constexpr uint16_t kVersionMinor = 0;

// Limits the reader enforces (FORMAT.md, "Validation").
inline constexpr uint32_t kMaxViewport = 16384;      // pixels, per axis
inline constexpr uint32_t kMaxSubpixelBits = 8;      // 16.8 fixed point (D3D11 §15.16)
inline constexpr uint32_t kMaxSamples = 16;          // 1, 2, 4, 8 or 16
inline constexpr uint32_t kMaxNameBytes = 4096;
inline constexpr uint32_t kMaxSourceBytes = 65536;

// Per-draw flags. A draw with none of AlphaTested/Blended is opaque.
enum DrawFlag : uint32_t {
  kAlphaTested = 1u << 0,
  kBlended = 1u << 1,
  kShaderWritesDepth = 1u << 2,
  kShaderDiscards = 1u << 3,
  kTriangleSoup = 1u << 4,  // no shared indices: silhouettes are keyed by position
  kSampleRateShading = 1u << 5,  // major 2: the shader runs once per covered sample, not per pixel
};
inline constexpr uint32_t kKnownDrawFlags = 0x3f;  // of the newest major
// The flags a file of `major` may set.
constexpr uint32_t known_draw_flags(uint16_t major) { return major >= 2 ? kKnownDrawFlags : 0x1fu; }

struct Vec4 {
  float x = 0, y = 0, z = 0, w = 1;
  bool operator==(const Vec4&) const = default;
};

// One sample position inside a pixel, in 1/2^subpixel_bits pixel units from the
// pixel's top-left corner (so the pixel centre is 2^(subpixel_bits-1)).
struct SamplePos {
  uint16_t x = 0, y = 0;
  bool operator==(const SamplePos&) const = default;
};

struct Draw {
  std::string name;
  uint32_t flags = 0;
  float shader_cycles_per_fragment = 1.0f;
  uint32_t varying_bytes_per_vertex = 0;
  uint32_t texture_bytes_per_fragment = 0;
  std::vector<Vec4> vertices;      // clip space, as the vertex shader left them
  std::vector<uint32_t> indices;   // triangle list: 3 per triangle, each < vertices.size()

  bool opaque() const { return (flags & (kAlphaTested | kBlended)) == 0; }
  bool per_pixel_only() const { return (flags & (kShaderWritesDepth | kShaderDiscards)) != 0; }
  bool sample_rate() const { return (flags & kSampleRateShading) != 0; }
  size_t triangle_count() const { return indices.size() / 3; }
  bool operator==(const Draw&) const = default;
};

struct Frame {
  uint32_t width = 1920, height = 1080;
  float depth_near = 0.0f, depth_far = 1.0f;   // glDepthRange / D3D viewport MinDepth, MaxDepth
  uint32_t subpixel_bits = 8;
  std::vector<SamplePos> samples;              // sample count = samples.size()
  std::vector<Draw> draws;

  size_t triangle_count() const;
  size_t vertex_count() const;
  bool operator==(const Frame&) const = default;
};

struct Trace {
  std::string source;   // what produced it (scene file, tool); free text
  std::vector<Frame> frames;
  bool operator==(const Trace&) const = default;
};

// The standard sample patterns (D3D11 standard multisample positions for 2, 4, 8, 16;
// the pixel centre for 1), expressed at the given sub-pixel precision.
// Throws std::invalid_argument for an unsupported count.
std::vector<SamplePos> standard_samples(uint32_t count, uint32_t subpixel_bits = 8);

// Every reader rejection: one line naming file, byte offset and what was expected.
class FormatError : public std::runtime_error {
 public:
  FormatError(const std::string& file, uint64_t offset, const std::string& what);
  const std::string& file() const { return m_file; }
  uint64_t offset() const { return m_offset; }

 private:
  std::string m_file;
  uint64_t m_offset;
};

// Serialise to bytes / parse from bytes. `name` is used in error messages only.
std::vector<uint8_t> encode(const Trace& trace);
Trace decode(const uint8_t* data, size_t size, const std::string& name = "<memory>");

// File I/O. write() writes to a temporary file and renames it, so a reader never
// sees a half-written trace. read() throws FormatError (or std::runtime_error for I/O).
void write(const Trace& trace, const std::string& path);
Trace read(const std::string& path);

// Checks a trace in memory with the same rules the reader applies (a writer must not
// produce what the reader would reject). Throws FormatError with offset 0.
void validate(const Trace& trace, const std::string& name = "<memory>");

}  // namespace tilevis::trace
