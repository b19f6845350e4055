#include "units/tile_scheduler/tile_scheduler.h"

#include <algorithm>

namespace tilevis::sim {
namespace {

uint64_t morton(uint32_t x, uint32_t y) {
  uint64_t m = 0;
  for (int b = 0; b < 32; ++b) m |= (uint64_t((x >> b) & 1) << (2 * b)) | (uint64_t((y >> b) & 1) << (2 * b + 1));
  return m;
}

}  // namespace

const char* to_string(Schedule s) {
  switch (s) {
    case Schedule::row_major: return "row_major";
    case Schedule::morton: return "morton";
    case Schedule::dynamic: return "dynamic";
  }
  return "?";
}

TileScheduler::TileScheduler(const sc_core::sc_module_name& name, const UnitEnv& env, const TileSchedulerConfig& config)
    : UnitBase(name, env, "tile scheduler: a segment's tiles to the tile cores, in order or to the first free core"),
      ready("ready"),
      to_core("to_core", config.cores),
      done("done", config.cores),
      released("released"),
      m_cfg(config) {
  for (uint32_t c = 0; c < config.cores; ++c)
    m_core_tiles.push_back(&m_stats.add("core" + std::to_string(c) + "_tiles", "tiles", "tiles given to core " + std::to_string(c)));
  SC_THREAD(dispatch);
  SC_THREAD(join);
}

std::vector<uint32_t> TileScheduler::order(const std::vector<uint32_t>& row_major) const {
  std::vector<uint32_t> v = row_major;
  if (m_cfg.policy != Schedule::row_major) {
    const geom::TileGrid& g = m_work.grid();
    std::stable_sort(v.begin(), v.end(), [&](uint32_t a, uint32_t b) {
      return morton(g.tile_x(a), g.tile_y(a)) < morton(g.tile_x(b), g.tile_y(b));
    });
  }
  return v;
}

void TileScheduler::count(uint32_t core) {
  m_core_tiles[core]->value += 1;
  m_items.value += 1;
}

uint32_t TileScheduler::free_core() {
  for (;;) {
    for (uint32_t c = 0; c < m_cfg.cores; ++c)
      if (to_core[c]->num_free() > 0) return c;
    sc_core::sc_event_or_list any;
    for (uint32_t c = 0; c < m_cfg.cores; ++c) any |= to_core[c]->data_read_event();
    const sc_core::sc_time t0 = sc_core::sc_time_stamp();
    sc_core::wait(any);
    m_stall.value += double(cycles(sc_core::sc_time_stamp() - t0));
  }
}

void TileScheduler::dispatch() {
  for (;;) {
    const uint32_t k = ready.read();
    m_work.prepare_segment(k);
    const std::vector<uint32_t> tiles = order(m_work.segment_tiles());
    for (size_t i = 0; i < tiles.size(); ++i) {
      const uint32_t core = m_cfg.policy == Schedule::dynamic ? free_core() : static_core(i);
      Item it;
      it.segment = k;
      it.tile = m_work.open_tile(tiles[i]);
      count(core);
      push(to_core[core], it);
    }
    Item end;
    end.kind = Item::Kind::segment_end;
    end.segment = k;
    for (uint32_t c = 0; c < m_cfg.cores; ++c) push(to_core[c], end);
  }
}

void TileScheduler::join() {
  for (;;) {
    uint32_t k = 0;
    for (uint32_t c = 0; c < m_cfg.cores; ++c) k = done[c]->read();
    m_work.finish_segment();
    if (k + 1 == m_work.segment_count()) {
      m_frame_end = cycles(sc_core::sc_time_stamp());
      m_done = true;
    }
    released.write(k);
  }
}

}  // namespace tilevis::sim
