// The tilevis subcommands. Each registers its options on the CLI11 app and
// returns the function that runs it.
#pragma once

#include <functional>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "tilevis/trace.h"

namespace tilevis::app {

struct Command {
  CLI::App* sub;              // the parsed subcommand
  std::function<int()> run;   // runs it; returns the exit code
};

Command add_trace_command(CLI::App& app);
Command add_info_command(CLI::App& app);
Command add_compare_command(CLI::App& app);
Command add_golden_command(CLI::App& app);
Command add_sim_command(CLI::App& app);
Command add_cuda_command(CLI::App& app);
Command add_sweep_command(CLI::App& app);
Command add_capture_command(CLI::App& app);
Command add_compare_depth_command(CLI::App& app);

// Parses "WxH" or "N" (square).
bool parse_size(const std::string& text, uint32_t& width, uint32_t& height);
// A --tile value: parse_size with 4 <= W, H <= 256, or a one-line error.
void parse_tile(const std::string& text, uint32_t& width, uint32_t& height);
// An --occlusion-bin value (SVGPU §4.1 bins within a tile): empty gives 0 x 0 (off).
void parse_occlusion_bin(const std::string& text, uint32_t tile_w, uint32_t tile_h, uint32_t& width, uint32_t& height);
// stats.json's "config" of a visibility producer (golden, cuda): tiles, occlusion bins (the
// tile when off), samples, depth bits.
nlohmann::json visibility_config(uint32_t tile_w, uint32_t tile_h, uint32_t occlusion_bin_w, uint32_t occlusion_bin_h,
                                 uint32_t samples, uint32_t depth_bits);
// Frame `frame_index` of the trace at `path`; samples != 0 replaces its sample pattern with
// the standard one of that count (--samples). Errors name the option.
trace::Frame load_frame(const std::string& path, uint32_t frame_index, uint32_t samples);
// Estimated peak memory of one golden, truth or sim run of `frame` at tile_w x tile_h: sample
// buffers, per-tile tables, setup. Refuses (one line: estimate, limit, what to change) when it
// exceeds the address-space limit or the memory available.
void check_memory(const std::string& what, const trace::Frame& frame, uint32_t tile_w, uint32_t tile_h);

}  // namespace tilevis::app
