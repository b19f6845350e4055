// A set-associative cache with LRU replacement, plain C++ (timing-free): what a unit's
// stream cache keeps, and which lines go to DRAM. Read-only use (a miss allocates).
#pragma once

#include <cstdint>
#include <vector>

#include "units/memory/traffic.h"

namespace tilevis::sim {

struct CacheConfig {
  uint32_t bytes = 16384;
  uint32_t line_bytes = 64;
  uint32_t ways = 4;
};

class Cache {
 public:
  explicit Cache(const CacheConfig& config);
  // Reads [address, address + bytes): the lines it misses are added to `misses`.
  // Returns the number of lines that hit.
  uint64_t read(uint64_t address, uint64_t bytes, Traffic& misses);
  uint64_t hits() const { return m_hits; }
  uint64_t misses() const { return m_misses; }
  const CacheConfig& config() const { return m_cfg; }

 private:
  CacheConfig m_cfg;
  uint32_t m_sets;
  std::vector<uint64_t> m_tags;  // set-major, way 0 most recent; ~0: empty
  uint64_t m_hits = 0, m_misses = 0;
};

}  // namespace tilevis::sim
