// libFuzzer target for the trace reader. Beyond "no crash, no leak, no UB" it checks
// the reader's contract (FORMAT.md): whatever decode() accepts passes validate(),
// survives encode()/decode() unchanged, and, for a file of this library's minor
// version, re-encodes to exactly the input bytes (1.0 is canonical).
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "tilevis/trace.h"

using namespace tilevis::trace;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Trace trace;
  try {
    trace = decode(data, size, "fuzz");
  } catch (const FormatError&) {
    return 0;
  }
  validate(trace);  // an exception escaping here aborts the run: a reader/validate mismatch
  const std::vector<uint8_t> bytes = encode(trace);
  if (decode(bytes.data(), bytes.size()) != trace) __builtin_trap();
  const bool same_minor = size >= 12 && data[10] == (kVersionMinor & 0xFF) && data[11] == (kVersionMinor >> 8);
  if (same_minor && (bytes.size() != size || std::memcmp(bytes.data(), data, size) != 0)) __builtin_trap();
  return 0;
}
