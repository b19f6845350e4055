// The CUDA reference implementation of the SVGPU visibility pipeline (cuda_ref/): from a
// clip-space trace frame to the canonical outputs (ids per sample, visible area per original
// triangle, per-tile counters). Host-only interface: no CUDA types.
//
// Precision `exact` takes every geometric decision with exact integer predicates and agrees
// with the golden pipeline (model/visibility) bit for bit: ids and per-tile counters. `float`
// runs the per-tile visibility in float32 arithmetic, as SVGPU did.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "tilevis/trace.h"
#include "visibility/tile_counters.h"

namespace tilevis::cuda {

enum class Precision { exact, floating };
enum class Device {
  gpu,  // CUDA device 0
  cpu   // the same stage bodies run one element at a time on the host (no GPU needed):
        // checks the kernels' logic here; timings are host times
};

struct CudaConfig {
  uint32_t tile_w = 32, tile_h = 32;
  // Finer occlusion bins (SVGPU §4.1) within each tile, in pixels; 0: one bin per tile. As in
  // golden, only the scanning of occluders shrinks: ids and counters are unchanged.
  uint32_t occlusion_bin_w = 0, occlusion_bin_h = 0;
  uint32_t depth_bits = 24;
  Precision precision = Precision::exact;
  Device device = Device::gpu;
  uint32_t runs = 20;    // timed runs after warm-up; stage times are medians
  uint32_t warmup = 2;
  bool shuffle_cpu = false;  // cpu: visit elements in a scrambled order (order-independence check)
  uint32_t initial_pool = 0;  // 0: default; else the first size of every overflow-checked pool
                              // (tests use a tiny one to exercise grow-and-retry)
  // Hybrid mode (golden --mode hybrid, vis::ResolverOptions): a tile goes per pixel where two
  // opaque triangles' planes cross inside their overlap, where it holds non-opaque triangles,
  // or where its work is over the budget or the on-chip lists (0: no limit).
  bool hybrid = false;
  uint64_t pair_budget = 0;
  uint32_t list_triangles = 512, list_edges = 256;
  uint32_t detection_bin = 8;  // pixels
};

// Per-stage times in milliseconds (median over runs), in pipeline order.
struct StageTime {
  std::string name;
  double ms = 0;
};

struct CudaResult {
  uint32_t width = 0, height = 0, samples = 1;
  std::vector<int32_t> ids;            // (y * width + x) * samples + s; -1 background
  std::vector<double> visible_area;    // per original triangle, pixels²
  uint32_t tiles_x = 0, tiles_y = 0, tile_w = 0, tile_h = 0;
  std::vector<vis::TileCounters> tiles;  // row-major, the golden tiles.csv's counters
  // Hybrid only, per tile (row-major): 0 analytic, else why per pixel (vis::kPerPixel*); the
  // triangles in some crossing pair (interpenetration tiles); the detector's screens and tests.
  std::vector<uint32_t> per_pixel_cause, crossing_triangles;
  std::vector<uint64_t> detection_screens, detection_tests;

  // Totals (names as in the golden stats.json).
  uint64_t triangles_in = 0, triangles_front = 0, triangles_back = 0, triangles_degenerate = 0,
           triangles_clipped = 0, triangles_frustum_culled = 0, triangles_edge_on = 0, silhouette_edges = 0;
  uint64_t pair_tests = 0, candidate_pairs = 0, clip_polygons = 0, pieces = 0, visible_pieces = 0,
           visible_triangles = 0, occlusion_tests = 0, samples_covered = 0, fragments_generated = 0;
  uint64_t max_tile_triangles = 0, max_tile_edges = 0, max_tile_pieces = 0;
  uint64_t fragments_shaded = 0;  // at 1 sample: shader invocations (golden's fragments_shaded); hybrid's
                                  // per-pixel tiles shade their owners and the non-opaque triangles in front
  uint64_t deep_pairs = 0;       // pairs past the cheap tests (test 6, bounding boxes, test 4)
  uint64_t float_anomalies = 0;  // float only: polygons that outgrew their bound (non-convex results)
  uint64_t float_regularized = 0;     // float only: splits whose vertex sides were made convex first
  uint64_t float_negative_areas = 0;  // float only: visible pieces with a negative area (none: areas are never
                                      // clamped; a float area is used only where its sign is proven)
  uint64_t float_exact_areas = 0;     // float only: visible pieces whose float vertices were not proven a convex
                                      // polygon in positive order: the exact area of the region their lines bound

  // Medians of the whole pipeline (trace in device memory -> id raster).
  // total_ms (the headline): a new frame. With device_sized (every configuration but finer
  // occlusion bins): one launch of the device-sized graph, a CUDA graph that holds no size of
  // any frame (kernels, scans and sorts run over upper bounds learned from earlier runs and read
  // the counts on the device; only buffer capacities carry over, as in any renderer), then one
  // check of overflow after the frame (outside the events; a frame past a bound runs again with
  // host reads); the results are that run's. stream_total_ms: the work queued stage by stage with
  // the host reading sizes in between (host_syncs round trips), no graph (without device_sized
  // also total_ms; on the host emulation every time is this one's). stage_ms and probed_total_ms:
  // a second device-sized graph with an event at every stage boundary (without device_sized, the
  // known frame's, as below). graph_total_ms: the frame recorded as
  // one CUDA graph and replayed (its host reads answered by the first runs; each replay checked
  // against them): a known frame. stage_ms come from a second graph with an event at every
  // stage boundary (its own total: probed_total_ms). cpu: every time is the host emulation's.
  std::vector<StageTime> stage_ms, stream_stage_ms;
  double total_ms = 0, stream_total_ms = 0, graph_total_ms = 0, probed_total_ms = 0;
  // presized_total_ms: the new frame's launches, queued the same way, with no host round trip
  // (each host read answered by the last run's, checked after): total_ms - presized_total_ms is
  // what the host round trips cost, presized_total_ms - graph_total_ms what the launches do.
  double presized_total_ms = 0;
  uint32_t graph_nodes = 0;
  bool device_sized = false;         // total_ms is the device-sized graph's (above)
  uint32_t device_graph_nodes = 0;
  // Programmatic dependent launch in both graphs (TILEVIS_CUDA_PDL: off, exit, launch): the
  // mode and the kernel-to-kernel edges it made programmatic in each.
  std::string graph_pdl = "off";
  uint32_t graph_programmatic_edges = 0, device_graph_programmatic_edges = 0;
  double upload_ms = 0, download_ms = 0;
  uint32_t runs = 0;
  uint32_t retries = 0;             // grow-and-retry rounds (first run)
  uint64_t peak_device_bytes = 0;
  std::string device_name;
  // For lower bounds: work queued on the stream per run (kernels, CUB calls, memsets, copies),
  // host round trips per run, the least DRAM traffic of any implementation (read the trace's
  // vertices and indices, write the id raster) and the device's peak DRAM bandwidth.
  uint32_t queued_operations = 0, host_syncs = 0;
  uint64_t min_dram_bytes = 0;
  double dram_bandwidth_gbs = 0;
  // Measured on the device with an empty kernel: microseconds per back-to-back launch and per
  // launch + 8-byte copy back + wait (a host round trip); 0 where TILEVIS_CUDA_NO_LAUNCH_PROBE is set
  // (compute-sanitizer runs: gpu_run.sh sanitize).
  double launch_us = 0, round_trip_us = 0;
  // k_clip_long's walk timed by clock64 in a build with TILEVIS_CUDA_WALK_CLOCK=ON (empty in
  // others): cycles of each phase summed over every warp and every run of the process, then the
  // steps without and with a split and the pieces walked (clip.cu, WalkPhase).
  std::vector<std::pair<std::string, uint64_t>> walk_clock;
};

// A sequence of frames (an orbit) through one pipeline, as a renderer meets them: per frame, the
// first sight (host clock around its run, buffer growth and grow-and-retry included), then
// `laps` more laps over the sequence, each frame run right after a different one as a new frame
// (sizes read on the host, no graph; CUDA events; median over the laps), then the frame's own
// graph recorded and replayed `config.runs` times (a known frame; median).
struct FrameTime {
  uint32_t frame = 0;
  uint64_t triangles_front = 0;
  double first_ms = 0;
  uint32_t first_retries = 0;
  double new_frame_ms = 0;
  uint32_t retries = 0;  // grow-and-retry rounds in the later laps (their time is host clock)
  double graph_ms = 0;
  uint64_t ids_hash = 0;  // FNV-1a of the id buffer after the frame's last new-frame run
};
std::vector<FrameTime> run_cuda_frames(const std::vector<trace::Frame>& frames, const CudaConfig& config, uint32_t laps);

// FNV-1a over ids (FrameTime::ids_hash of a CudaResult's ids).
uint64_t ids_hash(const std::vector<int32_t>& ids);

// Whether a CUDA device is usable; `why` says what is missing otherwise.
bool cuda_available(std::string* why = nullptr);

// Throws std::runtime_error with a one-line reason (no device, CUDA error, bad config).
CudaResult run_cuda(const trace::Frame& frame, const CudaConfig& config);

// Z-buffer rasterisers of the same frame on the same GPU: the baselines analytic visibility is
// measured against (cuda_ref/src/zbuffer.cu).
//  - tiled: exact, in the manner of CudaRaster. The pipeline's setup arithmetic (clip-space
//    clipping, snap, facing), the front opaque triangles binned into tiles of 64 samples (8x8
//    pixels at 1 sample) by an exact edge test over each tile's rectangle (a triangle over more
//    than 16 tiles through coarse bins of 8x8 tiles first), then a warp per tile, a lane per two
//    samples: coverage by the top-left rule at the snapped sample position, the exact depth test
//    of zbuffer.h (strictly nearer wins; at equal depth the earlier setup triangle). No size is
//    read on the host between its stages (device counters; capacities learned by earlier frames,
//    checked once after the frame). Its ids equal the z-buffer truth's.
//  - naive: one thread per trace triangle from clip space, float depth, a 64-bit atomicMin of
//    (depth bits, id) per sample; no near-plane clipping (triangles with a vertex at w <= 0 or
//    outside the guard band are not drawn: `skipped`). A speed baseline; its ids are measured.
enum class ZBufferKind { tiled, naive };

struct ZBufferResult {
  uint32_t width = 0, height = 0, samples = 1;
  std::vector<int32_t> ids;  // as CudaResult::ids
  std::vector<StageTime> stage_ms;
  double total_ms = 0;       // median of runs: trace in device memory -> id raster, a frame not
                             // seen before (every run queued anew: host_syncs round trips inside it)
  uint32_t runs = 0, host_syncs = 0;
  uint32_t retries = 0;          // tiled: frames run again after a pool overflowed (learning capacities)
  uint64_t triangles_drawn = 0;  // tiled: front opaque setup triangles; naive: trace triangles rastered
  uint64_t bin_entries = 0;      // tiled: (tile, triangle) pairs
  uint64_t skipped = 0;          // naive: opaque triangles not drawn (near plane, guard band)
  uint32_t bin_w = 0, bin_h = 0;
  std::string device_name;
};

ZBufferResult run_cuda_zbuffer(const trace::Frame& frame, const CudaConfig& config, ZBufferKind kind);

}  // namespace tilevis::cuda
