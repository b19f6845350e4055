// One frame through the tiler model: elaboration, the functional steps, one sc_start()
// (or the closed form at fidelity analytic), and the canonical outputs plus the model's
// own (DESIGN.md "Canonical outputs"): stats.json with cycles, param_buffer_bytes,
// dram_bytes, per-unit groups and triangle accounts; tiles.csv with cycle columns;
// config.json; tile_cycles.exr (per-tile cycles, one pixel per tile) and tile_cycles.png
// (the whole-tile cycles as a viridis heatmap).
// A process can simulate once (SystemC allows one elaboration per process).
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tilevis/outputs.h"
#include "tilevis/trace.h"
#include "top/config.h"

namespace tilevis::sim {

struct SimOptions {
  std::string trace_name;   // for stats.json
  uint32_t frame_index = 0;
  std::string vcd;          // VCD of unit busy and queue occupancy; empty: none
  // Called as tiles are resolved: (tiles resolved, tiles binned) over every segment so far.
  std::function<void(uint64_t done, uint64_t total)> progress;
};

struct SimOutput {
  outputs::Result result;               // canonical outputs, stats.json included
  uint64_t cycles = 0;
  double host_seconds = 0;
  double host_prepare_seconds = 0;  // of which elaboration and the functional prepare every level shares
  std::vector<std::string> systemc_reports;  // warnings and errors SystemC raised
};

SimOutput simulate(const trace::Frame& frame, const TilerConfig& config, const SimOptions& options = {});
// Canonical outputs, config.json, tile_cycles.exr and tile_cycles.png into `dir`.
void write_sim_outputs(const SimOutput& out, const std::filesystem::path& dir);

}  // namespace tilevis::sim
