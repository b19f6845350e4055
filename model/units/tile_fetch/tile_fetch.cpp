#include "units/tile_fetch/tile_fetch.h"

namespace tilevis::sim {

TileFetch::TileFetch(const sc_core::sc_module_name& name, const UnitEnv& env, const TileFetchConfig& config,
                     const ParameterBuffer& buffer, const FramebufferConfig& framebuffer, bool per_primitive)
    : UnitBase(name, env, "tile fetch: control streams, edges and primitives of each tile from the parameter buffer"),
      tiles("tiles"),
      out("out"),
      pb("pb"),
      mem("mem"),
      m_cfg(config),
      m_buffer(buffer),
      m_fb(framebuffer),
      m_per_primitive(per_primitive),
      m_cache(config.cache),
      m_tiles(m_stats.add("tiles", "tiles", "tiles fetched (a tile counts once per segment)")),
      m_triangles(m_stats.add("triangle_fetches", "triangles", "triangle records fetched (one per tile reference)")),
      m_reloads(m_stats.add("tile_reloads", "tiles", "tiles whose stored depth/colour was read back")),
      m_extra_passes(m_stats.add("evu_extra_passes", "passes",
                                 "extra passes over lists longer than the EVU's on-chip capacity")),
      m_cache_hits(m_stats.add("cache_hits", "lines", "primitive-record lines found in the parameter cache")),
      m_cache_misses(m_stats.add("cache_misses", "lines", "primitive-record lines read from DRAM")) {
  SC_THREAD(run);
}

Cost TileFetch::cost(const Item& it) {
  const TileWork& w = *it.tile;
  const ParameterBufferConfig& pc = m_buffer.config();
  Cost c;
  // The tile's control stream (references, then its edge records: their placement beside
  // the stream is an assumption), read once, in order.
  const uint64_t stream = region::control + uint64_t(w.tile) * region::control_per_tile;
  if (it.first_of_tile)
    c.reads.add(stream, uint64_t(w.triangles()) * pc.reference_bytes + uint64_t(w.edges) * (pc.edge_bytes + pc.reference_bytes));
  // Each triangle's position record, through the parameter cache.
  const uint64_t hits_before = m_cache.hits(), misses_before = m_cache.misses();
  for (uint32_t i = it.first; i < it.first + it.count; ++i)
    m_cache.read(m_buffer.address(w.segment, w.ids[i]), m_buffer.position_record_bytes(), c.reads);
  m_cache_hits.value += double(m_cache.hits() - hits_before);
  m_cache_misses.value += double(m_cache.misses() - misses_before);
  c.cycles = ceil_div(it.count, m_cfg.primitives_per_clock);
  if (it.first_of_tile) {
    c.cycles += ceil_div(w.edges, m_cfg.edges_per_clock);
    // Each extra pass streams the edges and the occluders' positions again.
    const uint64_t extra = w.passes - 1;
    c.reads.add(stream + uint64_t(w.triangles()) * pc.reference_bytes,
                extra * (uint64_t(w.edges) * pc.edge_bytes + uint64_t(w.opaque) * m_buffer.position_record_bytes()));
    c.cycles += extra * (ceil_div(w.edges, m_cfg.edges_per_clock) + ceil_div(w.opaque, m_cfg.primitives_per_clock));
  }
  if (it.last) c.cycles += m_cfg.latency_cycles;
  return c;
}

Traffic TileFetch::reload(const Item& it) const {
  Traffic t;
  if (!it.first_of_tile || !it.tile->reload) return t;
  const uint64_t tile_bytes = uint64_t(m_work.config().tile_w) * m_work.config().tile_h * m_work.samples() *
                              (m_fb.colour_bytes + m_fb.depth_bytes);
  t.add(region::stored + uint64_t(it.tile->tile) * tile_bytes, uint64_t(it.tile->pixels) * m_work.samples() *
                                                                   (m_fb.colour_bytes + m_fb.depth_bytes));
  return t;
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
  m_busy.value += double(c.cycles);
  m_items.value += 1;
  m_bytes.value += double(c.reads.bytes() + reload(it).bytes());
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
    const Item tile = tiles.read();
    if (tile.kind == Item::Kind::segment_end) {
      push(out, tile);
      continue;
    }
    TileWork* w = tile.tile;
    w->start_cycle = cycles(sc_core::sc_time_stamp());
    for (const Item& it : items(w)) {
      const Cost c = cost(it);
      // The control stream names every record of the tile: after the tile's first read
      // the rest are prefetched, so only the first waits for the DRAM latency.
      sc_core::sc_time memory = transfer(pb, tlm::TLM_READ_COMMAND, c.reads, !it.first_of_tile);
      const sc_core::sc_time stored = transfer(mem, tlm::TLM_READ_COMMAND, reload(it));
      if (stored > memory) memory = stored;
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
}

}  // namespace tilevis::sim
