#include "units/geometry_front_end/geometry_front_end.h"

#include <deque>
#include <unordered_set>

namespace tilevis::sim {

GeometryFrontEnd::GeometryFrontEnd(const sc_core::sc_module_name& name, const UnitEnv& env,
                                   const GeometryFrontEndConfig& config, uint32_t batch_triangles)
    : UnitBase(name, env, "geometry front end: index and vertex fetch, post-transform vertex cache"),
      out("out"),
      mem("mem"),
      m_cfg(config),
      m_batch(batch_triangles),
      m_triangles(m_stats.add("triangles", "triangles", "trace triangles fetched")),
      m_vertex_misses(m_stats.add("vertex_cache_misses", "vertices", "vertices fetched from memory")) {
  SC_THREAD(run);
}

void GeometryFrontEnd::prepare() {
  const trace::Frame& f = m_work.frame();
  const uint32_t n = m_work.trace_triangles();
  m_misses.assign(n, 0);
  m_cycles.assign(size_t(n) + 1, 0);
  m_bytes_prefix.assign(size_t(n) + 1, 0);
  uint32_t id = 0;
  for (const trace::Draw& d : f.draws) {
    // FIFO cache of vertex indices, emptied per draw.
    std::deque<uint32_t> fifo;
    std::unordered_set<uint32_t> in_cache;
    const uint64_t vertex_bytes = m_cfg.position_bytes + d.varying_bytes_per_vertex;
    for (size_t t = 0; t < d.indices.size(); t += 3, ++id) {
      uint32_t misses = 0;
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = d.indices[t + size_t(k)];
        if (in_cache.count(v)) continue;
        ++misses;
        fifo.push_back(v);
        in_cache.insert(v);
        if (fifo.size() > m_cfg.vertex_cache_entries) {
          in_cache.erase(fifo.front());
          fifo.pop_front();
        }
      }
      m_misses[id] = misses;
      // One triangle assembled per clock; vertex fetch at its own rate beside it.
      m_cycles[id + 1] = m_cycles[id] + std::max<uint64_t>(1, ceil_div(misses, m_cfg.vertices_per_clock));
      m_bytes_prefix[id + 1] = m_bytes_prefix[id] + 3ull * m_cfg.index_bytes + misses * vertex_bytes;
    }
  }
}

Cost GeometryFrontEnd::cost(const Item& it) const {
  Cost c;
  c.cycles = m_cycles[it.first + it.count] - m_cycles[it.first] + (it.last ? m_cfg.latency_cycles : 0);
  // Index and vertex streams, contiguous in the order the draws read them.
  c.reads.add(region::vertices + m_bytes_prefix[it.first], m_bytes_prefix[it.first + it.count] - m_bytes_prefix[it.first]);
  return c;
}

void GeometryFrontEnd::account(const Item& it, const Cost& c) {
  m_busy.value += double(c.cycles);
  m_items.value += 1;
  m_bytes.value += double(c.reads.bytes());
  m_triangles.value += it.count;
  for (uint32_t i = it.first; i < it.first + it.count; ++i) m_vertex_misses.value += m_misses[i];
}

std::vector<Item> GeometryFrontEnd::batches() const {
  std::vector<Item> items;
  for (uint32_t k = 0; k < m_work.segment_count(); ++k) {
    const uint32_t first = m_work.segment_first(k), end = m_work.segment_end(k);
    uint32_t a = first;
    do {  // an empty frame still sends one (empty) last batch, so that it renders
      Item it;
      it.segment = k;
      it.first = a;
      it.count = std::min(m_batch, end - a);
      it.last = a + it.count == end;
      items.push_back(it);
      a += it.count;
    } while (a < end);
  }
  return items;
}

void GeometryFrontEnd::run() {
  for (const Item& it : batches()) {
    const Cost c = cost(it);
    // Index and vertex streams are sequential: prefetched after a segment's first batch.
    const sc_core::sc_time memory = transfer(mem, tlm::TLM_READ_COMMAND, c.reads, it.first != m_work.segment_first(it.segment));
    spend(c.cycles, memory, nullptr, TileUnit::count);
    m_items.value += 1;
    m_triangles.value += it.count;
    for (uint32_t i = it.first; i < it.first + it.count; ++i) m_vertex_misses.value += m_misses[i];
    push(out, it);
  }
}

}  // namespace tilevis::sim
