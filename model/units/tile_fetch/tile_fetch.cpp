#include "units/tile_fetch/tile_fetch.h"

namespace tilevis::sim {

TileFetch::TileFetch(const sc_core::sc_module_name& name, const UnitEnv& env, const TileFetchConfig& config,
                     const ParameterBuffer& buffer, const FramebufferConfig& framebuffer, bool per_primitive)
    : UnitBase(name, env, "tile fetch: control streams, edges and primitives of each tile from the parameter buffer"),
      ready("ready"),
      out("out"),
      pb("pb"),
      mem("mem"),
      m_cfg(config),
      m_buffer(buffer),
      m_fb(framebuffer),
      m_per_primitive(per_primitive),
      m_tiles(m_stats.add("tiles", "tiles", "tiles fetched (a tile counts once per segment)")),
      m_triangles(m_stats.add("triangle_fetches", "triangles", "triangle records fetched (one per tile reference)")),
      m_reloads(m_stats.add("tile_reloads", "tiles", "tiles whose stored depth/colour was read back")),
      m_extra_passes(m_stats.add("evu_extra_passes", "passes",
                                 "extra passes over lists longer than the EVU's on-chip capacity")) {
  SC_THREAD(run);
}

Cost TileFetch::cost(const Item& it) const {
  const TileWork& w = *it.tile;
  const ParameterBufferConfig& pc = m_buffer.config();
  Cost c;
  c.read_bytes = uint64_t(it.count) * m_buffer.position_record_bytes();
  c.cycles = ceil_div(it.count, m_cfg.primitives_per_clock);
  if (it.first_of_tile) {
    c.read_bytes += uint64_t(w.triangles()) * pc.reference_bytes + uint64_t(w.edges) * (pc.edge_bytes + pc.reference_bytes);
    c.cycles += ceil_div(w.edges, m_cfg.edges_per_clock);
    // Each extra pass streams the edges and the occluders' positions again.
    const uint64_t extra = w.passes - 1;
    c.read_bytes += extra * (uint64_t(w.edges) * pc.edge_bytes + uint64_t(w.opaque) * m_buffer.position_record_bytes());
    c.cycles += extra * (ceil_div(w.edges, m_cfg.edges_per_clock) + ceil_div(w.opaque, m_cfg.primitives_per_clock));
  }
  if (it.last) c.cycles += m_cfg.latency_cycles;
  return c;
}

uint64_t TileFetch::reload_bytes(const Item& it) const {
  if (!it.first_of_tile || !it.tile->reload) return 0;
  return uint64_t(it.tile->pixels) * m_work.samples() * (m_fb.colour_bytes + m_fb.depth_bytes);
}

std::vector<Item> TileFetch::items(TileWork* w) const {
  std::vector<Item> v;
  const uint32_t n = w->triangles(), step = m_per_primitive ? 1 : n;
  for (uint32_t a = 0; a < n; a += step) {
    Item it;
    it.segment = w->segment;
    it.tile = w;
    it.first = a;
    it.count = std::min(step, n - a);
    it.first_of_tile = a == 0;
    it.last = a + it.count == n;
    v.push_back(it);
  }
  return v;
}

void TileFetch::account(const Item& it, const Cost& c) {
  const uint64_t reload = reload_bytes(it);
  m_busy.value += double(c.cycles);
  m_items.value += 1;
  m_bytes.value += double(c.read_bytes + reload);
  it.tile->cycles[size_t(TileUnit::fetch)] += c.cycles;
  m_triangles.value += it.count;
  if (it.first_of_tile) {
    m_tiles.value += 1;
    m_reloads.value += it.tile->reload;
    m_extra_passes.value += it.tile->passes - 1;
  }
}

void TileFetch::run() {
  for (;;) {
    const uint32_t k = ready.read();
    m_work.prepare_segment(k);
    for (uint32_t tile : m_work.segment_tiles()) {
      TileWork* w = m_work.open_tile(tile);
      w->start_cycle = cycles(sc_core::sc_time_stamp());
      for (const Item& it : items(w)) {
        const Cost c = cost(it);
        // The control stream names every record of the tile: after the tile's first read
        // the rest are prefetched, so only the first waits for the DRAM latency.
        sc_core::sc_time memory = transfer(pb, tlm::TLM_READ_COMMAND, c.read_bytes, !it.first_of_tile);
        const sc_core::sc_time reload = transfer(mem, tlm::TLM_READ_COMMAND, reload_bytes(it));
        if (reload > memory) memory = reload;
        spend(c.cycles, memory, w, TileUnit::fetch);
        m_items.value += 1;
        m_triangles.value += it.count;
        if (it.first_of_tile) {
          m_tiles.value += 1;
          m_reloads.value += w->reload;
          m_extra_passes.value += w->passes - 1;
        }
        push(out, it);
      }
    }
    Item end;
    end.kind = Item::Kind::segment_end;
    end.segment = k;
    push(out, end);
  }
}

}  // namespace tilevis::sim
