// Tile writer, the tail of a tile core: at the end of a tile, writes the resolved colour
// to the frame buffer (tile-linear, optionally compressed); in a partial render, writes
// the tile's colour and depth per sample instead, for the next render of that tile to
// read back. Closes the tile's functional record, and tells the scheduler when its core
// has finished a segment.
#pragma once

#include "units/common/framebuffer.h"
#include "units/common/stage.h"

namespace tilevis::sim {

struct TileWriterConfig {
  // 4 pixels per clock: an IMG BXS-4-64's pixel rate (TI SPRUJB3C: "4 pixel(s) per clock (@32 BPP)").
  uint32_t pixels_per_clock = 4;
  uint32_t latency_cycles = 8;  // per tile (assumption)
  // Colour write-back compression: bytes written / bytes of the tile (1: off). Lossless
  // frame-buffer compression (Arm AFBC, Imagination's PVRIC) typically halves it; the
  // ratio is an assumption of the study, not a measured figure.
  double colour_compression = 1.0;
};

class TileWriter : public UnitBase {
 public:
  sc_core::sc_fifo_in<Item> in;
  sc_core::sc_fifo_out<uint32_t> done;  // segments this core has finished: to the scheduler
  tlm_utils::simple_initiator_socket<UnitBase> mem;
  sc_core::sc_event* closed = nullptr;  // notified after each tile is written (the scheduler's sampled rounds)

  SC_HAS_PROCESS(TileWriter);
  TileWriter(const sc_core::sc_module_name& name, const UnitEnv& env, const TileWriterConfig& config,
             const FramebufferConfig& framebuffer);
  Cost cost(const Item& item) const;
  void account(const Item& item, const Cost& c);

 private:
  void run();
  TileWriterConfig m_cfg;
  FramebufferConfig m_fb;
  Stat& m_tiles;
  Stat& m_stores;
};

}  // namespace tilevis::sim
