#include "units/silhouette_unit/silhouette_unit.h"

#include <algorithm>
#include <array>
#include <deque>
#include <map>

namespace tilevis::sim {
namespace {

struct EdgeUse {
  uint32_t lo, hi;   // the edge's vertex keys, lo <= hi
  uint32_t triangle; // trace triangle
  uint32_t id = 0;   // dense id of (lo, hi) within the draw
};

// Numbers the distinct (lo, hi) pairs of `uses` densely and returns how many there are: a
// counting sort by lo into (hi, use) words, then each bucket (a vertex's edges: a few, or a
// fan's many) sorted as plain integers, in place. No hash.
uint32_t dense_edge_ids(std::vector<EdgeUse>& uses, size_t vertices, std::vector<uint64_t>& scratch) {
  std::vector<uint32_t> begin(vertices + 1, 0);
  for (const EdgeUse& u : uses) ++begin[u.lo + 1];
  for (size_t v = 1; v < begin.size(); ++v) begin[v] += begin[v - 1];
  scratch.resize(uses.size());
  std::vector<uint32_t> fill(begin.begin(), begin.end() - 1);
  for (uint32_t i = 0; i < uses.size(); ++i) scratch[fill[uses[i].lo]++] = uint64_t(uses[i].hi) << 32 | i;
  uint32_t next = 0;
  for (size_t v = 0; v < vertices; ++v) {
    const auto b = scratch.begin() + begin[v], e = scratch.begin() + begin[v + 1];
    if (e - b > 1) std::sort(b, e);
    for (auto i = b; i != e; ++i) uses[uint32_t(*i)].id = (i != b && *i >> 32 == *(i - 1) >> 32) ? next - 1 : next++;
  }
  return next;
}

}  // namespace

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
  // Per triangle t, its look-ups, spill writes and reads are counted at [t + 1] of the prefix
  // arrays they are summed into at the end (no per-triangle arrays beside them).
  m_cycles.assign(size_t(n) + 1, 0);
  m_spill_write.assign(size_t(n) + 1, 0);
  m_spill_read.assign(size_t(n) + 1, 0);
  uint64_t* const ops = m_cycles.data() + 1;
  uint64_t* const wr = m_spill_write.data() + 1;
  uint64_t* const rd = m_spill_read.data() + 1;
  const bool on = uses_evu(m_work.mode());
  std::vector<EdgeUse> uses;
  std::vector<uint64_t> scratch;
  std::vector<uint8_t> state;
  uint64_t lookups = 0, paired = 0, spills = 0, probes = 0, readback = 0, peak = 0;
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
    // The draw's looked-up edges in order, each as a dense id of its key (vertex pair), so
    // that the hash's contents are a state per id: 0 absent, 1 on chip, 2 spilled.
    uses.clear();
    uses.reserve(3 * size_t(id - first));
    for (uint32_t t = first; t < id; ++t) {
      if (m_work.setup_begin(t) == m_work.setup_begin(t + 1)) continue;  // frustum-culled: no edges
      ops[t] = 3;
      if (s.triangles[m_work.setup_begin(t)].clipped) continue;  // edges made by clipping have no partner: boundaries, no look-up
      for (int k = 0; k < 3; ++k) {
        uint32_t a = d.indices[3 * size_t(t - first) + size_t(k)], b = d.indices[3 * size_t(t - first) + size_t(k + 1) % 3];
        if (!weld.empty()) a = weld[a], b = weld[b];
        uses.push_back({std::min(a, b), std::max(a, b), t});
      }
    }
    const uint32_t keys = dense_edge_ids(uses, d.vertices.size(), scratch);
    state.assign(keys, 0);
    uint64_t on_chip = 0, spilled = 0;
    std::deque<uint32_t> order;  // insertion order on chip, for FIFO eviction (lazily pruned)
    for (const EdgeUse& u : uses) {
      ++lookups;
      uint8_t& st = state[u.id];
      if (st == 1) {
        st = 0, --on_chip;
        ++paired;
        continue;
      }
      if (spilled) {
        ++rd[u.triangle];  // the miss must look in memory
        ++probes;
        if (st == 2) {
          st = 0, --spilled;
          ++paired;
          continue;
        }
      }
      if (on_chip >= m_cfg.hash_entries) {
        while (state[order.front()] != 1) order.pop_front();
        state[order.front()] = 2;
        order.pop_front();
        --on_chip, ++spilled;
        ++wr[u.triangle];
        ++spills;
      }
      st = 1, ++on_chip;
      order.push_back(u.id);
      peak = std::max(peak, on_chip + spilled);
    }
    // End of draw: what stays open is a boundary; spilled entries come back to be emitted.
    rd[id - 1] += spilled;
    readback += spilled;
  }
  m_lookups.value = double(lookups);
  m_paired.value = double(paired);
  m_spills.value = double(spills);
  m_probes.value = double(probes);
  m_readback.value = double(readback);
  m_peak.value = double(peak);
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
