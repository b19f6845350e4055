// The library against traces/FORMAT.md: the worked example byte for byte, an encoder
// written from the spec alone, and the compatibility rules for later minor versions.
#include <gtest/gtest.h>

#include "trace_test_support.h"

namespace tilevis::trace {
namespace {

using test::spec_encode;
using test::SpecOptions;

// FORMAT.md "Example", typed from the document.
const std::vector<uint8_t> kExample = {
    0x89, 0x54, 0x56, 0x54, 0x0D, 0x0A, 0x1A, 0x0A,                          // magic
    0x01, 0x00, 0x00, 0x00, 0x04, 0x03, 0x02, 0x01,                          // 1.0, BOM
    0xB2, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,                          // file_size 178
    0x01, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x74,                    // 1 frame, "t"
    0x46, 0x52, 0x41, 0x4D, 0x85, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // FRAM 133
    0x10, 0x00, 0x00, 0x00, 0x08, 0x00, 0x00, 0x00,                          // 16 x 8
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80, 0x3F,                          // depth 0, 1
    0x08, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x80, 0x00, 0x80, 0x00,  // 8 bits, 1 sample
    0x01, 0x00, 0x00, 0x00,                                                  // 1 draw
    0x44, 0x52, 0x41, 0x57, 0x59, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // DRAW 89
    0x01, 0x00, 0x00, 0x00, 0x64,                                            // "d"
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80, 0x3F,                          // flags, cost 1
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,                          // varying, texture
    0x03, 0x00, 0x00, 0x00, 0x03, 0x00, 0x00, 0x00,                          // 3 vertices, 3 indices
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80, 0x3F,
    0x00, 0x00, 0x80, 0x3F, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80, 0x3F,
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80, 0x3F, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80, 0x3F,
    0x00, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00,  // indices
};

TEST(TraceSpec, ExampleIsWrittenByteForByte) {
  ASSERT_EQ(kExample.size(), 178u);
  EXPECT_EQ(encode(test::triangle_trace()), kExample);
}

TEST(TraceSpec, ExampleReadsBack) {
  EXPECT_EQ(decode(kExample.data(), kExample.size()), test::triangle_trace());
}

TEST(TraceSpec, LibraryAndSpecEncoderWriteTheSameBytes) {
  for (const Trace& trace : {test::triangle_trace(), test::multi_frame_trace(), test::grid_trace(5)})
    EXPECT_EQ(encode(trace), spec_encode(trace).bytes) << trace.source;
}

TEST(TraceSpec, SpecEncoderOffsetsMatchTheExample) {
  const test::SpecFile file = spec_encode(test::triangle_trace());
  EXPECT_EQ(file.at("f0"), 0x21u);
  EXPECT_EQ(file.at("f0.width"), 0x2Du);
  EXPECT_EQ(file.at("f0.draw_count"), 0x49u);
  EXPECT_EQ(file.at("f0.d0"), 0x4Du);
  EXPECT_EQ(file.at("f0.d0.flags"), 0x5Eu);
  EXPECT_EQ(file.at("f0.d0.v0.x"), 0x76u);
  EXPECT_EQ(file.at("f0.d0.i0"), 0xA6u);
  EXPECT_EQ(file.at("end"), 0xB2u);
}

TEST(TraceSpec, LaterMinorUnknownChunksAndDrawFieldsAreSkipped) {
  SpecOptions later;
  later.minor = kVersionMinor + 1;
  later.unknown_chunk_in_file = true;
  later.unknown_chunk_in_frame = true;
  later.draw_tail = {1, 2, 3};
  const Trace trace = test::multi_frame_trace();
  const test::SpecFile file = spec_encode(trace, later);
  ASSERT_NE(file.bytes, spec_encode(trace).bytes);
  EXPECT_EQ(decode(file.bytes.data(), file.bytes.size()), trace);
}

TEST(TraceSpec, LaterMinorStillRejectsUnknownFlags) {
  SpecOptions later;
  later.minor = kVersionMinor + 1;
  Trace trace = test::triangle_trace();
  trace.frames[0].draws[0].flags = 1u << 6;  // unknown in every major
  const test::SpecFile file = spec_encode(trace, later);
  try {
    decode(file.bytes.data(), file.bytes.size());
    FAIL() << "accepted an unknown flag bit";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.offset(), file.at("f0.d0.flags"));
  }
}

template <typename F>
FormatError catch_format_error(F&& f) {
  try {
    f();
  } catch (const FormatError& e) {
    return e;
  }
  ADD_FAILURE() << "no FormatError";
  return FormatError("", 0, "");
}

TEST(TraceSpec, SameMinorRejectsUnknownFileLevelChunk) {
  SpecOptions same;
  same.unknown_chunk_in_file = true;
  const test::SpecFile file = spec_encode(test::multi_frame_trace(), same);
  const FormatError e = catch_format_error([&] { decode(file.bytes.data(), file.bytes.size(), "x.tvt"); });
  EXPECT_EQ(e.offset(), file.at("xtra.f0"));
  EXPECT_STREQ(e.what(),
               ("x.tvt: offset " + std::to_string(file.at("xtra.f0")) +
                ": unknown chunk tag 'XTRA' in a version 2.0 file, expected FRAM")  // the seed shades at sample rate
                   .c_str());
}

TEST(TraceSpec, SameMinorRejectsUnknownChunkInFrame) {
  SpecOptions same;
  same.unknown_chunk_in_frame = true;
  const test::SpecFile file = spec_encode(test::multi_frame_trace(), same);
  const FormatError e = catch_format_error([&] { decode(file.bytes.data(), file.bytes.size()); });
  EXPECT_EQ(e.offset(), file.at("xtra.f0.d0"));
  EXPECT_NE(std::string(e.what()).find("frame 0: unknown chunk tag 'XTRA' in a version 2.0 file, expected DRAW"),
            std::string::npos)
      << e.what();
}

TEST(TraceSpec, SameMinorRejectsBytesAfterTheIndices) {
  SpecOptions same;
  same.draw_tail = {7, 7, 7};
  const test::SpecFile file = spec_encode(test::multi_frame_trace(), same);
  const FormatError e = catch_format_error([&] { decode(file.bytes.data(), file.bytes.size()); });
  EXPECT_EQ(e.offset(), file.at("f0.d0.tail"));
  EXPECT_NE(std::string(e.what()).find(
                "frame 0, draw 0: 3 unexpected bytes after the indices, expected end of DRAW payload"),
            std::string::npos)
      << e.what();
}

}  // namespace
}  // namespace tilevis::trace
