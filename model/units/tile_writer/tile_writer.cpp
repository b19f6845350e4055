#include "units/tile_writer/tile_writer.h"

#include <cmath>

namespace tilevis::sim {

TileWriter::TileWriter(const sc_core::sc_module_name& name, const UnitEnv& env, const TileWriterConfig& config,
                       const FramebufferConfig& framebuffer)
    : UnitBase(name, env, "tile writer: resolved colour out; colour and depth per sample in a partial render"),
      in("in"),
      done("done"),
      mem("mem"),
      m_cfg(config),
      m_fb(framebuffer),
      m_tiles(m_stats.add("tiles", "tiles", "tiles written")),
      m_stores(m_stats.add("partial_stores", "tiles", "tiles stored by a partial render for a later one")) {
  SC_THREAD(run);
}

Cost TileWriter::cost(const Item& it) const {
  Cost c;
  if (!it.last) return c;
  const TileWork& w = *it.tile;
  const uint64_t values = w.store ? uint64_t(w.pixels) * m_work.samples() : w.pixels;
  const uint64_t tile_pixels = uint64_t(m_work.config().tile_w) * m_work.config().tile_h;
  if (w.store) {
    const uint64_t per = m_work.samples() * (m_fb.colour_bytes + m_fb.depth_bytes);
    c.writes.add(region::stored + uint64_t(w.tile) * tile_pixels * per, values * (m_fb.colour_bytes + m_fb.depth_bytes));
  } else {
    const uint64_t bytes = uint64_t(std::ceil(double(values * m_fb.colour_bytes) * m_cfg.colour_compression));
    c.writes.add(region::colour + uint64_t(w.tile) * tile_pixels * m_fb.colour_bytes, bytes);
  }
  c.cycles = ceil_div(values, m_cfg.pixels_per_clock) + m_cfg.latency_cycles;
  return c;
}

void TileWriter::account(const Item& it, const Cost& c) {
  m_busy.value += double(c.cycles);
  m_items.value += 1;
  m_bytes.value += double(c.writes.bytes());
  it.tile->cycles[size_t(TileUnit::writer)] += c.cycles;
  if (it.last) {
    m_tiles.value += 1;
    m_stores.value += it.tile->store;
  }
}

void TileWriter::run() {
  for (;;) {
    const Item it = in.read();
    if (it.kind == Item::Kind::segment_end) {
      done.write(it.segment);
      continue;
    }
    m_items.value += 1;
    if (!it.last) continue;  // the tile buffer fills on chip; it leaves at the end
    const Cost c = cost(it);
    const sc_core::sc_time memory = transfer(mem, tlm::TLM_WRITE_COMMAND, c.writes);
    spend(c.cycles, memory, it.tile, TileUnit::writer);
    m_tiles.value += 1;
    m_stores.value += it.tile->store;
    it.tile->end_cycle = cycles(sc_core::sc_time_stamp());
    m_work.close_tile(it.tile);
    if (closed) closed->notify(sc_core::SC_ZERO_TIME);
  }
}

}  // namespace tilevis::sim
