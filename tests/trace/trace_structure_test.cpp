// Structural rejections of FORMAT.md: header, sizes, truncation, counts against the
// bytes present, chunk order, trailing bytes; and the reader's resource bounds.
#include <gtest/gtest.h>

#include "alloc_probe.h"
#include "expect_format_error.h"
#include "trace_test_support.h"

namespace tilevis::trace {
namespace {

using test::expect_rejected;
using test::put_u16;
using test::put_u32;
using test::put_u64;
using test::SpecFile;
using test::spec_encode;

SpecFile triangle() { return spec_encode(test::triangle_trace()); }
SpecFile multi() { return spec_encode(test::multi_frame_trace()); }

std::vector<uint8_t> prefix(const std::vector<uint8_t>& bytes, size_t size) {
  return {bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(size)};
}

TEST(TraceHeader, BadMagic) {
  SpecFile f = triangle();
  f.bytes[3] = 'X';
  expect_rejected(f.bytes, 0, "bad magic 89 54 56 58 0D 0A 1A 0A, expected 89 54 56 54 0D 0A 1A 0A (a TileVis trace)");
}

TEST(TraceHeader, TextFileIsBadMagic) {
  const std::string text = "v 0 0 0\nv 1 0 0\nf 1 2 3\n";
  expect_rejected(std::vector<uint8_t>(text.begin(), text.end()), 0, "bad magic 76 20 30 20 30 20 30 0A");
}

TEST(TraceHeader, NewlineConvertedFileIsBadMagic) {
  std::vector<uint8_t> bytes = triangle().bytes;
  bytes.erase(bytes.begin() + 4);  // CR LF -> LF
  expect_rejected(bytes, 0, "bad magic");
}

TEST(TraceHeader, EmptyInputIsTruncated) {
  expect_rejected({}, 0, "truncated: magic needs 8 bytes, 0 remain in file");
  EXPECT_THROW(decode(nullptr, 0), FormatError);
}

TEST(TraceHeader, MagicPrefixIsTruncated) {
  expect_rejected(prefix(triangle().bytes, 5), 0, "truncated: magic needs 8 bytes, 5 remain in file");
}

TEST(TraceHeader, UnsupportedMajorVersion) {
  SpecFile f = triangle();
  put_u16(f.bytes, 8, 3);
  expect_rejected(f.bytes, 8, "major version 3, expected 1 to 2");
  put_u16(f.bytes, 8, 0);
  expect_rejected(f.bytes, 8, "major version 0, expected 1 to 2");
}

// Major 2 adds one flag, sample-rate shading (bit 5); a file is of the lowest major that
// holds it, so each trace keeps one encoding and readers of major 1 keep reading every
// trace without that flag.
TEST(TraceHeader, SampleRateShadingIsMajorTwoAndOnlyThere) {
  Trace trace = test::triangle_trace();
  std::vector<uint8_t> bytes = encode(trace);
  EXPECT_EQ(bytes[8], 1);
  trace.frames[0].draws[0].flags |= kSampleRateShading;
  bytes = encode(trace);
  EXPECT_EQ(bytes[8], 2);
  EXPECT_EQ(bytes, test::spec_encode(trace).bytes);
  EXPECT_EQ(decode(bytes.data(), bytes.size()), trace);
  EXPECT_TRUE(decode(bytes.data(), bytes.size()).frames[0].draws[0].sample_rate());

  test::SpecOptions major1;
  major1.major = 1;
  SpecFile old = test::spec_encode(trace, major1);  // the flag in a version 1 file: unknown there
  expect_rejected(old.bytes, old.at("f0.d0.flags"), "frame 0, draw 0: flags 0x20 set unknown bits 0x20, expected only bits of 0x1f (version 1)");

  SpecFile plain = triangle();  // major 2 without the flag: not the trace's one encoding
  put_u16(plain.bytes, 8, 2);
  expect_rejected(plain.bytes, 8, "major version 2 but no draw shades at sample rate, expected 1");
}

TEST(TraceHeader, BigEndianByteOrderMark) {
  SpecFile f = triangle();
  put_u32(f.bytes, 12, 0x04030201);
  expect_rejected(f.bytes, 12, "byte-order mark 01 02 03 04, expected 04 03 02 01 (0x01020304 little-endian)");
}

TEST(TraceHeader, FileSizeFieldTooLarge) {
  SpecFile f = triangle();
  put_u64(f.bytes, 16, f.bytes.size() + 1);
  expect_rejected(f.bytes, 16, "file size field 179, expected the actual size 178");
}

TEST(TraceHeader, FileSizeFieldTooSmall) {
  SpecFile f = triangle();
  put_u64(f.bytes, 16, 0);
  expect_rejected(f.bytes, 16, "file size field 0, expected the actual size 178");
}

TEST(TraceTruncation, LastByteMissing) {
  const SpecFile f = triangle();
  expect_rejected(prefix(f.bytes, f.bytes.size() - 1), 16, "file size field 178, expected the actual size 177");
}

TEST(TraceTruncation, InsideMinorVersion) {
  expect_rejected(prefix(triangle().bytes, 11), 10, "truncated: minor version needs 2 bytes, 1 remain in file");
}

TEST(TraceTruncation, InsideFileSizeField) {
  expect_rejected(prefix(triangle().bytes, 20), 16, "truncated: file size needs 8 bytes, 4 remain in file");
}

TEST(TraceTruncation, InsideSourceLength) {
  expect_rejected(prefix(triangle().bytes, 30), 16, "file size field 178, expected the actual size 30");
  std::vector<uint8_t> bytes = prefix(triangle().bytes, 30);
  test::fix_file_size(bytes);
  expect_rejected(bytes, 28, "truncated: source length needs 4 bytes, 2 remain in file");
}

TEST(TraceTruncation, InsideVerticesWithMatchingFileSize) {
  const SpecFile f = multi();
  std::vector<uint8_t> bytes = prefix(f.bytes, f.at("f1.d0.v2.x"));
  test::fix_file_size(bytes);
  expect_rejected(bytes, f.at("f1.length"), "chunk 'FRAM' payload length");
}

TEST(TraceTruncation, FieldCutByDrawPayloadLength) {
  SpecFile f = multi();
  // "floor": name_length (4) + name (5) + flags (4) + one byte of the shader cost.
  put_u64(f.bytes, f.at("f0.d0.length"), 14);
  expect_rejected(f.bytes, f.at("f0.d0.shader_cost"),
                  "frame 0, draw 0: truncated: shader cycles per fragment needs 4 bytes, 1 remain in DRAW payload");
}

TEST(TraceTruncation, FrameFieldCutByFramePayloadLength) {
  SpecFile f = triangle();
  put_u64(f.bytes, f.at("f0.length"), 10);
  expect_rejected(f.bytes, f.at("f0.depth_near"),
                  "frame 0: truncated: depth_near needs 4 bytes, 2 remain in FRAM payload");
}

TEST(TraceTruncation, EveryPrefixIsRejected) {
  for (const std::vector<uint8_t>& full : {triangle().bytes, multi().bytes}) {
    for (size_t size = 0; size < full.size(); ++size) {
      std::vector<uint8_t> bytes = prefix(full, size);
      for (bool fixed_size : {false, true}) {
        if (fixed_size && size >= 24) test::fix_file_size(bytes);
        try {
          decode(bytes.data(), bytes.size());
          ADD_FAILURE() << "accepted a " << size << "-byte prefix of " << full.size();
        } catch (const FormatError& e) {
          EXPECT_LE(e.offset(), size);
        }
      }
    }
  }
}

TEST(TraceCounts, FrameCountBeyondFile) {
  SpecFile f = triangle();
  put_u32(f.bytes, f.at("frame_count"), 0xFFFFFFFFu);
  expect_rejected(f.bytes, 24, "frame count 4294967295 needs at least 188978560980 bytes, 145 remain in file");
}

TEST(TraceCounts, SourceLengthBeyondFile) {
  SpecFile f = triangle();
  put_u32(f.bytes, f.at("source_length"), 60000);
  expect_rejected(f.bytes, 32, "truncated: source needs 60000 bytes, 146 remain in file");
}

TEST(TraceCounts, FramePayloadLengthBeyondFile) {
  SpecFile f = triangle();
  put_u64(f.bytes, f.at("f0.length"), ~uint64_t{0});
  expect_rejected(f.bytes, f.at("f0.length"),
                  "chunk 'FRAM' payload length 18446744073709551615 exceeds the 133 bytes remaining in file");
}

TEST(TraceCounts, DrawPayloadLengthBeyondFrame) {
  SpecFile f = triangle();
  put_u64(f.bytes, f.at("f0.d0.length"), 90);
  expect_rejected(f.bytes, f.at("f0.d0.length"),
                  "frame 0: chunk 'DRAW' payload length 90 exceeds the 89 bytes remaining in FRAM payload");
}

TEST(TraceCounts, DrawCountBeyondFrame) {
  SpecFile f = triangle();
  put_u32(f.bytes, f.at("f0.draw_count"), 0xFFFFFFFFu);
  expect_rejected(f.bytes, f.at("f0.draw_count"),
                  "frame 0: draw count 4294967295 needs at least 171798691800 bytes, 101 remain in FRAM payload");
}

TEST(TraceCounts, VertexCountBeyondDraw) {
  SpecFile f = triangle();
  put_u32(f.bytes, f.at("f0.d0.vertex_count"), 0xFFFFFFFFu);
  expect_rejected(f.bytes, f.at("f0.d0.vertex_count"),
                  "frame 0, draw 0: vertex count 4294967295 needs 68719476720 bytes, 60 remain in DRAW payload");
}

TEST(TraceCounts, IndexCountBeyondDraw) {
  SpecFile f = triangle();
  put_u32(f.bytes, f.at("f0.d0.index_count"), 0xFFFFFFFFu);  // a multiple of 3
  expect_rejected(f.bytes, f.at("f0.d0.index_count"),
                  "frame 0, draw 0: index count 4294967295 needs 17179869180 bytes, 12 remain in DRAW payload");
}

TEST(TraceCounts, NameLengthBeyondDraw) {
  SpecFile f = triangle();
  put_u32(f.bytes, f.at("f0.d0.name_length"), 4000);
  expect_rejected(f.bytes, f.at("f0.d0.name"), "frame 0, draw 0: truncated: name needs 4000 bytes, 85 remain in DRAW payload");
}

TEST(TraceCounts, SampleCountBeyondFrame) {
  SpecFile f = spec_encode([] {
    Trace t = test::triangle_trace();
    t.frames[0].draws.clear();
    return t;
  }());
  put_u32(f.bytes, f.at("f0.sample_count"), 16);
  expect_rejected(f.bytes, f.at("f0.s0.x"),
                  "frame 0: truncated: sample positions needs 64 bytes, 8 remain in FRAM payload");
}

// A count of 2^32-1 must fail on the size check, not on an attempt to allocate.
TEST(TraceCounts, HugeCountsFailWithoutLargeAllocations) {
  std::vector<std::vector<uint8_t>> files;
  for (const char* field : {"frame_count", "f0.draw_count", "f0.d0.vertex_count", "f0.d0.index_count"}) {
    SpecFile f = triangle();
    put_u32(f.bytes, f.at(field), 0xFFFFFFFFu);
    files.push_back(f.bytes);
  }
  for (const std::vector<uint8_t>& bytes : files) {
    test::reset_largest_allocation();
    EXPECT_THROW(decode(bytes.data(), bytes.size()), FormatError);
    EXPECT_LT(test::largest_allocation(), 4096u);
  }
}

TEST(TraceCounts, AllocationProbeSeesLargeAllocations) {
  test::reset_largest_allocation();
  const SpecFile f = spec_encode(test::grid_trace(40));
  const Trace trace = decode(f.bytes.data(), f.bytes.size());
  EXPECT_GE(test::largest_allocation(), trace.frames[0].draws[0].vertices.size() * sizeof(Vec4));
}

TEST(TraceChunks, FewerFramesThanCounted) {
  SpecFile f = triangle();
  put_u32(f.bytes, f.at("frame_count"), 2);
  expect_rejected(f.bytes, f.at("end"), "file ends after 1 of 2 frames");
}

TEST(TraceChunks, FewerDrawsThanCounted) {
  SpecFile f = triangle();
  put_u32(f.bytes, f.at("f0.draw_count"), 2);
  expect_rejected(f.bytes, f.at("f0.end"), "frame 0: FRAM payload ends after 1 of 2 draws");
}

TEST(TraceChunks, FramBeyondFrameCount) {
  SpecFile f = triangle();
  const uint64_t end = f.bytes.size();
  f.bytes.insert(f.bytes.end(), f.bytes.begin() + static_cast<std::ptrdiff_t>(f.at("f0")), f.bytes.end());
  test::fix_file_size(f.bytes);
  expect_rejected(f.bytes, end, "FRAM chunk beyond the header's frame count 1, expected end of file");
}

TEST(TraceChunks, DrawBeyondDrawCount) {
  SpecFile f = multi();
  put_u32(f.bytes, f.at("f0.draw_count"), 1);
  expect_rejected(f.bytes, f.at("f0.d1"), "frame 0: DRAW chunk beyond the frame's draw count 1, expected end of FRAM payload");
}

TEST(TraceChunks, UnknownTagWhereDrawExpected) {
  SpecFile f = multi();
  f.bytes[f.at("f1.d2") + 3] = 'X';
  expect_rejected(f.bytes, f.at("f1.d2"), "frame 1: unknown chunk tag 'DRAX' in a version 2.0 file, expected DRAW");
}

TEST(TraceChunks, NonPrintableTagShownInHex) {
  SpecFile f = triangle();
  f.bytes[f.at("f0")] = 0x01;
  expect_rejected(f.bytes, f.at("f0"), "unknown chunk tag 01 52 41 4D (hex) in a version 1.0 file, expected FRAM");
}

TEST(TraceTrailing, FewBytesAfterLastFrame) {
  SpecFile f = triangle();
  const uint64_t end = f.bytes.size();
  f.bytes.insert(f.bytes.end(), {0, 0, 0, 0, 0});
  test::fix_file_size(f.bytes);
  expect_rejected(f.bytes, end, "5 trailing bytes after the last frame, expected end of file");
}

TEST(TraceTrailing, ChunkSizedGarbageAfterLastFrame) {
  SpecFile f = triangle();
  const uint64_t end = f.bytes.size();
  f.bytes.resize(f.bytes.size() + 20, 0);
  test::fix_file_size(f.bytes);
  expect_rejected(f.bytes, end, "unknown chunk tag 00 00 00 00 (hex) in a version 1.0 file, expected end of file");
}

TEST(TraceTrailing, AppendedBytesWithoutSizeFix) {
  SpecFile f = triangle();
  f.bytes.push_back(0);
  expect_rejected(f.bytes, 16, "file size field 178, expected the actual size 179");
}

// Every single-byte corruption of a seed either decodes to a trace that re-encodes to
// exactly those bytes (1.0 is canonical) or is a FormatError.
TEST(TraceRobustness, SingleByteCorruptions) {
  const std::vector<uint8_t> seed = multi().bytes;
  size_t accepted = 0, rejected = 0;
  for (size_t i = 0; i < seed.size(); ++i) {
    for (int variant = 0; variant < 4; ++variant) {
      std::vector<uint8_t> bytes = seed;
      const uint8_t b = bytes[i];
      bytes[i] = variant == 0 ? uint8_t{0} : variant == 1 ? uint8_t{0xFF} : static_cast<uint8_t>(b ^ (variant == 2 ? 0x01 : 0x80));
      if (bytes[i] == b) continue;
      try {
        const Trace trace = decode(bytes.data(), bytes.size());
        if (i == 10 || i == 11)  // a later minor: same content, written back as 1.0
          EXPECT_EQ(trace, test::multi_frame_trace());
        else
          EXPECT_EQ(encode(trace), bytes) << "byte " << i;
        ++accepted;
      } catch (const FormatError&) {
        ++rejected;
      }
    }
  }
  EXPECT_GT(accepted, 0u);  // vertex and other free-valued bytes
  EXPECT_GT(rejected, 0u);
}

}  // namespace
}  // namespace tilevis::trace
