// tilevis: one binary, one subcommand per job (DESIGN.md "CLI").
#include <cstdio>
#include <exception>
#include <new>

#include <fmt/format.h>

#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app{"TileVis: a tile-based deferred renderer with an analytic early-visibility unit"};
  app.require_subcommand(1);
  const tilevis::app::Command commands[] = {
      tilevis::app::add_trace_command(app),
      tilevis::app::add_info_command(app),
      tilevis::app::add_golden_command(app),
      tilevis::app::add_sim_command(app),
      tilevis::app::add_compare_command(app),
      tilevis::app::add_cuda_command(app),
      tilevis::app::add_sweep_command(app),
      tilevis::app::add_capture_command(app),
      tilevis::app::add_compare_depth_command(app),
  };
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    for (const auto& c : commands)
      if (c.sub->parsed()) return c.run();
  } catch (const std::bad_alloc&) {
    for (const auto& c : commands)
      if (c.sub->parsed())
        fmt::print(stderr, "tilevis: error: {}: out of memory (over the address-space limit or the machine's memory): "
                           "use larger tiles, fewer samples or a smaller viewport\n",
                   c.sub->get_name());
    return 1;
  } catch (const std::exception& e) {
    fmt::print(stderr, "tilevis: error: {}\n", e.what());
    return 1;
  }
  return 1;
}
