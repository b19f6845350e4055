// The tiler's configuration in two layers (DRAMSys, VCML): a JSON layer — a file of
// nested objects or dotted keys, then `-p key=value` overrides — checked key by key
// against the parameter registry (unknown keys, wrong types and out-of-range values are
// one-line errors naming the file or option, the key and what was expected), and the
// validated runtime structs below with their named defaults. `--list-params` prints the
// registry; the effective config is written beside every result.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "units/common/framebuffer.h"
#include "units/common/work.h"
#include "units/early_visibility_unit/early_visibility_unit.h"
#include "units/fragment_unit/fragment_unit.h"
#include "units/geometry_front_end/geometry_front_end.h"
#include "units/hsr_unit/hsr_unit.h"
#include "units/memory/memory.h"
#include "units/parameter_buffer/parameter_buffer.h"
#include "units/primitive_setup/primitive_setup.h"
#include "units/silhouette_unit/silhouette_unit.h"
#include "units/tile_fetch/tile_fetch.h"
#include "units/tile_scheduler/tile_scheduler.h"
#include "units/tile_writer/tile_writer.h"
#include "units/tiling_engine/tiling_engine.h"

namespace tilevis::sim {

struct SimulationConfig {
  Fidelity fidelity = Fidelity::tile;
  Mode mode = Mode::analytic;
  // 32 x 32-pixel tiles, PowerVR's tile size since Series 1 (the PowerVR entry of
  // Wikipedia's "Tiled rendering": "a 32x32 tile into which polygons were rasterized").
  uint32_t tile_width = 32, tile_height = 32;
  uint32_t depth_bits = 24;          // D24, as snapped by primitive setup
  // 800 MHz GPU clock (assumption: the upper range of PowerVR-class mobile GPUs).
  double clock_mhz = 800.0;
  uint32_t batch_triangles = 1024;   // geometry transaction size at fidelity tile
  uint32_t fifo_tiles = 2;           // queue between render units at fidelity tile: double-buffered tile memory
  uint32_t fifo_primitives = 16;     // queue between units at fidelity primitive (assumption)
  // A recorded functional pass (units/common/functional_record.h): written here when absent,
  // replayed when present; empty: off.
  std::string functional_record;
  // A folder of recorded functional passes, one file per frame and functional configuration
  // (named by their hash): a run replays its own if there, else computes it and adds it (not at
  // fidelity auto, whose record holds its sample only); not used at fidelity rtl. Empty: off.
  std::string functional_cache;
};

// Energy proxy (stats.json totals.energy): events times per-event energies, to rank
// configurations against each other, not to predict a chip's power. Per-operation figures
// of a 45 nm process from M. Horowitz, "Computing's energy problem (and what we can do
// about it)", ISSCC 2014: DRAM 1.3-2.6 nJ per 64-bit access; 32-bit float multiply
// 3.7 pJ, add 0.9 pJ; 32-bit integer multiply 3.1 pJ, add 0.1 pJ; 64-bit read of an 8 KB
// SRAM 10 pJ. How many of them one model event takes is an assumption, stated per field.
struct EnergyConfig {
  double dram_pj_per_byte = 244;          // 1.95 nJ (the range's middle) per 8 bytes
  double shader_pj_per_lane_cycle = 4.6;  // one fp32 multiply-add per lane-cycle
  double evu_pj_per_test = 12.5;          // an SVGPU test: ~4 integer multiply-adds on snapped coordinates
  double depth_test_pj = 8.2;             // interpolate (integer multiply-add), compare, 32 bits of an 8 KB SRAM
};

struct TilerConfig {
  SimulationConfig sim;
  TileSchedulerConfig scheduler;
  MemoryConfig memory;
  FramebufferConfig framebuffer;
  GeometryFrontEndConfig front_end;
  PrimitiveSetupConfig setup;
  SilhouetteUnitConfig silhouette;
  TilingEngineConfig tiling;
  ParameterBufferConfig pb;
  TileFetchConfig fetch;
  EarlyVisibilityConfig evu;
  HsrUnitConfig hsr;
  FragmentUnitConfig fragment;
  TileWriterConfig writer;
  EnergyConfig energy;
};

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Layer 1 -> layer 2. `file` may be empty; `overrides` are "key=value" (value: JSON, or a
// bare word for enums). Throws ConfigError.
TilerConfig load_config(const std::string& file, const std::vector<std::string>& overrides);
// The effective config as nested JSON (what config.json holds).
nlohmann::json to_json(const TilerConfig& config);
// name, default, unit, help of every parameter, one per line.
std::string list_params();
std::vector<std::string> param_names();

}  // namespace tilevis::sim
