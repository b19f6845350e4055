// Tile writer: at the end of a tile, writes the resolved colour to the frame buffer; in a
// partial render, writes the tile's colour and depth per sample instead, for the next
// render of that tile to read back. Closes the tile's functional record, and at a
// segment's end frees its parameter-buffer pages.
#pragma once

#include "units/common/framebuffer.h"
#include "units/common/stage.h"

namespace tilevis::sim {

struct TileWriterConfig {
  // 4 pixels per clock: an IMG BXS-4-64's pixel rate (TI SPRUJB3C: "4 pixel(s) per clock (@32 BPP)").
  uint32_t pixels_per_clock = 4;
  uint32_t latency_cycles = 8;  // per tile (assumption)
};

class TileWriter : public UnitBase {
 public:
  sc_core::sc_fifo_in<Item> in;
  sc_core::sc_fifo_out<uint32_t> released;  // segments done: to the parameter buffer
  tlm_utils::simple_initiator_socket<UnitBase> mem;

  SC_HAS_PROCESS(TileWriter);
  TileWriter(const sc_core::sc_module_name& name, const UnitEnv& env, const TileWriterConfig& config,
             const FramebufferConfig& framebuffer);
  Cost cost(const Item& item) const;
  void account(const Item& item, const Cost& c);
  // When the last segment's last tile was written (event-driven levels).
  uint64_t frame_end_cycle() const { return m_frame_end; }
  bool frame_done() const { return m_done; }

 private:
  void run();
  TileWriterConfig m_cfg;
  FramebufferConfig m_fb;
  uint64_t m_frame_end = 0;
  bool m_done = false;
  Stat& m_tiles;
  Stat& m_stores;
};

}  // namespace tilevis::sim
