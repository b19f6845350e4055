// Tile fetch, the head of a tile core: takes the tiles the scheduler gives its core, reads
// each tile's control stream, edges and primitive records, and feeds the visibility
// stage. Primitive records are read through the core's parameter cache (a triangle that
// covers several tiles is fetched once while it stays cached). A tile that an earlier
// partial render stored gets its depth and colour read back.
#pragma once

#include "units/common/framebuffer.h"
#include "units/common/stage.h"
#include "units/memory/cache.h"
#include "units/parameter_buffer/parameter_buffer.h"

namespace tilevis::sim {

struct TileFetchConfig {
  uint32_t primitives_per_clock = 1;  // primitive records parsed per clock (assumption)
  uint32_t edges_per_clock = 1;       // silhouette edge records per clock (assumption)
  uint32_t latency_cycles = 16;       // per tile: control stream to first primitive (assumption)
  // Parameter cache for primitive records (assumption: 16 KiB, 4-way, 64-byte lines, the
  // order of a GPU's L1 data cache).
  CacheConfig cache{16384, 64, 4};
};

class TileFetch : public UnitBase {
 public:
  sc_core::sc_fifo_in<Item> tiles;  // from the tile scheduler: tiles (work), then segment_end
  sc_core::sc_fifo_out<Item> out;
  tlm_utils::simple_initiator_socket<UnitBase> pb;   // control streams and primitives
  tlm_utils::simple_initiator_socket<UnitBase> mem;  // stored depth/colour of earlier partial renders

  SC_HAS_PROCESS(TileFetch);
  TileFetch(const sc_core::sc_module_name& name, const UnitEnv& env, const TileFetchConfig& config,
            const ParameterBuffer& buffer, const FramebufferConfig& framebuffer, bool per_primitive);
  const Cache& cache() const { return m_cache; }

  // Parameter-buffer reads (after the cache) and cycles of one item, once per item: the
  // cache remembers. reload(): the stored tile's colour and depth.
  Cost cost(const Item& item);
  Traffic reload(const Item& item) const;
  // The items of one tile at this unit's granularity.
  std::vector<Item> items(TileWork* w) const;
  void account(const Item& item, const Cost& c);

 private:
  void run();
  TileFetchConfig m_cfg;
  const ParameterBuffer& m_buffer;
  FramebufferConfig m_fb;
  bool m_per_primitive;
  Cache m_cache;
  Stat& m_tiles;
  Stat& m_triangles;
  Stat& m_reloads;
  Stat& m_extra_passes;
  Stat& m_cache_hits;
  Stat& m_cache_misses;
};

}  // namespace tilevis::sim
