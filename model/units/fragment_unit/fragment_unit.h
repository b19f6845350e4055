// Fragment unit: rasterises what the visibility stage lets through and shades it at the
// trace's cycles per fragment, fetching texture bytes per shaded fragment and the
// varyings of each triangle with a shaded fragment from the parameter buffer.
// Texture traffic follows a footprint model per draw: a draw's shaded pixels in a tile
// touch texels_per_pixel texels each, contiguous in its texture, and the texture cache
// holds them for the tile: DRAM reads the footprint's lines, at most what the shader asks
// for (the trace's texture bytes per fragment), once per tile whether the tile's triangles
// come as one transaction or one at a time; reuse across tiles is not modelled.
//   analytic: the visible pieces' samples (plus, after a partial render, a depth test of
//             each against the stored depth); hsr: the visible samples the ISP passes on;
//   early_z:  every covered sample, depth-tested on arrival, the passing ones shaded;
//   none:     every covered sample shaded.
#pragma once

#include "units/common/stage.h"
#include "units/parameter_buffer/parameter_buffer.h"

namespace tilevis::sim {

struct FragmentUnitConfig {
  uint32_t raster_samples_per_clock = 16;  // rasteriser output (assumption: a 4x4 stamp per clock)
  uint32_t depth_tests_per_clock = 16;     // early depth tests beside the rasteriser (assumption)
  // 32 shader lanes: an IMG BXS-4-64 does 64 FP32 operations per clock (TI SPRUJB3C,
  // "Performance"), i.e. 32 fused multiply-adds; the trace's cycles per fragment are per lane.
  uint32_t shader_lanes = 32;
  // Texture footprint: mip-mapping selects the level with about one texel per pixel
  // (Williams, "Pyramidal parametrics", SIGGRAPH 1983); 4-byte RGBA8 texels and 64-byte
  // cache lines are assumptions.
  double texels_per_pixel = 1.0;
  uint32_t texel_bytes = 4;
  uint32_t texture_line_bytes = 64;
  uint32_t latency_cycles = 32;            // raster to shaded output, per tile (assumption)
};

class FragmentUnit : public Stage {
 public:
  tlm_utils::simple_initiator_socket<UnitBase> mem;  // texture
  tlm_utils::simple_initiator_socket<UnitBase> pb;   // varyings of the triangles it shades

  FragmentUnit(const sc_core::sc_module_name& name, const UnitEnv& env, const FragmentUnitConfig& config,
               const ParameterBuffer& buffer);
  Cost cost(const Item& item) const override;
  // DRAM bytes of a draw's texture footprint in tile `w` once `fragments` are shaded and
  // `asked` bytes asked for: the footprint's whole lines, at most what was asked.
  uint64_t texture_footprint(const TileWork& w, uint64_t fragments, double asked) const;

 private:
  FragmentUnitConfig m_cfg;
  const ParameterBuffer& m_buffer;
  Stat& m_rasterised;
  Stat& m_tests;
  Stat& m_shaded;
  Stat& m_shader_cycles;
  Stat& m_texture_requested;
};

}  // namespace tilevis::sim
