// The tilevis subcommands. Each registers its options on the CLI11 app and
// returns the function that runs it.
#pragma once

#include <functional>

#include <CLI/CLI.hpp>

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

// Parses "WxH" or "N" (square).
bool parse_size(const std::string& text, uint32_t& width, uint32_t& height);

}  // namespace tilevis::app
