// FNV-1a 64: the one hash of bytes TileVis uses for identities (a trace file's, a frame's, an
// id buffer's) and checksums. Continue a hash over more bytes by passing it back as `h`.
#pragma once

#include <cstddef>
#include <cstdint>

namespace tilevis {

inline constexpr uint64_t kFnv1a64Basis = 1469598103934665603ull;
inline constexpr uint64_t kFnv1a64Prime = 1099511628211ull;

inline uint64_t fnv1a64(const void* data, size_t n, uint64_t h = kFnv1a64Basis) {
  const auto* p = static_cast<const uint8_t*>(data);
  for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * kFnv1a64Prime;
  return h;
}

}  // namespace tilevis
