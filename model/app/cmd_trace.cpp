// tilevis trace SCENE.json -o T: scene description -> trace file.
#include <chrono>

#include <fmt/format.h>

#include "commands.h"
#include "tilevis/scene.h"
#include "tilevis/trace.h"

namespace tilevis::app {

Command add_trace_command(CLI::App& app) {
  struct Args {
    std::string scene, out, viewport;
    uint32_t samples = 0;
    bool quiet = false;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("trace", "Build a trace from a scene description (JSON)");
  cmd->add_option("scene", args->scene, "Scene file (traces/scenes/*.json)")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", args->out, "Trace file to write")->required();
  cmd->add_option("--viewport", args->viewport, "Override the viewport, WxH");
  cmd->add_option("--samples", args->samples, "Override the sample count (1, 2, 4, 8, 16)");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress messages");
  return {cmd, [args]() {
    auto t0 = std::chrono::steady_clock::now();
    scene::BuildOptions opt;
    if (!args->viewport.empty()) {
      uint32_t w = 0, h = 0;
      if (!parse_size(args->viewport, w, h))
        throw std::runtime_error(fmt::format("--viewport {}: expected WxH", args->viewport));
      opt.width = w;
      opt.height = h;
    }
    if (args->samples) opt.samples = args->samples;
    if (!args->quiet) opt.progress = [](const std::string& s) { fmt::print(stderr, "  {}\n", s); };
    opt.warn = [](const std::string& s) { fmt::print(stderr, "tilevis trace: warning: {}\n", s); };
    trace::Trace t = scene::build_trace(args->scene, opt);
    trace::write(t, args->out);
    size_t tris = 0;
    for (const auto& f : t.frames) tris += f.triangle_count();
    double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!args->quiet)
      fmt::print(stderr, "wrote {}: {} frame(s), {} triangles in {:.2f} s\n", args->out, t.frames.size(), tris, secs);
    return 0;
  }};
}

}  // namespace tilevis::app
