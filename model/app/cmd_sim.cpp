// tilevis sim T -o DIR: the cycle-approximate SystemC model of the tiler on one frame.
// Writes the canonical outputs (ids.exr, visible_area.bin, tiles.csv with per-unit cycle
// columns, stats.json with cycles, param_buffer_bytes, dram_bytes and per-unit groups),
// config.json (the effective config), tile_cycles.exr and tile_cycles.png; optionally a VCD.
#include <fmt/format.h>

#include "commands.h"
#include "progress.h"
#include "tilevis/trace.h"

#if TILEVIS_HAVE_SIM
#include <systemc>

#include "top/config.h"
#include "top/simulate.h"

// libsystemc brings its own main(), which calls sc_main(); tilevis has its own main() and
// elaborates from `sim`, so this is never called. It exists to satisfy the library.
int sc_main(int, char**) { return 1; }
#endif

namespace tilevis::app {
namespace {

struct SimArgs {
  std::string trace, out, tile, config, vcd;
  std::vector<std::string> params;
  uint32_t samples = 0, frame = 0;
  bool list = false;
};

int run_sim(const SimArgs& a) {
#if !TILEVIS_HAVE_SIM
  (void)a;
  throw std::runtime_error("sim: this build has no SystemC model (configured without SystemC)");
#else
  if (a.list) {
    fmt::print("{}", sim::list_params());
    return 0;
  }
  if (a.trace.empty() || a.out.empty()) throw std::runtime_error("sim: expected a trace and -o DIR (or --list-params)");
  std::vector<std::string> params = a.params;
  if (!a.tile.empty()) {
    uint32_t tw = 0, th = 0;
    parse_tile(a.tile, tw, th);
    params.push_back(fmt::format("sim.tile_width={}", tw));
    params.push_back(fmt::format("sim.tile_height={}", th));
  }
  const sim::TilerConfig cfg = sim::load_config(a.config, params);
  if (!a.vcd.empty() && cfg.sim.fidelity == sim::Fidelity::analytic)
    throw std::runtime_error("--vcd " + a.vcd + ": fidelity analytic simulates no events; use tile or primitive");
  const trace::Frame frame = load_frame(a.trace, a.frame, a.samples);
  check_memory("sim " + a.trace, frame, cfg.sim.tile_width, cfg.sim.tile_height);
  sim::SimOptions opt;
  opt.trace_name = a.trace;
  opt.frame_index = a.frame;
  opt.vcd = a.vcd;
  Progress progress("sim: tiles");
  if (progress.enabled()) opt.progress = [&](uint64_t done, uint64_t total) { progress.update(done, total); };
  const sim::SimOutput out = sim::simulate(frame, cfg, opt);
  sim::write_sim_outputs(out, a.out);
  for (const std::string& r : out.systemc_reports) fmt::print(stderr, "tilevis: systemc: {}\n", r);
  const auto& tot = out.result.stats.at("totals");
  // Fidelity auto: the cycles are an estimate with an interval; the counts cover what was simulated.
  std::string cycles = fmt::format("{} cycles", out.cycles), scope;
  if (const auto& s = out.result.stats.at("sampling"); !s.is_null()) {
    cycles = fmt::format("{} cycles (estimated, +/- {:.2f} %)", out.cycles, 100.0 * s.at("relative_half_width").get<double>());
    scope = fmt::format(" in the {} of {} tiles simulated", s.at("tiles_simulated").get<uint64_t>(),
                        s.at("tiles").get<uint64_t>());
  }
  // A recorded functional pass: say which file it came from or went to.
  if (const std::string how = out.result.stats.at("functional"); how != "computed")
    scope += fmt::format(", functional pass {} ({})", how, out.result.stats.at("functional_record_file").get<std::string>());
  fmt::print("sim {} frame {} ({} mode, fidelity {}, {}x{} tiles): {}, {} fragments shaded of {} generated{}, "
             "parameter buffer {} B ({} partial renders), DRAM {} B, {:.3f} s host -> {}\n",
             a.trace, a.frame, sim::to_string(cfg.sim.mode), sim::to_string(cfg.sim.fidelity), cfg.sim.tile_width,
             cfg.sim.tile_height, cycles, tot.at("fragments_shaded").get<uint64_t>(),
             tot.at("fragments_generated").get<uint64_t>(), scope, tot.at("param_buffer_bytes").get<uint64_t>(),
             tot.at("partial_renders").get<uint64_t>(), tot.at("dram_bytes").get<uint64_t>(), out.host_seconds, a.out);
  return 0;
#endif
}

}  // namespace

Command add_sim_command(CLI::App& app) {
  auto a = std::make_shared<SimArgs>();
  auto* cmd = app.add_subcommand("sim", "Run the cycle-approximate SystemC model of the tiler on a trace");
  cmd->add_option("trace", a->trace, "Trace file")->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", a->out, "Result directory");
  cmd->add_option("--tile", a->tile, "Tile size, N or WxH (4..256); overrides sim.tile_width/height");
  cmd->add_option("-c,--config", a->config, "Config file (JSON: nested objects or dotted keys)");
  cmd->add_option("-p,--param", a->params, "Override one parameter: key=value (repeatable)");
  cmd->add_flag("--list-params", a->list, "Print every parameter: name, default, unit, help");
  cmd->add_option("--vcd", a->vcd, "Write a VCD of unit busy and queue occupancy (fidelity tile or primitive)");
  cmd->add_option("--samples", a->samples, "Samples per pixel (1, 2, 4, 8, 16); default: the trace's");
  cmd->add_option("--frame", a->frame, "Frame of the trace")->capture_default_str();
  return {cmd, [a]() { return run_sim(*a); }};
}

}  // namespace tilevis::app
