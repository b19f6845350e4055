// tilevis trace SCENE.json -o T: scene description -> trace file.
#include <chrono>

#include <fmt/format.h>

#include "commands.h"
#include "tilevis/scene.h"
#include "tilevis/trace.h"

namespace tilevis::app {

bool parse_size(const std::string& text, uint32_t& width, uint32_t& height) {
  unsigned long w = 0, h = 0;
  char x = 0, extra = 0;
  int n = std::sscanf(text.c_str(), "%lu%c%lu%c", &w, &x, &h, &extra);
  if (n == 1) h = w;
  else if (n != 3 || x != 'x') return false;
  if (w == 0 || h == 0 || w > 65536 || h > 65536) return false;
  width = static_cast<uint32_t>(w);
  height = static_cast<uint32_t>(h);
  return true;
}

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
