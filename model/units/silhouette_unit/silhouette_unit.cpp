#include "units/silhouette_unit/silhouette_unit.h"

#include <array>
#include <deque>
#include <map>
#include <unordered_map>
#include <unordered_set>

namespace tilevis::sim {

SilhouetteUnit::SilhouetteUnit(const sc_core::sc_module_name& name, const UnitEnv& env,
                               const SilhouetteUnitConfig& config)
    : Stage(name, env, "silhouette unit: edge hash pairing the edges of each draw (SVGPU 3.1)", TileUnit::count, false),
      mem("mem"),
      m_cfg(config),
      m_lookups(m_stats.add("edge_lookups", "edges", "edges looked up in the hash")),
      m_paired(m_stats.add("edges_paired", "edges", "edges that met their partner in the hash")),
      m_spills(m_stats.add("spills", "entries", "open edges evicted to memory (hash full)")),
      m_probes(m_stats.add("spill_probes", "entries", "memory look-ups of a missing edge while entries are spilled")),
      m_readback(m_stats.add("spill_readback", "entries", "spilled entries read back at the end of a draw")),
      m_peak(m_stats.add("peak_open_edges", "entries", "most open edges at once, on chip and spilled")) {
  m_mem = &mem;
  m_latency_hidden = true;  // spill traffic is written and read back in bulk, off the critical path
}

void SilhouetteUnit::prepare() {
  const trace::Frame& f = m_work.frame();
  const vis::Setup& s = m_work.setup();
  const uint32_t n = m_work.trace_triangles();
  std::vector<uint64_t> ops(n, 0), wr(n, 0), rd(n, 0);
  const bool on = uses_evu(m_work.mode());
  uint32_t id = 0;
  for (const trace::Draw& d : f.draws) {
    const uint32_t first = id;
    id += uint32_t(d.triangle_count());
    if (!on || !(d.opaque() && !d.per_pixel_only()) || first == id) continue;
    // Soup: vertices with bit-identical positions share a key (as setup welds them).
    std::vector<uint32_t> weld;
    if (d.flags & trace::kTriangleSoup) {
      std::map<std::array<float, 4>, uint32_t> first_of;
      weld.resize(d.vertices.size());
      for (uint32_t v = 0; v < d.vertices.size(); ++v) {
        const auto& p = d.vertices[v];
        weld[v] = first_of.emplace(std::array<float, 4>{p.x, p.y, p.z, p.w}, v).first->second;
      }
    }
    std::unordered_set<uint64_t> chip, spilled;
    std::deque<uint64_t> order;  // insertion order on chip, for FIFO eviction (lazily pruned)
    for (uint32_t t = first; t < id; ++t) {
      if (m_work.setup_begin(t) == m_work.setup_begin(t + 1)) continue;  // frustum-culled: no edges
      const bool clipped = s.triangles[m_work.setup_begin(t)].clipped;
      ops[t] = 3;
      if (clipped) continue;  // edges made by clipping have no partner: boundaries, no look-up
      for (int k = 0; k < 3; ++k) {
        uint32_t a = d.indices[3 * size_t(t - first) + size_t(k)], b = d.indices[3 * size_t(t - first) + size_t(k + 1) % 3];
        if (!weld.empty()) a = weld[a], b = weld[b];
        const uint64_t key = (uint64_t(std::min(a, b)) << 32) | std::max(a, b);
        m_lookups.value += 1;
        if (chip.erase(key)) {
          m_paired.value += 1;
          continue;
        }
        if (!spilled.empty()) {
          ++rd[t];  // the miss must look in memory
          m_probes.value += 1;
          if (spilled.erase(key)) {
            m_paired.value += 1;
            continue;
          }
        }
        if (chip.size() >= m_cfg.hash_entries) {
          while (!chip.count(order.front())) order.pop_front();
          spilled.insert(order.front());
          chip.erase(order.front());
          order.pop_front();
          ++wr[t];
          m_spills.value += 1;
        }
        chip.insert(key);
        order.push_back(key);
        m_peak.value = std::max(m_peak.value, double(chip.size() + spilled.size()));
      }
    }
    // End of draw: what stays open is a boundary; spilled entries come back to be emitted.
    rd[id - 1] += spilled.size();
    m_readback.value += double(spilled.size());
  }
  m_cycles.assign(size_t(n) + 1, 0);
  m_spill_write.assign(size_t(n) + 1, 0);
  m_spill_read.assign(size_t(n) + 1, 0);
  for (uint32_t t = 0; t < n; ++t) {
    m_cycles[t + 1] = m_cycles[t] + ceil_div(ops[t], m_cfg.edges_per_clock);
    m_spill_write[t + 1] = m_spill_write[t] + wr[t] * m_cfg.entry_bytes;
    m_spill_read[t + 1] = m_spill_read[t] + rd[t] * m_cfg.entry_bytes;
  }
}

Cost SilhouetteUnit::cost(const Item& it) const {
  Cost c;
  const uint32_t a = it.first, b = it.first + it.count;
  c.cycles = m_cycles[b] - m_cycles[a];
  if (it.last && uses_evu(m_work.mode())) c.cycles += m_cfg.latency_cycles;
  // Spilled entries go to a region of their own, written and read back in order.
  c.writes.add(region::spill + m_spill_write[a], m_spill_write[b] - m_spill_write[a]);
  c.reads.add(region::spill + m_spill_read[a], m_spill_read[b] - m_spill_read[a]);
  return c;
}

}  // namespace tilevis::sim
