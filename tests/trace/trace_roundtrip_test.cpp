// Round trips through bytes and files, file-level behaviour of write()/read(), and the
// small accessors of the API.
#include <gtest/gtest.h>

#include <bit>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>

#include "trace_test_support.h"

namespace tilevis::trace {
namespace {

namespace fs = std::filesystem;

// operator== on floats equates -0 and +0; the format must keep every bit.
void expect_bitwise_vertices(const Trace& a, const Trace& b) {
  ASSERT_EQ(a.frames.size(), b.frames.size());
  for (size_t f = 0; f < a.frames.size(); ++f) {
    ASSERT_EQ(a.frames[f].draws.size(), b.frames[f].draws.size());
    for (size_t d = 0; d < a.frames[f].draws.size(); ++d) {
      const auto& va = a.frames[f].draws[d].vertices;
      const auto& vb = b.frames[f].draws[d].vertices;
      ASSERT_EQ(va.size(), vb.size());
      for (size_t i = 0; i < va.size(); ++i) {
        EXPECT_EQ(std::bit_cast<uint32_t>(va[i].x), std::bit_cast<uint32_t>(vb[i].x));
        EXPECT_EQ(std::bit_cast<uint32_t>(va[i].y), std::bit_cast<uint32_t>(vb[i].y));
        EXPECT_EQ(std::bit_cast<uint32_t>(va[i].z), std::bit_cast<uint32_t>(vb[i].z));
        EXPECT_EQ(std::bit_cast<uint32_t>(va[i].w), std::bit_cast<uint32_t>(vb[i].w));
      }
    }
  }
}

Trace round_trip(const Trace& trace) {
  const std::vector<uint8_t> bytes = encode(trace);
  return decode(bytes.data(), bytes.size());
}

class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    m_path = fs::path(::testing::TempDir()) /
             (std::string("tilevis_trace_") + info->test_suite_name() + "_" + info->name());
    fs::remove_all(m_path);
    fs::create_directories(m_path);
  }
  ~TempDir() {
    std::error_code ignored;
    fs::remove_all(m_path, ignored);
  }
  std::string file(const std::string& name) const { return (m_path / name).string(); }
  size_t entries() const { return static_cast<size_t>(std::distance(fs::directory_iterator(m_path), {})); }

 private:
  fs::path m_path;
};

TEST(TraceRoundTrip, Triangle) { EXPECT_EQ(round_trip(test::triangle_trace()), test::triangle_trace()); }

TEST(TraceRoundTrip, MultiFrameWithEmptyNamesEmptyDrawsAndEmptyFrame) {
  const Trace trace = test::multi_frame_trace();
  ASSERT_TRUE(trace.frames[0].draws[1].name.empty());
  ASSERT_TRUE(trace.frames[1].draws[2].vertices.empty());
  ASSERT_TRUE(trace.frames[2].draws.empty());
  const Trace back = round_trip(trace);
  EXPECT_EQ(back, trace);
  expect_bitwise_vertices(back, trace);
}

TEST(TraceRoundTrip, SixteenSamples) {
  Trace trace = test::triangle_trace();
  trace.frames[0].samples = standard_samples(16, 8);
  const Trace back = round_trip(trace);
  ASSERT_EQ(back.frames[0].samples.size(), 16u);
  EXPECT_EQ(back, trace);
}

TEST(TraceRoundTrip, EverySampleCountAndPrecision) {
  for (uint32_t count : {1u, 2u, 4u, 8u, 16u}) {
    for (uint32_t bits = 4; bits <= kMaxSubpixelBits; ++bits) {
      Trace trace = test::triangle_trace();
      trace.frames[0].subpixel_bits = bits;
      trace.frames[0].samples = standard_samples(count, bits);
      EXPECT_EQ(round_trip(trace), trace) << count << " samples at " << bits << " bits";
    }
  }
}

TEST(TraceRoundTrip, ExtremeFloatsKeepEveryBit) {
  Trace trace = test::triangle_trace();
  trace.frames[0].draws[0].vertices = {
      {std::numeric_limits<float>::max(), std::numeric_limits<float>::lowest(), -0.0f, 0.0f},
      {std::numeric_limits<float>::denorm_min(), -std::numeric_limits<float>::denorm_min(),
       std::numeric_limits<float>::min(), -1e-38f},
      {0.1f, -0.2f, 0.3f, -0.0f}};
  trace.frames[0].draws[0].shader_cycles_per_fragment = std::numeric_limits<float>::max();
  const Trace back = round_trip(trace);
  EXPECT_EQ(back, trace);
  expect_bitwise_vertices(back, trace);
}

TEST(TraceRoundTrip, LargeGrid) {
  const Trace trace = test::grid_trace(100);
  ASSERT_EQ(trace.frames[0].triangle_count(), 20000u);
  EXPECT_EQ(round_trip(trace), trace);
}

TEST(TraceRoundTrip, FileWriteRead) {
  const TempDir dir;
  const std::string path = dir.file("multi.tvt");
  const Trace trace = test::multi_frame_trace();
  write(trace, path);
  EXPECT_EQ(read(path), trace);
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  EXPECT_EQ(dir.entries(), 1u);

  std::ifstream in(path, std::ios::binary);
  const std::vector<uint8_t> on_disk((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(on_disk, encode(trace));
}

TEST(TraceRoundTrip, WriteReplacesAnExistingFile) {
  const TempDir dir;
  const std::string path = dir.file("t.tvt");
  write(test::multi_frame_trace(), path);
  write(test::triangle_trace(), path);
  EXPECT_EQ(read(path), test::triangle_trace());
  EXPECT_EQ(dir.entries(), 1u);
}

TEST(TraceFile, WriteOfAnInvalidTraceLeavesNothing) {
  const TempDir dir;
  const std::string path = dir.file("bad.tvt");
  Trace trace = test::triangle_trace();
  trace.frames[0].draws[0].indices[0] = 3;
  try {
    write(trace, path);
    FAIL() << "wrote an invalid trace";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.offset(), 0u);
  }
  EXPECT_EQ(dir.entries(), 0u);
}

TEST(TraceFile, WriteIntoMissingDirectoryIsAnIoError) {
  const TempDir dir;
  const std::string path = dir.file("no/such/dir/t.tvt");
  try {
    write(test::triangle_trace(), path);
    FAIL() << "wrote into a missing directory";
  } catch (const FormatError& e) {
    FAIL() << "an I/O failure reported as a format error: " << e.what();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ".tmp"), std::string::npos) << e.what();
  }
}

TEST(TraceFile, ReadOfMissingFileIsAnIoError) {
  const TempDir dir;
  const std::string path = dir.file("missing.tvt");
  try {
    read(path);
    FAIL() << "read a missing file";
  } catch (const FormatError& e) {
    FAIL() << "an I/O failure reported as a format error: " << e.what();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(TraceFile, ReadNamesTheFileInFormatErrors) {
  const TempDir dir;
  const std::string path = dir.file("short.tvt");
  {
    std::ofstream out(path, std::ios::binary);
    out << "TVT";
  }
  try {
    read(path);
    FAIL() << "read a 3-byte file";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(std::string(e.what()).rfind(path + ": offset 0: bad magic", 0), 0u) << e.what();
  }
}

TEST(TraceApi, FrameCounts) {
  const Trace trace = test::multi_frame_trace();
  EXPECT_EQ(trace.frames[0].triangle_count(), 3u);
  EXPECT_EQ(trace.frames[0].vertex_count(), 7u);
  EXPECT_EQ(trace.frames[1].triangle_count(), 3u);
  EXPECT_EQ(trace.frames[1].vertex_count(), 9u);
  EXPECT_EQ(trace.frames[2].triangle_count(), 0u);
  EXPECT_EQ(trace.frames[2].vertex_count(), 0u);
}

TEST(TraceApi, FormatErrorParts) {
  const FormatError e("traces/x.tvt", 1024, "index 70000 >= vertex count 69666");
  EXPECT_STREQ(e.what(), "traces/x.tvt: offset 1024: index 70000 >= vertex count 69666");
  EXPECT_EQ(e.file(), "traces/x.tvt");
  EXPECT_EQ(e.offset(), 1024u);
}

}  // namespace
}  // namespace tilevis::trace
