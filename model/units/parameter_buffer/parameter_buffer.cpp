#include "units/parameter_buffer/parameter_buffer.h"

#include <stdexcept>
#include <string>

namespace tilevis::sim {

ParameterBuffer::ParameterBuffer(const sc_core::sc_module_name& name, const UnitEnv& env,
                                 const ParameterBufferConfig& config)
    : UnitBase(name, env, "parameter buffer: primitive blocks and tile control streams in DRAM, flushed when full"),
      socket("socket"),
      mem("mem"),
      in("in"),
      ready("ready"),
      released("released"),
      m_cfg(config),
      m_written(m_stats.add("bytes_written", "bytes", "primitive blocks, vertices, edges and control streams written")),
      m_read(m_stats.add("bytes_read", "bytes", "read back by tile fetch")),
      m_peak(m_stats.add("peak_bytes", "bytes", "most bytes held at once")),
      m_partial(m_stats.add("partial_renders", "renders", "renders forced by a full buffer (flushes)")),
      m_capacity(m_stats.add("capacity_bytes", "bytes", "configured size")) {
  socket.register_b_transport(this, &ParameterBuffer::b_transport);
  m_capacity.value = double(m_cfg.capacity_bytes);
  SC_THREAD(collect);
  SC_THREAD(release);
}

uint64_t ParameterBuffer::varying_bytes(uint32_t draw) const {
  return 3ull * m_work.frame().draws[draw].varying_bytes_per_vertex;
}

void ParameterBuffer::prepare(const GeometryFrontEnd& front_end) {
  const vis::Setup& s = m_work.setup();
  const uint32_t n = m_work.trace_triangles();
  m_prefix.assign(size_t(n) + 1, 0);
  for (uint32_t id = 0; id < n; ++id) {
    uint64_t b = 0;
    uint32_t binned_fans = 0;
    for (uint32_t t = m_work.setup_begin(id); t < m_work.setup_begin(id + 1); ++t) {
      if (!s.triangles[t].front || m_work.tile_refs(t) == 0) continue;  // culled or off screen: not written
      ++binned_fans;
      b += m_cfg.triangle_bytes + uint64_t(m_work.tile_refs(t)) * m_cfg.reference_bytes;
    }
    if (binned_fans) {
      // New vertices: the cache misses, plus one per extra fan triangle of a clipped one.
      const uint64_t vertex = m_cfg.vertex_bytes + m_work.frame().draws[m_work.draw_of(id)].varying_bytes_per_vertex;
      b += (front_end.vertex_misses(id) + binned_fans - 1) * vertex;
    }
    const auto [e0, e1] = m_work.owned_edges(id);
    for (const uint32_t* e = e0; e != e1; ++e) b += m_cfg.edge_bytes + uint64_t(m_work.edge_refs(*e)) * m_cfg.reference_bytes;
    m_prefix[id + 1] = m_prefix[id] + b;
  }
  // Flush plan: a segment ends before the triangle that would overflow the buffer.
  std::vector<uint32_t> first_ids{0};
  m_segment_bytes.assign(1, 0);
  for (uint32_t id = 0; id < n; ++id) {
    const uint64_t b = bytes(id, id + 1);
    if (b > m_cfg.capacity_bytes)
      throw std::runtime_error("pb.capacity_bytes = " + std::to_string(m_cfg.capacity_bytes) + ": triangle " +
                               std::to_string(id) + " alone needs " + std::to_string(b) + " bytes");
    if (m_segment_bytes.back() + b > m_cfg.capacity_bytes) {
      first_ids.push_back(id);
      m_segment_bytes.push_back(0);
    }
    m_segment_bytes.back() += b;
  }
  m_work.set_segments(first_ids);
}

void ParameterBuffer::account_analytic(uint64_t written, uint64_t read) {
  m_written.value += double(written);
  m_read.value += double(read);
  m_bytes.value += double(written + read);
  for (uint64_t b : m_segment_bytes) m_peak.value = std::max(m_peak.value, double(b));
  m_partial.value = double(m_segment_bytes.size() - 1);
}

void ParameterBuffer::b_transport(int, tlm::tlm_generic_payload& p, sc_core::sc_time& delay) {
  const uint64_t len = p.get_data_length();
  if (p.is_write()) {
    // A full buffer holds the tiling engine until a (partial) render frees pages.
    while (m_used + len > m_cfg.capacity_bytes) sc_core::wait(m_freed);
    m_used += len;
    m_peak.value = std::max(m_peak.value, double(m_used));
    m_written.value += double(len);
  } else {
    m_read.value += double(len);
  }
  m_bytes.value += double(len);
  mem->b_transport(p, delay);
}

void ParameterBuffer::collect() {
  for (;;) {
    const Item it = in.read();
    m_items.value += 1;
    if (arrivals) {
      arrivals->log.push_back({it.first, cycles(sc_core::sc_time_stamp())});
      arrivals->arrived.notify(sc_core::SC_ZERO_TIME);
    }
    if (!it.last) continue;
    m_ready_cycles.push_back(cycles(sc_core::sc_time_stamp()));
    if (it.segment + 1 < m_work.segment_count()) m_partial.value += 1;
    ready.write(it.segment);
  }
}

uint64_t ParameterBuffer::total_bytes() const {
  uint64_t b = 0;
  for (uint64_t s : m_segment_bytes) b += s;
  return b;
}

void ParameterBuffer::release() {
  for (;;) {
    const uint32_t k = released.read();
    m_used -= std::min(m_used, m_segment_bytes[k]);
    m_freed.notify(sc_core::SC_ZERO_TIME);
  }
}

}  // namespace tilevis::sim
