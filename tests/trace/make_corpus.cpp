// Writes the fuzz seed corpus: trace_make_corpus traces/fuzz/corpus
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "trace_test_support.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s CORPUS_DIR\n", argv[0]);
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  std::filesystem::create_directories(dir);
  for (const auto& seed : tilevis::trace::test::seed_corpus()) {
    std::ofstream out(dir / seed.name, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(seed.bytes.data()), static_cast<std::streamsize>(seed.bytes.size()));
    if (!out) {
      std::fprintf(stderr, "%s: cannot write\n", (dir / seed.name).c_str());
      return 1;
    }
    std::printf("%s %zu bytes\n", seed.name.c_str(), seed.bytes.size());
  }
  return 0;
}
