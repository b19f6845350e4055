// Tile fetch: when the parameter buffer holds a complete segment (the frame, or what a
// partial render must draw), walks its non-empty tiles in row-major order, reads each
// tile's control stream, edges and primitive records, and feeds the visibility stage.
// A tile that an earlier partial render stored gets its depth and colour read back.
#pragma once

#include "units/common/framebuffer.h"
#include "units/common/stage.h"
#include "units/parameter_buffer/parameter_buffer.h"

namespace tilevis::sim {

struct TileFetchConfig {
  uint32_t primitives_per_clock = 1;  // primitive records parsed per clock (assumption)
  uint32_t edges_per_clock = 1;       // silhouette edge records per clock (assumption)
  uint32_t latency_cycles = 16;       // per tile: control stream to first primitive (assumption)
};

class TileFetch : public UnitBase {
 public:
  sc_core::sc_fifo_in<uint32_t> ready;  // segments the parameter buffer holds completely
  sc_core::sc_fifo_out<Item> out;
  tlm_utils::simple_initiator_socket<UnitBase> pb;   // control streams and primitives
  tlm_utils::simple_initiator_socket<UnitBase> mem;  // stored depth/colour of earlier partial renders

  SC_HAS_PROCESS(TileFetch);
  TileFetch(const sc_core::sc_module_name& name, const UnitEnv& env, const TileFetchConfig& config,
            const ParameterBuffer& buffer, const FramebufferConfig& framebuffer, bool per_primitive);

  // Parameter-buffer reads and cycles of one item; reload_bytes(): the stored tile.
  Cost cost(const Item& item) const;
  uint64_t reload_bytes(const Item& item) const;
  // The items of one tile at this unit's granularity.
  std::vector<Item> items(TileWork* w) const;
  void account(const Item& item, const Cost& c);

 private:
  void run();
  TileFetchConfig m_cfg;
  const ParameterBuffer& m_buffer;
  FramebufferConfig m_fb;
  bool m_per_primitive;
  Stat& m_tiles;
  Stat& m_triangles;
  Stat& m_reloads;
  Stat& m_extra_passes;
};

}  // namespace tilevis::sim
