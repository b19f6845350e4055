// Byte layout constants of the trace format (traces/FORMAT.md, "Layout").
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace tilevis::trace::detail {

// PNG-style magic: the high-bit byte catches 7-bit channels, CR LF catches newline
// conversion, ^Z stops `type` on DOS, the final LF catches LF -> CR LF.
inline constexpr std::array<uint8_t, 8> kMagic = {0x89, 'T', 'V', 'T', 0x0D, 0x0A, 0x1A, 0x0A};
inline constexpr uint32_t kByteOrderMark = 0x01020304;

inline constexpr uint64_t kOffsetMajor = 8;
inline constexpr uint64_t kOffsetMinor = 10;
inline constexpr uint64_t kOffsetByteOrderMark = 12;
inline constexpr uint64_t kOffsetFileSize = 16;
inline constexpr uint64_t kOffsetFrameCount = 24;
inline constexpr uint64_t kOffsetSourceLength = 28;
inline constexpr uint64_t kHeaderFixedBytes = 32;

inline constexpr uint64_t kChunkHeaderBytes = 12;  // 4-byte tag + u64 payload length
using Tag = std::array<char, 4>;
inline constexpr Tag kTagFrame = {'F', 'R', 'A', 'M'};
inline constexpr Tag kTagDraw = {'D', 'R', 'A', 'W'};

// FRAM payload: width, height, depth_near, depth_far, subpixel_bits, sample_count,
// 4 bytes per sample, draw_count; the smallest has one sample.
inline constexpr uint64_t kFrameFixedBytes = 7 * 4;
inline constexpr uint64_t kSampleBytes = 4;
inline constexpr uint64_t kMinFrameChunkBytes = kChunkHeaderBytes + kFrameFixedBytes + kSampleBytes;

// DRAW payload: name_length, flags, shader_cycles_per_fragment, varying_bytes_per_vertex,
// texture_bytes_per_fragment, vertex_count, index_count; the name and arrays follow.
inline constexpr uint64_t kDrawFixedBytes = 7 * 4;
inline constexpr uint64_t kMinDrawChunkBytes = kChunkHeaderBytes + kDrawFixedBytes;
inline constexpr uint64_t kVertexBytes = 16;
inline constexpr uint64_t kIndexBytes = 4;

}  // namespace tilevis::trace::detail
