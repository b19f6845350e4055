// tilevis cuda T -o DIR: the CUDA reference implementation (cuda_ref/) on a trace frame, in
// the canonical output layout of `tilevis golden`, plus per-stage GPU times (CUDA events,
// median of --runs after warm-up), the device name and its peak device memory.
#include <chrono>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>

#include "commands.h"
#include "tilevis/outputs.h"
#include "tilevis/trace.h"
#if TILEVIS_HAVE_CUDA_REF
#include "tilevis/cuda_ref.h"
#endif

namespace tilevis::app {
namespace {

struct CudaArgs {
  std::string trace, out, tile = "32", precision = "exact", device = "gpu", occlusion_bin, zbuffer, baselines = "on";
  uint32_t samples = 0, frame = 0, depth_bits = 24, runs = 20, warmup = 2;
  double hw_raster_ms = 0;  // the GPU's own rasteriser on this frame (cuda_ref/tools/gl_raster), when measured
  uint32_t laps = 0;        // > 0: every frame of the trace in sequence (run_cuda_frames), this many laps timed
  std::string mode = "analytic";
  uint64_t pair_budget = 0;
  std::vector<uint32_t> list_capacity = {512, 256};
};

#if TILEVIS_HAVE_CUDA_REF
nlohmann::json zbuffer_json(const cuda::ZBufferResult& z) {
  nlohmann::json st = nlohmann::json::object();
  for (const auto& s : z.stage_ms) st[s.name] = s.ms;
  return {{"total_ms", z.total_ms}, {"stage_ms", st}, {"runs", z.runs}, {"host_syncs", z.host_syncs},
          {"triangles_drawn", z.triangles_drawn}, {"bin_entries", z.bin_entries}, {"skipped", z.skipped},
          {"retries", z.retries},
          {"bin", std::to_string(z.bin_w) + "x" + std::to_string(z.bin_h)}};
}

// --zbuffer tiled|naive: a z-buffer of the frame instead of the analytic pipeline (the
// baselines of cuda_ref.h), in the canonical layout (ids and the covered samples).
int run_zbuffer(const CudaArgs& a, const trace::Frame& frame, const cuda::CudaConfig& cfg) {
  const auto t0 = std::chrono::steady_clock::now();
  cuda::ZBufferResult z = cuda::run_cuda_zbuffer(frame, cfg, a.zbuffer == "naive" ? cuda::ZBufferKind::naive
                                                                                   : cuda::ZBufferKind::tiled);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  outputs::Result out;
  out.width = z.width;
  out.height = z.height;
  out.samples = z.samples;
  uint64_t covered = 0;
  for (int32_t id : z.ids) covered += id >= 0 ? 1 : 0;
  out.ids = std::move(z.ids);
  nlohmann::json config = {{"zbuffer", a.zbuffer}, {"samples", z.samples}, {"depth_bits", a.depth_bits},
                           {"device", a.device}};
  out.stats = {{"tool", "cuda_zbuffer"},
               {"trace", a.trace},
               {"frame", a.frame},
               {"config", config},
               {"totals", {{"samples_covered", covered}}},
               {"device", z.device_name},
               {"total_ms", z.total_ms},
               {"zbuffer", zbuffer_json(z)},
               {"timing", a.device == "gpu" ? "CUDA events on the stream, median of runs after warm-up; every run a "
                                              "new frame queued anew (tiled: no size read on the host between its "
                                              "stages; its overflow counters are read once, after the last event)"
                                            : "host clock (emulation)"},
               {"host_seconds", secs}};
  outputs::write_result(out, a.out);
  fmt::print("cuda zbuffer ({}) {} frame {} on {}: {} triangles drawn, {} skipped; {:.3f} ms (median of {}) -> {}\n",
             a.zbuffer, a.trace, a.frame, z.device_name, z.triangles_drawn, z.skipped, z.total_ms, z.runs, a.out);
  return 0;
}

// --laps N: every frame of the trace through one pipeline in order (an orbit), the first sight,
// then N laps of new frames, then each frame's graph replayed; DIR/sequence.json and a table.
int run_sequence(const CudaArgs& a, const cuda::CudaConfig& cfg) {
  trace::Trace t = trace::read(a.trace);
  std::vector<trace::Frame> frames;
  for (uint32_t k = 0; k < t.frames.size(); ++k) frames.push_back(load_frame(a.trace, k, a.samples));
  const std::vector<cuda::FrameTime> ft = cuda::run_cuda_frames(frames, cfg, a.laps);
  nlohmann::json rows = nlohmann::json::array();
  fmt::print("cuda {} ({} frames, {}, {}x{} tiles, {} laps): ms per frame\n", a.trace, ft.size(), a.precision,
             cfg.tile_w, cfg.tile_h, a.laps);
  fmt::print("  {:>5} {:>9} {:>10} {:>14} {:>9} {:>8}\n", "frame", "front", "first", "new frame", "graph", "retries");
  for (const auto& f : ft) {
    rows.push_back({{"frame", f.frame}, {"triangles_front", f.triangles_front}, {"first_ms", f.first_ms},
                    {"first_retries", f.first_retries}, {"new_frame_ms", f.new_frame_ms}, {"retries", f.retries},
                    {"graph_ms", f.graph_ms}, {"ids_hash", fmt::format("{:016x}", f.ids_hash)}});
    fmt::print("  {:>5} {:>9} {:>10.3f} {:>14.3f} {:>9.3f} {:>8}\n", f.frame, f.triangles_front, f.first_ms,
               f.new_frame_ms, f.graph_ms, f.first_retries + f.retries);
  }
  nlohmann::json j = {{"tool", "cuda_sequence"},
                      {"trace", a.trace},
                      {"precision", a.precision},
                      {"mode", a.mode},
                      {"tile", a.tile},
                      {"laps", a.laps},
                      {"timing", "first_ms: host clock around the frame's first run in the sequence (buffer growth "
                                 "included); new_frame_ms: CUDA events, median over the laps, each run right after "
                                 "another frame, sizes read on the host, no graph; graph_ms: the frame's own graph "
                                 "recorded and replayed (median of runs)"},
                      {"frames", rows}};
  std::filesystem::create_directories(a.out);
  std::ofstream(std::filesystem::path(a.out) / "sequence.json") << j.dump(1) << "\n";
  return 0;
}

int run(const CudaArgs& a, const trace::Frame& frame, uint32_t tw, uint32_t th) {
  cuda::CudaConfig cfg;
  cfg.tile_w = tw;
  cfg.tile_h = th;
  parse_occlusion_bin(a.occlusion_bin, tw, th, cfg.occlusion_bin_w, cfg.occlusion_bin_h);
  cfg.depth_bits = a.depth_bits;
  cfg.precision = a.precision == "float" ? cuda::Precision::floating : cuda::Precision::exact;
  cfg.device = a.device == "cpu" ? cuda::Device::cpu : cuda::Device::gpu;
  cfg.runs = a.runs;
  cfg.warmup = a.warmup;
  cfg.hybrid = a.mode == "hybrid";
  cfg.pair_budget = a.pair_budget;
  cfg.list_triangles = a.list_capacity.at(0);
  cfg.list_edges = a.list_capacity.at(1);
  if (cfg.device == cuda::Device::gpu) {
    std::string why;
    if (!cuda::cuda_available(&why)) {
      fmt::print(stderr, "tilevis cuda: no usable CUDA GPU ({}); nothing written (--device cpu runs the kernels' "
                         "logic on the host)\n", why);
      return 2;
    }
  } else {
    cfg.runs = std::min<uint32_t>(cfg.runs, 1);
    cfg.warmup = 1;
  }
  if (!a.zbuffer.empty()) return run_zbuffer(a, frame, cfg);
  if (a.laps > 0) return run_sequence(a, cfg);
  const auto t0 = std::chrono::steady_clock::now();
  cuda::CudaResult r = cuda::run_cuda(frame, cfg);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  outputs::Result out;
  out.width = r.width;
  out.height = r.height;
  out.samples = r.samples;
  out.ids = std::move(r.ids);
  out.visible_area = std::move(r.visible_area);
  out.tiles.resize(tw, th, r.width, r.height, vis::TileCounters::columns());
  if (out.tiles.rows.size() != r.tiles.size()) throw std::runtime_error("cuda: tile table size mismatch");
  for (size_t t = 0; t < r.tiles.size(); ++t) r.tiles[t].write(out.tiles.rows[t].data());
  // Hybrid: golden's extra tiles.csv columns (hybrid_resolver.cpp) and its fallback totals.
  nlohmann::json fallback;
  if (cfg.hybrid) {
    std::vector<std::string> cols = vis::TileCounters::columns();
    for (const char* c : {"per_pixel", "per_pixel_cause", "detection_screens", "detection_tests"}) cols.push_back(c);
    outputs::TileTable t;
    t.resize(tw, th, r.width, r.height, cols);
    uint64_t tiles = 0, by_cause[4] = {0, 0, 0, 0}, samples = 0, triangles = 0, crossing = 0, screens = 0, tests = 0;
    for (size_t k = 0; k < r.tiles.size(); ++k) {
      r.tiles[k].write(t.rows[k].data());
      const uint32_t cause = r.per_pixel_cause.at(k);
      const size_t n = vis::TileCounters::kCount;
      t.rows[k][n] = cause != 0;
      t.rows[k][n + 1] = cause;
      t.rows[k][n + 2] = int64_t(r.detection_screens[k]);
      t.rows[k][n + 3] = int64_t(r.detection_tests[k]);
      screens += r.detection_screens[k];
      tests += r.detection_tests[k];
      if (cause == 0) continue;
      ++tiles;
      ++by_cause[cause & 3];
      samples += uint64_t(r.tiles[k].samples_covered);
      triangles += uint64_t(r.tiles[k].triangles);
      crossing += r.crossing_triangles[k];
    }
    out.tiles = std::move(t);
    fallback = {{"tiles", tiles},           {"tiles_interpenetration", by_cause[1]}, {"tiles_non_opaque", by_cause[2]},
                {"tiles_budget", by_cause[3]}, {"samples", samples},             {"triangles", triangles},
                {"triangles_crossing", crossing}, {"detection_screens", screens},  {"detection_tests", tests}};
  }
  nlohmann::json totals = {{"triangles_in", r.triangles_in},
                           {"triangles_front", r.triangles_front},
                           {"triangles_back", r.triangles_back},
                           {"triangles_degenerate", r.triangles_degenerate},
                           {"triangles_clipped", r.triangles_clipped},
                           {"triangles_frustum_culled", r.triangles_frustum_culled},
                           {"triangles_edge_on", r.triangles_edge_on},
                           {"silhouette_edges", r.silhouette_edges},
                           {"pair_tests", r.pair_tests},
                           {"candidate_pairs", r.candidate_pairs},
                           {"clip_polygons", r.clip_polygons},
                           {"pieces", r.pieces},
                           {"visible_pieces", r.visible_pieces},
                           {"visible_triangles", r.visible_triangles},
                           {"occlusion_tests", r.occlusion_tests},
                           {"samples_covered", r.samples_covered},
                           {"fragments_generated", r.fragments_generated},
                           {"samples_tested", r.fragments_generated},
                           {"max_tile_triangles", r.max_tile_triangles},
                           {"max_tile_edges", r.max_tile_edges},
                           {"max_tile_pieces", r.max_tile_pieces},
                           {"deep_pairs", r.deep_pairs},
                           {"float_anomalies", r.float_anomalies},
                           {"float_regularized", r.float_regularized},
                           {"float_negative_areas", r.float_negative_areas},
                           {"float_exact_areas", r.float_exact_areas}};
  // Shader invocations (once per pixel and triangle) are the covered samples at 1 sample per
  // pixel; with more samples the CUDA reference does not count them (golden does).
  if (r.samples == 1) totals["fragments_shaded"] = r.fragments_shaded;
  if (cfg.hybrid) totals["per_pixel_fallback"] = fallback;
  auto stage_json = [](const std::vector<tilevis::cuda::StageTime>& v) {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& s : v) j[s.name] = s.ms;
    return j;
  };
  nlohmann::json config = visibility_config(tw, th, cfg.occlusion_bin_w, cfg.occlusion_bin_h, r.samples, a.depth_bits);
  config["precision"] = a.precision;
  config["device"] = a.device;
  config["mode"] = a.mode;
  if (cfg.hybrid) {
    config["pair_budget"] = a.pair_budget;
    config["list_capacity"] = a.list_capacity;
  }
  out.stats = {{"tool", "cuda"},
               {"trace", a.trace},
               {"frame", a.frame},
               {"config", config},
               {"totals", totals},
               {"device", r.device_name},
               {"stage_ms", stage_json(r.stage_ms)},
               {"total_ms", r.total_ms},
               {"graph_total_ms", r.graph_total_ms},
               {"stream_stage_ms", stage_json(r.stream_stage_ms)},
               {"stream_total_ms", r.stream_total_ms},
               {"presized_total_ms", r.presized_total_ms},
               {"probed_total_ms", r.probed_total_ms},
               {"graph_nodes", r.graph_nodes},
               {"device_graph_nodes", r.device_graph_nodes},
               {"graph_pdl", r.graph_pdl},
               {"graph_programmatic_edges", r.graph_programmatic_edges},
               {"device_graph_programmatic_edges", r.device_graph_programmatic_edges},
               {"timing", a.device == "gpu" ? "CUDA events, median of runs after warm-up. total_ms: a new frame, "
                                              "one launch of the device-sized graph (no size of any frame in it: "
                                              "grids, scans and sorts over bounds learned from earlier runs, counts "
                                              "read on the device; the overflow check after it outside the events); "
                                              "stream_total_ms: the frame queued stage by stage with the host reading "
                                              "sizes in between, no graph; graph_total_ms: the known "
                                              "frame as one CUDA graph (sizes as the first runs read them; every "
                                              "replay checked) with events at its ends only; stage_ms from a second "
                                              "device-sized graph with an event at every stage boundary (its total: "
                                              "probed_total_ms); stream_stage_ms: the stream's stages; "
                                              "presized_total_ms: the stream's launches with no host round trip "
                                              "(its reads answered by the last run's, checked after)"
                                            : "host clock (emulation)"},
               {"runs", r.runs},
               {"upload_ms", r.upload_ms},
               {"download_ms", r.download_ms},
               {"retries", r.retries},
               {"peak_device_bytes", r.peak_device_bytes},
               {"queued_operations", r.queued_operations},
               {"host_syncs", r.host_syncs},
               {"min_dram_bytes", r.min_dram_bytes},
               {"dram_bandwidth_gbs", r.dram_bandwidth_gbs},
               {"launch_us", r.launch_us},
               {"round_trip_us", r.round_trip_us},
               {"host_seconds", secs}};
  // The z-buffers of the same frame on the same GPU, and the ratios to each (> 1: slower).
  if (a.baselines != "off" && cfg.device == cuda::Device::gpu) {
    cuda::CudaConfig zc = cfg;
    const cuda::ZBufferResult tiled = cuda::run_cuda_zbuffer(frame, zc, cuda::ZBufferKind::tiled);
    // --baselines tiled: the naive one not timed (at 4K 4 spp its big triangles take seconds a run).
    cuda::ZBufferResult naive = tiled;
    if (a.baselines == "on") naive = cuda::run_cuda_zbuffer(frame, zc, cuda::ZBufferKind::naive);
    uint64_t naive_diff = 0, exact_diff = 0;
    for (size_t k = 0; k < tiled.ids.size(); ++k) naive_diff += tiled.ids[k] != naive.ids[k] ? 1 : 0;
    // The analytic ids against the exact z-buffer's (exact analytic equals them where no
    // planes cross; the truth comparison is tilevis compare's).
    for (size_t k = 0; k < tiled.ids.size() && k < out.ids.size(); ++k) exact_diff += tiled.ids[k] != out.ids[k] ? 1 : 0;
    out.stats["cuda_zbuffer"] = zbuffer_json(tiled);
    out.stats["cuda_zbuffer"]["differs_from_this_run"] = exact_diff;
    out.stats["cuda_zbuffer_ms"] = tiled.total_ms;
    // Both z-buffers are timed as new frames: the ratios are new frame to new frame; the graph's beside.
    out.stats["cuda_zbuffer_ratio"] = tiled.total_ms > 0 ? r.total_ms / tiled.total_ms : 0.0;
    out.stats["cuda_zbuffer_ratio_graph"] = tiled.total_ms > 0 ? r.graph_total_ms / tiled.total_ms : 0.0;
    if (a.baselines == "on") {
      out.stats["naive_zbuffer"] = zbuffer_json(naive);
      out.stats["naive_zbuffer"]["differs_from_cuda_zbuffer"] = naive_diff;
      out.stats["naive_zbuffer_ms"] = naive.total_ms;
      out.stats["naive_zbuffer_ratio"] = naive.total_ms > 0 ? r.total_ms / naive.total_ms : 0.0;
    }
    fmt::print("  z-buffers: tiled exact {:.3f} ms (ratio {:.2f}), naive {:.3f} ms (ratio {:.2f}, {} samples differ)\n",
               tiled.total_ms, r.total_ms / tiled.total_ms, naive.total_ms, r.total_ms / naive.total_ms, naive_diff);
  }
  if (!r.walk_clock.empty()) {  // a TILEVIS_CUDA_WALK_CLOCK build
    nlohmann::json w = nlohmann::json::object();
    for (const auto& [name, value] : r.walk_clock) w[name] = value;
    out.stats["clip_walk_clock"] = w;
  }
  if (a.hw_raster_ms > 0) {
    out.stats["hw_raster_ms"] = a.hw_raster_ms;
    out.stats["hw_raster_ratio"] = r.total_ms / a.hw_raster_ms;
    out.stats["hw_raster_ratio_graph"] = r.graph_total_ms / a.hw_raster_ms;
  }
  outputs::write_result(out, a.out);
  fmt::print("cuda {} frame {} at {}x{} tiles, {} on {}: {} triangles, {} silhouette edges, {} candidate pairs, "
             "{} clips, {} pieces ({} visible); {:.3f} ms (median of {}), peak {:.1f} MiB -> {}\n",
             a.trace, a.frame, tw, th, a.precision, r.device_name, r.triangles_in, r.silhouette_edges,
             r.candidate_pairs, r.clip_polygons, r.pieces, r.visible_pieces, r.total_ms, r.runs,
             double(r.peak_device_bytes) / (1 << 20), a.out);
  for (size_t k = 0; k < r.stage_ms.size(); ++k)
    fmt::print("  {:<12} {:9.3f} ms   (stream {:.3f} ms)\n", r.stage_ms[k].name, r.stage_ms[k].ms, r.stream_stage_ms[k].ms);
  fmt::print("  {:<12} {:9.3f} ms   (new frame: {} host round trips, no graph; the known frame's graph replayed: "
             "{:.3f} ms)\n", "total", r.total_ms, r.host_syncs, r.graph_total_ms);
  return 0;
}
#endif

}  // namespace

Command add_cuda_command(CLI::App& app) {
  auto a = std::make_shared<CudaArgs>();
  auto* cmd = app.add_subcommand("cuda", "Run the CUDA reference implementation (cuda_ref) on a trace");
  cmd->add_option("trace", a->trace, "Trace file")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", a->out, "Result directory")->required();
  cmd->add_option("--tile", a->tile, "Tile size, N or WxH (4..256)")->capture_default_str();
  cmd->add_option("--samples", a->samples, "Samples per pixel (1, 2, 4, 8, 16); default: the trace's");
  cmd->add_option("--precision", a->precision, "exact (bit-identical to golden) or float (float32, as SVGPU)")
      ->check(CLI::IsMember({"exact", "float"}))
      ->capture_default_str();
  cmd->add_option("--runs", a->runs, "Timed runs after warm-up (stage times are medians)")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str();
  cmd->add_option("--warmup", a->warmup, "Untimed runs first (the first also grows the buffers)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--frame", a->frame, "Frame of the trace")->capture_default_str();
  cmd->add_option("--occlusion-bin", a->occlusion_bin,
                  "Finer occlusion bins (SVGPU 4.1), N or WxH pixels within each tile; ids and counters are "
                  "unchanged (default: the tile)");
  cmd->add_option("--depth-bits", a->depth_bits, "Bits of snapped depth")->check(CLI::Range(1, 24))->capture_default_str();
  cmd->add_option("--device", a->device, "gpu, or cpu: the kernels' logic on the host, one element at a time")
      ->check(CLI::IsMember({"gpu", "cpu"}))
      ->capture_default_str();
  cmd->add_option("--mode", a->mode,
                  "analytic: SVGPU in every tile; hybrid: golden --mode hybrid's tiles go per pixel (interpenetration, "
                  "non-opaque content, work over --pair-budget or the lists)")
      ->check(CLI::IsMember({"analytic", "hybrid"}))
      ->capture_default_str();
  cmd->add_option("--pair-budget", a->pair_budget,
                  "With --mode hybrid: a tile whose triangles x edges exceed this goes per pixel (0: no budget)")
      ->capture_default_str();
  cmd->add_option("--list-capacity", a->list_capacity,
                  "With --mode hybrid: TRIANGLES EDGES the on-chip lists hold; a tile with more goes per pixel (0: no limit)")
      ->expected(2)
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--zbuffer", a->zbuffer,
                  "Run a z-buffer of the frame instead: tiled (exact, equal to the truth's ids) or naive (a thread "
                  "per triangle, float depth, 64-bit atomicMin)")
      ->check(CLI::IsMember({"tiled", "naive"}));
  cmd->add_option("--baselines", a->baselines,
                  "on: also time both z-buffers on the same GPU and write cuda_zbuffer_ratio, naive_zbuffer_ratio; "
                  "tiled: the tiled one only")
      ->check(CLI::IsMember({"on", "tiled", "off"}))
      ->capture_default_str();
  cmd->add_option("--laps", a->laps,
                  "Every frame of the trace in order through one pipeline (an orbit): first sight, then this many "
                  "laps of new frames, then each frame's graph; writes DIR/sequence.json (0: one frame, --frame)")
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--hw-raster-ms", a->hw_raster_ms,
                  "The GPU's own rasteriser's time for this frame (cuda_ref/tools/gl_raster): writes hw_raster_ratio")
      ->check(CLI::PositiveNumber);
  return {cmd, [a]() {
            uint32_t tw = 0, th = 0;
            parse_tile(a->tile, tw, th);
#if TILEVIS_HAVE_CUDA_REF
            trace::Frame frame = load_frame(a->trace, a->frame, a->samples);
            return run(*a, frame, tw, th);
#else
            fmt::print(stderr, "tilevis cuda: this tilevis was built without CUDA (no nvcc at configure time, or "
                               "-DTILEVIS_CUDA=OFF); nothing written\n");
            return 2;
#endif
          }};
}

}  // namespace tilevis::app
