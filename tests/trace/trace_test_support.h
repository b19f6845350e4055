// Test-side helpers for the trace format: an encoder written from traces/FORMAT.md
// alone (no validation, so it can write every defect), which records the offset of
// every field it writes, and the seed traces shared by the tests and the fuzz corpus.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "tilevis/trace.h"

namespace tilevis::trace::test {

struct SpecOptions {
  uint16_t major = 0;  // 0: the lowest that holds the trace (2 where a draw sets flag bit 5, else 1)
  uint16_t minor = 0;
  bool unknown_chunk_in_file = false;   // an "XTRA" chunk before each FRAM chunk
  bool unknown_chunk_in_frame = false;  // an "XTRA" chunk before each DRAW chunk
  std::vector<uint8_t> draw_tail;       // appended to each DRAW payload
};

// Field offsets are keyed as "frame_count", "source", "f1.width", "f1.s5.x",
// "f1.d0.length", "f1.d0.v2.w", "f1.d0.i4", "f1.d0.end", "xtra.f0", "end", ...
// ("f1" alone is the FRAM tag, "f1.d0" the DRAW tag).
struct SpecFile {
  std::vector<uint8_t> bytes;
  std::map<std::string, uint64_t> offsets;

  uint64_t at(const std::string& field) const { return offsets.at(field); }
};

SpecFile spec_encode(const Trace& trace, const SpecOptions& options = {});

void put_u16(std::vector<uint8_t>& bytes, uint64_t at, uint16_t value);
void put_u32(std::vector<uint8_t>& bytes, uint64_t at, uint32_t value);
void put_u64(std::vector<uint8_t>& bytes, uint64_t at, uint64_t value);
void put_f32(std::vector<uint8_t>& bytes, uint64_t at, float value);
// Sets the header's file_size field to the vector's size.
void fix_file_size(std::vector<uint8_t>& bytes);

// The FORMAT.md example: one frame, one draw, one triangle.
Trace triangle_trace();
// Three frames: 4 samples and two draws (one unnamed); 16 samples at 4 subpixel bits,
// reversed depth, every flag, a UTF-8 name, an empty draw; and an empty frame.
Trace multi_frame_trace();
// An indexed n x n quad grid in one draw.
Trace grid_trace(uint32_t n);

struct CorpusFile {
  std::string name;  // valid_* decodes, bad_* is rejected
  std::vector<uint8_t> bytes;
};
// The committed fuzz seed corpus (traces/fuzz/corpus), byte for byte.
std::vector<CorpusFile> seed_corpus();

}  // namespace tilevis::trace::test
