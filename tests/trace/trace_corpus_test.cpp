// The committed fuzz seed corpus (traces/fuzz/corpus) through the ordinary build:
// every file decodes or is a FormatError, and the seeds are what the generator makes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "trace_test_support.h"

namespace tilevis::trace {
namespace {

namespace fs = std::filesystem;

std::vector<uint8_t> slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::vector<fs::path> corpus_files() {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(TILEVIS_TRACE_CORPUS_DIR))
    if (entry.is_regular_file()) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

TEST(TraceCorpus, EveryFileDecodesOrIsAFormatError) {
  const auto files = corpus_files();
  ASSERT_GE(files.size(), test::seed_corpus().size());
  for (const fs::path& path : files) {
    const std::vector<uint8_t> bytes = slurp(path);
    const std::string name = path.filename().string();
    try {
      const Trace trace = decode(bytes.data(), bytes.size(), name);
      EXPECT_NE(name.rfind("bad_", 0), 0u) << name << " was accepted";
      EXPECT_NO_THROW(validate(trace)) << name;
    } catch (const FormatError& e) {
      EXPECT_NE(name.rfind("valid_", 0), 0u) << e.what();
      EXPECT_EQ(e.file(), name);
      EXPECT_LE(e.offset(), bytes.size());
    }
  }
}

// Regenerate with the trace_make_corpus target if the format changes on purpose.
TEST(TraceCorpus, SeedsMatchTheGenerator) {
  for (const test::CorpusFile& seed : test::seed_corpus()) {
    const fs::path path = fs::path(TILEVIS_TRACE_CORPUS_DIR) / seed.name;
    ASSERT_TRUE(fs::exists(path)) << path;
    EXPECT_EQ(slurp(path), seed.bytes) << path;
    EXPECT_LE(seed.bytes.size(), 1024u) << seed.name << ": seeds stay small so the fuzzer mutates them quickly";
  }
}

}  // namespace
}  // namespace tilevis::trace
