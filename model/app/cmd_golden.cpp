// tilevis golden T -o DIR: the untimed SVGPU visibility pipeline's canonical outputs;
// with --truth, the z-buffer truth of the same snapped scene in the same layout.
#include <chrono>
#include <filesystem>
#include <vector>

#include <fmt/format.h>

#include "commands.h"
#include "progress.h"
#include "tilevis/outputs.h"
#include "tilevis/trace.h"
#include "visibility/evu_jobs.h"
#include "visibility/golden.h"
#include "visibility/parallel.h"
#include "visibility/setup.h"
#include "visibility/svg.h"
#include "visibility/truth.h"

namespace tilevis::app {
namespace {

struct GoldenArgs {
  std::string trace, out, tile = "32", svg, occlusion_bin, dump_evu_jobs;
  uint32_t samples = 0, frame = 0, depth_bits = 24, quantized_depth_bits = 0;
  bool truth = false;
  std::string mode = "analytic";
  uint64_t pair_budget = 0;
  std::vector<uint32_t> list_capacity = {512, 256};
};

nlohmann::json setup_totals(const vis::Setup& s) {
  return {{"triangles_in", s.stats.triangles_in},
          {"triangles_front", s.stats.front_facing},
          {"triangles_back", s.stats.back_facing},
          {"triangles_degenerate", s.stats.degenerate},
          {"triangles_clipped", s.stats.clipped},
          {"triangles_frustum_culled", s.stats.frustum_culled},
          {"triangles_edge_on", s.stats.edge_on},
          {"silhouette_edges", s.stats.silhouette_edges}};
}

int run_truth(const GoldenArgs& a, const trace::Frame& frame, uint32_t tw, uint32_t th) {
  auto t0 = std::chrono::steady_clock::now();
  vis::Setup s = vis::primitive_setup(frame, {a.depth_bits});
  vis::TruthConfig cfg;
  cfg.tile_w = tw;
  cfg.tile_h = th;
  cfg.quantized_depth_bits = a.quantized_depth_bits;
  vis::TruthResult r = vis::zbuffer_truth(s, cfg);
  double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  outputs::Result out;
  out.width = r.width;
  out.height = r.height;
  out.samples = r.samples;
  out.ids = std::move(r.ids);
  out.overdraw = std::move(r.overdraw);
  out.tiles = std::move(r.tiles);
  nlohmann::json totals = setup_totals(s);
  totals["samples_covered"] = r.samples_covered;
  totals["fragments_generated"] = r.fragments_generated;
  totals["fragments_shaded"] = r.modes.hsr;  // shader invocations (MSAA: once per pixel and triangle)
  totals["samples_tested"] = r.fragments_generated;
  out.stats = {{"tool", a.quantized_depth_bits ? "truth_quantized" : "truth"},
               {"trace", a.trace},
               {"frame", a.frame},
               {"config",
                {{"tile_w", tw}, {"tile_h", th}, {"samples", r.samples}, {"depth_bits", a.depth_bits},
                 {"quantized_depth_bits", a.quantized_depth_bits}}},
               {"totals", totals},
               {"modes",
                {{"none", r.modes.none},
                 {"early_z", r.modes.early_z},
                 {"early_z_sorted", r.modes.early_z_sorted},
                 {"prepass", r.modes.prepass},
                 {"hsr", r.modes.hsr},
                 {"hsr_depth_tests", r.modes.hsr_depth_tests}}},
               {"host_seconds", secs}};
  outputs::write_result(out, a.out);
  fmt::print("truth {} frame {}: {}x{}x{} samples, {} fragments generated, {} samples covered, "
             "early-Z shades {}, {:.3f} s -> {}\n",
             a.trace, a.frame, out.width, out.height, out.samples, r.fragments_generated, r.samples_covered,
             r.modes.early_z, secs, a.out);
  return 0;
}

int run_golden(const GoldenArgs& a, const trace::Frame& frame, uint32_t tw, uint32_t th) {
  auto t0 = std::chrono::steady_clock::now();
  vis::Setup s = vis::primitive_setup(frame, {a.depth_bits});
  auto t1 = std::chrono::steady_clock::now();
  vis::GoldenConfig cfg;
  cfg.tile_w = tw;
  cfg.tile_h = th;
  cfg.options.keep_pieces = !a.svg.empty();
  cfg.mode = a.mode;
  cfg.options.pair_budget = a.pair_budget;
  cfg.options.list_triangles = a.list_capacity.at(0);
  cfg.options.list_edges = a.list_capacity.at(1);
  const bool hybrid = a.mode == "hybrid";
  parse_occlusion_bin(a.occlusion_bin, tw, th, cfg.options.occlusion_bin_w, cfg.options.occlusion_bin_h);
  Progress progress("golden: tiles");
  if (progress.enabled()) cfg.progress = [&](uint64_t done, uint64_t total) { progress.update(done, total); };
  vis::GoldenResult r = vis::golden_visibility(s, cfg);
  auto t2 = std::chrono::steady_clock::now();
  double setup_s = std::chrono::duration<double>(t1 - t0).count(), tiles_s = std::chrono::duration<double>(t2 - t1).count();

  outputs::Result out;
  out.width = r.width;
  out.height = r.height;
  out.samples = r.samples;
  out.ids = std::move(r.ids);
  out.visible_area = std::move(r.visible_area);
  out.tiles = std::move(r.tiles);
  nlohmann::json totals = setup_totals(s);
  totals["pair_tests"] = r.pair_tests;
  totals["candidate_pairs"] = r.candidate_pairs;
  totals["clip_polygons"] = r.clip_polygons;
  totals["pieces"] = r.pieces_total;
  totals["visible_pieces"] = r.visible_pieces;
  totals["visible_triangles"] = r.visible_triangles;
  totals["occlusion_tests"] = r.occlusion_tests;
  totals["samples_covered"] = r.samples_covered;
  totals["fragments_generated"] = r.fragments_generated;
  totals["fragments_shaded"] = r.shader_invocations;  // MSAA: once per pixel and triangle
  totals["samples_tested"] = r.fragments_generated;
  totals["max_tile_triangles"] = r.max_tile_triangles;
  totals["max_tile_edges"] = r.max_tile_edges;
  totals["max_tile_pieces"] = r.max_tile_pieces;
  totals["longest_clip_walk"] = {{"steps", r.longest_walk.steps},
                                 {"work", r.longest_walk.work},
                                 {"candidates", r.longest_walk.candidates},
                                 {"pieces", r.longest_walk.pieces},
                                 {"chain_splits", r.longest_walk.chain_splits},
                                 {"splits", r.longest_walk.splits},
                                 {"tile", r.longest_walk.tile},
                                 {"setup_index", r.longest_walk.setup_index}};
  if (hybrid)
    totals["per_pixel_fallback"] = {{"tiles", r.fallback_tiles},
                                    {"tiles_interpenetration", r.fallback_interpenetration},
                                    {"tiles_non_opaque", r.fallback_non_opaque},
                                    {"tiles_budget", r.fallback_budget},
                                    {"samples", r.fallback_samples},
                                    {"triangles", r.fallback_triangles},
                                    {"triangles_crossing", r.fallback_crossing_triangles},
                                    {"detection_screens", r.detection_screens},
                                    {"detection_tests", r.detection_tests}};
  nlohmann::json config = visibility_config(tw, th, cfg.options.occlusion_bin_w, cfg.options.occlusion_bin_h, r.samples, a.depth_bits);
  config["mode"] = a.mode;
  if (hybrid) {
    config["pair_budget"] = a.pair_budget;
    config["list_capacity"] = a.list_capacity;
  }
  out.stats = {{"tool", "golden"},
               {"trace", a.trace},
               {"frame", a.frame},
               {"config", config},
               {"totals", totals},
               {"stage_seconds", {{"setup", setup_s}, {"tiles", tiles_s}}},
               {"host_seconds", setup_s + tiles_s},
               {"host_threads", vis::host_threads()}};
  outputs::write_result(out, a.out);
  if (!a.svg.empty()) vis::write_svg(a.svg, r.width, r.height, r.pieces);
  if (!a.dump_evu_jobs.empty()) {
    std::filesystem::create_directories(a.dump_evu_jobs);
    const std::string path = a.dump_evu_jobs + "/evu_jobs.txt";
    const uint64_t jobs = vis::write_evu_jobs(s, tw, th, a.frame, path);
    fmt::print("  {} early-visibility tile jobs -> {}\n", jobs, path);
  }
  fmt::print("golden {} frame {} at {}x{} tiles: {} triangles, {} silhouette edges, {} candidate pairs, {} clips, "
             "{} pieces ({} visible), {:.3f} s -> {}\n",
             a.trace, a.frame, tw, th, s.stats.triangles_in, s.stats.silhouette_edges, r.candidate_pairs,
             r.clip_polygons, r.pieces_total, r.visible_pieces, setup_s + tiles_s, a.out);
  if (hybrid)
    fmt::print("  hybrid: {} of {} tiles per pixel ({} interpenetration, {} non-opaque, {} over budget), {} samples, "
               "{} triangles ({} of them crossing another)\n",
               r.fallback_tiles, out.tiles.rows.size(), r.fallback_interpenetration, r.fallback_non_opaque,
               r.fallback_budget, r.fallback_samples, r.fallback_triangles, r.fallback_crossing_triangles);
  return 0;
}

}  // namespace

Command add_golden_command(CLI::App& app) {
  auto a = std::make_shared<GoldenArgs>();
  auto* cmd = app.add_subcommand("golden", "Run the golden visibility pipeline (or, with --truth, the z-buffer truth)");
  cmd->add_option("trace", a->trace, "Trace file")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", a->out, "Result directory")->required();
  cmd->add_option("--tile", a->tile, "Tile size, N or WxH (4..256)")->capture_default_str();
  cmd->add_option("--samples", a->samples, "Samples per pixel (1, 2, 4, 8, 16); default: the trace's");
  cmd->add_option("--frame", a->frame, "Frame of the trace")->capture_default_str();
  cmd->add_option("--depth-bits", a->depth_bits, "Bits of snapped depth")->check(CLI::Range(1, 24))->capture_default_str();
  cmd->add_flag("--truth", a->truth, "Write the z-buffer truth instead");
  cmd->add_option("--quantized-depth", a->quantized_depth_bits,
                  "With --truth: compare depth rounded to N bits, as hardware does (shows z-fighting)")
      ->check(CLI::Range(1, 24));
  cmd->add_option("--mode", a->mode,
                  "Tile resolver. analytic: SVGPU in every tile; hybrid: tiles where the analytic answer can be "
                  "wrong (interpenetration, non-opaque content, work over --pair-budget) go per pixel; per_pixel: "
                  "the exact z-buffer in every tile (the truth's ids, tile by tile)")
      ->check(CLI::IsMember(vis::tile_resolver_modes()))
      ->capture_default_str();
  cmd->add_option("--pair-budget", a->pair_budget,
                  "With --mode hybrid: a tile whose triangles x edges exceed this goes per pixel (0: no budget)")
      ->capture_default_str();
  cmd->add_option("--list-capacity", a->list_capacity,
                  "With --mode hybrid: TRIANGLES EDGES the early-visibility unit's on-chip lists hold; a tile with "
                  "more goes per pixel (0: no limit; the model's evu.triangle_list_entries, evu.edge_list_entries)")
      ->expected(2)
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--svg", a->svg, "Also write the visible planar map as SVG");
  cmd->add_option("--dump-evu-jobs", a->dump_evu_jobs,
                  "Also write every tile's early-visibility job (rectangle, triangles, silhouette edges, the "
                  "analytic counters) to DIR/evu_jobs.txt: the RTL testbenches' vectors (rtl_ref/README.md)");
  cmd->add_option("--occlusion-bin", a->occlusion_bin,
                  "Finer occlusion bins (SVGPU 4.1), N or WxH pixels within each tile: only the scanning of "
                  "occluders shrinks; ids and counters are unchanged (default: 8, or the tile if smaller)");
  return {cmd, [a]() {
            uint32_t tw = 0, th = 0;
            parse_tile(a->tile, tw, th);
            trace::Frame frame = load_frame(a->trace, a->frame, a->samples);
            check_memory(std::string(a->truth ? "golden --truth " : "golden ") + a->trace, frame, tw, th);
            if (a->truth) return run_truth(*a, frame, tw, th);
            return run_golden(*a, frame, tw, th);
          }};
}

}  // namespace tilevis::app
