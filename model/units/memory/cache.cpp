#include "units/memory/cache.h"

#include <stdexcept>

namespace tilevis::sim {

Cache::Cache(const CacheConfig& config) : m_cfg(config) {
  if (!config.line_bytes || !config.ways || config.bytes % (config.line_bytes * config.ways))
    throw std::invalid_argument("cache: size must be a whole number of sets (line x ways)");
  m_sets = config.bytes / (config.line_bytes * config.ways);
  if (!m_sets) throw std::invalid_argument("cache: smaller than one set");
  m_tags.assign(size_t(m_sets) * config.ways, ~uint64_t(0));
}

uint64_t Cache::read(uint64_t address, uint64_t bytes, Traffic& misses) {
  if (!bytes) return 0;
  const uint64_t lb = m_cfg.line_bytes;
  uint64_t hits = 0;
  for (uint64_t line = address / lb; line <= (address + bytes - 1) / lb; ++line) {
    uint64_t* set = &m_tags[size_t(line % m_sets) * m_cfg.ways];
    uint32_t w = 0;
    while (w < m_cfg.ways && set[w] != line) ++w;
    if (w < m_cfg.ways) {
      ++hits;
    } else {
      w = m_cfg.ways - 1;  // evict the least recent
      misses.add(line * lb, lb);
    }
    for (; w > 0; --w) set[w] = set[w - 1];  // move to the front
    set[0] = line;
  }
  m_hits += hits;
  m_misses += (address + bytes - 1) / lb - address / lb + 1 - hits;
  return hits;
}

}  // namespace tilevis::sim
