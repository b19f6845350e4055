#include "top/config.h"

#include "geom/tile_grid.h"
#include "tilevis/json_node.h"

#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <sstream>

namespace tilevis::sim {
namespace {

struct Param {
  std::string name, unit, help;
  std::function<nlohmann::json(const TilerConfig&)> get;
  // Sets the value or returns what was expected.
  std::function<std::string(TilerConfig&, const nlohmann::json&)> set;
};

template <typename T>
std::string fmt_range(T lo, T hi) {
  std::ostringstream os;
  os << "[" << lo << ", " << hi << "]";
  return os.str();
}

class Registry {
 public:
  static const Registry& get() {
    static const Registry r;
    return r;
  }
  const Param* find(const std::string& name) const {
    auto it = m_index.find(name);
    return it == m_index.end() ? nullptr : &m_params[it->second];
  }
  const std::vector<Param>& params() const { return m_params; }

 private:
  template <typename T>
  void add_uint(std::string name, std::string unit, std::string help, uint64_t lo, uint64_t hi,
                T& (*field)(TilerConfig&)) {
    const std::string expect = "an integer in " + fmt_range(lo, hi);
    m_params.push_back({name, unit, help, [field](const TilerConfig& c) { return nlohmann::json(field(const_cast<TilerConfig&>(c))); },
                        [field, lo, hi, expect](TilerConfig& c, const nlohmann::json& v) -> std::string {
                          if (!v.is_number_integer() && !v.is_number_unsigned()) return expect;
                          if (v.is_number_integer() && v.get<int64_t>() < 0) return expect;
                          const uint64_t x = v.get<uint64_t>();
                          if (x < lo || x > hi) return expect;
                          field(c) = T(x);
                          return {};
                        }});
    m_index[name] = m_params.size() - 1;
  }
  void add_string(std::string name, std::string unit, std::string help, std::string& (*field)(TilerConfig&)) {
    m_params.push_back({name, unit, help, [field](const TilerConfig& c) { return nlohmann::json(field(const_cast<TilerConfig&>(c))); },
                        [field](TilerConfig& c, const nlohmann::json& v) -> std::string {
                          if (!v.is_string()) return "a string";
                          field(c) = v.get<std::string>();
                          return {};
                        }});
    m_index[name] = m_params.size() - 1;
  }
  void add_real(std::string name, std::string unit, std::string help, double lo, double hi,
                double& (*field)(TilerConfig&)) {
    const std::string expect = "a number in " + fmt_range(lo, hi);
    m_params.push_back({name, unit, help, [field](const TilerConfig& c) { return nlohmann::json(field(const_cast<TilerConfig&>(c))); },
                        [field, lo, hi, expect](TilerConfig& c, const nlohmann::json& v) -> std::string {
                          if (!v.is_number()) return expect;
                          const double x = v.get<double>();
                          if (!(x >= lo && x <= hi)) return expect;
                          field(c) = x;
                          return {};
                        }});
    m_index[name] = m_params.size() - 1;
  }
  template <typename E>
  void add_enum(std::string name, std::string help, std::vector<E> values, E& (*field)(TilerConfig&)) {
    std::string expect = "one of";
    for (size_t i = 0; i < values.size(); ++i) expect += std::string(i ? ", " : " ") + to_string(values[i]);
    m_params.push_back({name, "", help, [field](const TilerConfig& c) { return nlohmann::json(to_string(field(const_cast<TilerConfig&>(c)))); },
                        [field, values, expect](TilerConfig& c, const nlohmann::json& v) -> std::string {
                          if (!v.is_string()) return expect;
                          for (E e : values)
                            if (v.get<std::string>() == to_string(e)) {
                              field(c) = e;
                              return {};
                            }
                          return expect;
                        }});
    m_index[name] = m_params.size() - 1;
  }

  Registry();
  std::vector<Param> m_params;
  std::map<std::string, size_t> m_index;
};

constexpr uint64_t kMaxU32 = std::numeric_limits<uint32_t>::max();

#define TV_UINT(name, field, unit, lo, hi, help) \
  add_uint(name, unit, help, lo, hi, +[](TilerConfig& c) -> auto& { return c.field; })
#define TV_REAL(name, field, unit, lo, hi, help) \
  add_real(name, unit, help, lo, hi, +[](TilerConfig& c) -> double& { return c.field; })

Registry::Registry() {
  add_enum<Fidelity>("sim.fidelity", "analytic: closed form per tile; tile: one transaction per tile per unit; "
                     "primitive: per-primitive transactions, FIFO back-pressure, memory contention; "
                     "rtl: primitive with the EVU's clocks from its Verilated RTL (needs Verilator at build time); "
                     "auto: primitive on a random sample of each segment's tiles, grown until the frame's confidence "
                     "interval fits sim.error_budget, the rest estimated (ids only for the tiles simulated)",
                     {Fidelity::analytic, Fidelity::tile, Fidelity::primitive, Fidelity::rtl, Fidelity::automatic},
                     +[](TilerConfig& c) -> Fidelity& { return c.sim.fidelity; });
  TV_REAL("sim.error_budget", scheduler.sampling.error_budget, "ratio", 1e-4, 1.0,
          "fidelity auto: the confidence interval's half-width to reach, a share of the frame's cycles");
  TV_REAL("sim.confidence", scheduler.sampling.confidence, "ratio", 0.5, 0.9999,
          "fidelity auto: two-sided confidence of the frame's interval");
  TV_UINT("sim.sample_cluster", scheduler.sampling.cluster_tiles, "tiles", 1, 1u << 16,
          "fidelity auto: consecutive tiles (scheduler order) per sampling unit");
  TV_UINT("sim.sample_first", scheduler.sampling.first_clusters, "clusters", 2, 1u << 20,
          "fidelity auto: clusters in the first round of a segment's sample");
  TV_UINT("sim.sample_warm", scheduler.sampling.warm_tiles, "tiles/core", 0, 1u << 10,
          "fidelity auto: tiles per core at the start of a cluster that follows an unsimulated tile, simulated but not measured (detailed warming)");
  TV_UINT("sim.sample_geometry_cluster", scheduler.sampling.geometry_cluster, "triangles", 16, 1u << 24,
          "fidelity auto: consecutive trace triangles per sampling unit of a one-segment frame's geometry");
  TV_UINT("sim.sample_geometry_first", scheduler.sampling.geometry_first, "clusters", 2, 1u << 20,
          "fidelity auto: clusters in the first round of a one-segment frame's geometry, before the render");
  TV_UINT("sim.sample_geometry_warm", scheduler.sampling.geometry_warm, "triangles", 0, 1u << 24,
          "fidelity auto: triangles at the start of a geometry cluster that follows an unsimulated one, simulated but not measured");
  TV_REAL("sim.sample_certainty", scheduler.sampling.certainty_ratio, "ratio", 1.0, 1e9,
          "fidelity auto: tiles with more than this many times the mean binned work (triangles x the EVU's edge rows) or pairs (through test 6) are all simulated; geometry: triangles with this many times the mean bytes");
  TV_UINT("sim.sample_lead", scheduler.sampling.take_all_lead, "clusters", 0, 1u << 20,
          "fidelity auto: clusters before each run of take-all tiles, simulated with it (the run's cold start falls on them)");
  TV_REAL("sim.sample_tile_cost", scheduler.sampling.tile_triangle_cost, "ratio", 1e-3, 1e3,
          "fidelity auto: host cost of a tile's binned triangle against a geometry triangle's, by which the budget is shared between a sampled geometry and the render (measured: 2.4 bunny, 3.0 million)");
  TV_UINT("sim.sample_seed", scheduler.sampling.seed, "", 0, std::numeric_limits<uint64_t>::max(),
          "fidelity auto: seed of the sample (the same seed, the same tiles)");
  add_enum<Mode>("sim.mode", "visibility: analytic (EVU), hybrid (EVU, and the HSR unit for tiles where the analytic answer can be wrong), hsr (per-pixel HSR unit), early_z, none",
                 {Mode::analytic, Mode::hybrid, Mode::hsr, Mode::early_z, Mode::none}, +[](TilerConfig& c) -> Mode& { return c.sim.mode; });
  TV_UINT("sim.tile_width", sim.tile_width, "pixels", geom::TileGrid::kMinTile, geom::TileGrid::kMaxTile, "tile width");
  TV_UINT("sim.tile_height", sim.tile_height, "pixels", geom::TileGrid::kMinTile, geom::TileGrid::kMaxTile,
          "tile height");
  TV_UINT("sim.depth_bits", sim.depth_bits, "bits", 1, 24, "bits of snapped depth");
  add_string("sim.functional_record", "path",
             "recorded functional pass (setup, binning, visibility): absent, the run computes it and writes it "
             "there; present, the run replays it (same frame and functional parameters, else an error; any "
             "fidelity but rtl) and only the timing is simulated; empty: off",
             +[](TilerConfig& c) -> std::string& { return c.sim.functional_record; });
  add_string("sim.functional_cache", "path",
             "folder of recorded functional passes, one per frame and functional parameters (their hash names "
             "the file): a run replays its own if there, else computes it and adds it (not at fidelity auto: a "
             "sample); not used at fidelity rtl; made if missing; empty: off",
             +[](TilerConfig& c) -> std::string& { return c.sim.functional_cache; });
  TV_REAL("sim.clock_mhz", sim.clock_mhz, "MHz", 1.0, 10000.0, "GPU clock; every latency below is in its cycles");
  TV_UINT("sim.batch_triangles", sim.batch_triangles, "triangles", 1, kMaxU32, "geometry transaction size at fidelity tile");
  TV_UINT("sim.fifo_tiles", sim.fifo_tiles, "tiles", 1, 1024, "queue depth between render units at fidelity tile");
  TV_UINT("sim.fifo_primitives", sim.fifo_primitives, "items", 1, 1u << 20, "queue depth between units at fidelity primitive");

  TV_UINT("sim.cores", scheduler.cores, "cores", 1, 64, "tile cores (fetch, visibility, fragment, writer), sharing the memory");
  add_enum<Schedule>("sim.scheduler", "tile order and assignment: row_major or morton (tile i to core i mod N), dynamic (Morton order, to the first free core)",
                     {Schedule::row_major, Schedule::morton, Schedule::dynamic},
                     +[](TilerConfig& c) -> Schedule& { return c.scheduler.policy; });

  // DRAM: JEDEC LPDDR4-4266 timings (units/memory/dram.h says where each comes from).
#define JEDEC " (JESD209-4 LPDDR4-4266, as DRAMSys's JEDEC memspec gives it)"
  add_enum<MemoryModel>("memory.model", "detailed: the DRAM controller and DRAM timing model (queues, write drains, "
                        "banks, rows, refresh); bandwidth: each channel's bus as a server of bursts at "
                        "memory.bandwidth_efficiency of its peak, reads paying the unloaded latency; auto: bandwidth at "
                        "fidelity analytic and tile, detailed at primitive, rtl and auto (assumption: memory "
                        "contention is the primitive level's)",
                        {MemoryModel::automatic, MemoryModel::detailed, MemoryModel::bandwidth},
                        +[](TilerConfig& c) -> MemoryModel& { return c.memory.model; });
  TV_REAL("memory.bandwidth_efficiency", memory.bandwidth_efficiency, "ratio", 0.01, 1.0,
          "memory.model=bandwidth: the share of the buses' peak rate that bursts get, for the row switches, refresh "
          "and write batches of the detailed model (assumption: 0.9 fits it at fidelity tile on the built-in scenes)");
  TV_UINT("memory.channels", memory.dram.channels, "channels", 1, 64, "x16 DRAM channels (4: a 64-bit interface; assumption)");
  TV_UINT("memory.banks", memory.dram.banks, "banks", 1, 64, "banks per channel (JESD209-4: 8)");
  TV_UINT("memory.row_bytes", memory.dram.row_bytes, "bytes", 32, 1u << 20, "row (page) per bank (JESD209-4 x16: 2048)");
  TV_UINT("memory.burst_bytes", memory.dram.burst_bytes, "bytes", 1, 4096, "bytes per burst (BL16 x 16 bits: 32)");
  TV_UINT("memory.interleave_bytes", memory.dram.interleave_bytes, "bytes", 1, 1u << 20, "consecutive bytes per channel (assumption)");
  TV_UINT("memory.tck_ps", memory.dram.tck_ps, "ps", 1, 100000, "DRAM clock period (LPDDR4-4266: 469)");
  TV_UINT("memory.ccd", memory.dram.ccd, "tCK", 1, 1000, "column to column, one burst on the bus" JEDEC);
  TV_UINT("memory.rcd", memory.dram.rcd, "tCK", 0, 10000, "activate to column command" JEDEC);
  TV_UINT("memory.rp", memory.dram.rp, "tCK", 0, 10000, "precharge" JEDEC);
  TV_UINT("memory.ras", memory.dram.ras, "tCK", 0, 10000, "activate to precharge" JEDEC);
  TV_UINT("memory.rl", memory.dram.rl, "tCK", 0, 10000, "read latency" JEDEC);
  TV_UINT("memory.wl", memory.dram.wl, "tCK", 0, 10000, "write latency" JEDEC);
  TV_UINT("memory.refi", memory.dram.refi, "tCK", 1, 1u << 30, "all-bank refresh interval" JEDEC);
  TV_UINT("memory.rfc", memory.dram.rfc, "tCK", 0, 1u << 30, "all-bank refresh cycle time" JEDEC);
  TV_UINT("memory.controller_latency_ns", memory.controller_latency_ns, "ns", 0, 100000, "fabric and controller latency of a read (assumption)");
  // DRAM controller (units/memory/dram_controller.h): gem5 MemCtrl's defaults.
#define GEM5 " (assumption: gem5 MemCtrl/DRAMInterface default)"
  TV_UINT("memory.read_queue", memory.controller.read_queue, "bursts", 1, 1u << 16, "read queue per channel" GEM5);
  TV_UINT("memory.write_buffer", memory.controller.write_buffer, "bursts", 1, 1u << 16,
          "write buffer per channel; a posted write waits only while it is full" GEM5);
  TV_UINT("memory.write_high", memory.controller.write_high, "bursts", 1, 1u << 16,
          "write-buffer occupancy that forces a batch of writes ahead of reads (85 % of 64)" GEM5);
  TV_UINT("memory.write_low", memory.controller.write_low, "bursts", 0, 1u << 16,
          "a forced batch drains down to this; writes above it also go in the bus's idle gaps (50 % of 64)" GEM5);
  TV_UINT("memory.frfcfs_window", memory.controller.frfcfs_window, "bursts", 1, 1u << 16,
          "oldest buffered writes searched for a row hit (FR-FCFS; assumption: the whole buffer, as gem5 searches its whole queue)");
  TV_UINT("memory.read_merge", memory.controller.read_merge, "-", 0, 1,
          "1: a requester's read of a burst its own earlier read has in flight takes that data, as its miss registers merge them (assumption); 0: every read is a burst");
  TV_UINT("framebuffer.colour_bytes", framebuffer.colour_bytes, "bytes", 1, 16, "colour per sample (assumption: RGBA8)");
  TV_UINT("framebuffer.depth_bytes", framebuffer.depth_bytes, "bytes", 1, 8, "depth/stencil per sample (assumption: D24S8)");

  TV_UINT("front_end.vertex_cache_entries", front_end.vertex_cache_entries, "vertices", 1, 1u << 20, "post-transform vertex cache (FIFO)");
  TV_UINT("front_end.index_bytes", front_end.index_bytes, "bytes", 1, 8, "bytes per index");
  TV_UINT("front_end.position_bytes", front_end.position_bytes, "bytes", 1, 64, "bytes per fetched clip-space position");
  TV_UINT("front_end.vertices_per_clock", front_end.vertices_per_clock, "vertices/cycle", 1, 64, "vertex fetch rate");
  TV_UINT("front_end.latency_cycles", front_end.latency_cycles, "cycles", 0, 100000, "pipeline depth, once per segment");

  TV_UINT("setup.triangles_per_clock", setup.triangles_per_clock, "triangles/cycle", 1, 64, "setup rate");
  TV_UINT("setup.clip_cycles", setup.clip_cycles, "cycles", 0, 100000, "extra cycles per triangle a clip plane cuts");
  TV_UINT("setup.latency_cycles", setup.latency_cycles, "cycles", 0, 100000, "pipeline depth, once per segment");

  TV_UINT("silhouette.hash_entries", silhouette.hash_entries, "entries", 1, 1u << 28, "on-chip edge hash capacity; beyond it entries spill to memory");
  TV_UINT("silhouette.entry_bytes", silhouette.entry_bytes, "bytes", 1, 256, "bytes per spilled entry");
  TV_UINT("silhouette.edges_per_clock", silhouette.edges_per_clock, "edges/cycle", 1, 64, "hash look-up rate");
  TV_UINT("silhouette.latency_cycles", silhouette.latency_cycles, "cycles", 0, 100000, "pipeline depth, once per segment");

  TV_UINT("tiling.tile_tests_per_clock", tiling.tile_tests_per_clock, "tests/cycle", 1, 1024, "exact primitive/tile overlap tests");
  TV_UINT("tiling.latency_cycles", tiling.latency_cycles, "cycles", 0, 100000, "pipeline depth, once per segment");

  TV_UINT("pb.capacity_bytes", pb.capacity_bytes, "bytes", 1, uint64_t(1) << 40, "parameter buffer size; a full buffer forces a partial render (assumption)");
  TV_UINT("pb.triangle_bytes", pb.triangle_bytes, "bytes", 1, 1024, "primitive block entry per triangle (assumption)");
  TV_UINT("pb.vertex_bytes", pb.vertex_bytes, "bytes", 1, 1024, "screen-space vertex (plus the draw's varyings) (assumption)");
  TV_UINT("pb.reference_bytes", pb.reference_bytes, "bytes", 1, 64, "control-stream entry per tile per primitive (assumption)");
  TV_UINT("pb.edge_bytes", pb.edge_bytes, "bytes", 1, 1024, "silhouette edge record (assumption)");

  TV_UINT("fetch.primitives_per_clock", fetch.primitives_per_clock, "primitives/cycle", 1, 64, "records parsed per clock");
  TV_UINT("fetch.edges_per_clock", fetch.edges_per_clock, "edges/cycle", 1, 64, "edge records per clock");
  TV_UINT("fetch.latency_cycles", fetch.latency_cycles, "cycles", 0, 100000, "per tile");
  TV_UINT("fetch.cache_bytes", fetch.cache.bytes, "bytes", 1, 1u << 30, "parameter cache for primitive records (per core; assumption)");
  TV_UINT("fetch.cache_line_bytes", fetch.cache.line_bytes, "bytes", 1, 4096, "its line (assumption)");
  TV_UINT("fetch.cache_ways", fetch.cache.ways, "ways", 1, 1024, "its associativity, LRU (assumption)");

  TV_UINT("evu.reject.lanes", evu.reject.lanes, "lanes", 1, 1024, "pairs issued together: edges a row (RTL: TileSequencer LANES)");
  TV_UINT("evu.reject.ii", evu.reject.ii, "cycles", 1, 1024, "clocks per row of pairs (RTL: 1)");
  TV_UINT("evu.reject.latency_cycles", evu.reject.latency_cycles, "cycles", 0, 100000, "PairReject and DepthTest drain, per tile (RTL: 3 + 3)");
  TV_UINT("evu.reject.pass_cycles", evu.reject_pass_cycles, "cycles", 0, 100000, "start and end of a TileSequencer pass (RTL: 2)");
  TV_UINT("evu.reject.readahead_rows", evu.reject_readahead_rows, "rows", 0, 16, "row read ahead and dropped when test 6 stops a triangle before its last row (RTL: 1)");
  TV_UINT("evu.list_load_per_cycle", evu.list_load_per_cycle, "entries", 1, 1024, "list entries loaded per clock per list (RTL: one write port)");
  TV_UINT("evu.clip.lanes", evu.clip.lanes, "lanes", 1, 1024, "independent Clip units (assumption)");
  TV_UINT("evu.clip.ii", evu.clip.ii, "cycles", 1, 1024, "clocks per parent edge of a split (RTL: a vertex a clock)");
  TV_UINT("evu.clip.latency_cycles", evu.clip.latency_cycles, "cycles", 0, 100000, "drain per tile (RTL: inside the split's clocks)");
  TV_UINT("evu.clip.split_cycles", evu.clip_split_cycles, "cycles", 0, 100000, "start and done of a split (RTL: 2)");
  TV_UINT("evu.clip.emit_per_edge", evu.clip_emit_per_edge, "cycles", 0, 1024, "clocks per parent edge to emit a crossing split's children (RTL: 1)");
  TV_UINT("evu.clip.check_cycles", evu.clip_check_cycles, "cycles", 0, 1024, "tests 1-3 re-run on a piece against a candidate edge (assumption: not in the RTL)");
  TV_UINT("evu.occlude.lanes", evu.occlude.lanes, "lanes", 1, 1024, "independent Occlude units (assumption)");
  TV_UINT("evu.occlude.ii", evu.occlude.ii, "cycles", 1, 1024, "clocks per occluder test (RTL: 1)");
  TV_UINT("evu.occlude.latency_cycles", evu.occlude.latency_cycles, "cycles", 0, 100000, "drain per tile (RTL: inside the piece's clocks)");
  TV_UINT("evu.occlude.piece_cycles", evu.occlude_piece_cycles, "cycles", 0, 1024, "interior point of a piece (RTL: 2)");
  TV_UINT("evu.occlude.drain_cycles", evu.occlude_drain_cycles, "cycles", 0, 1024, "last verdict of a piece with occluder tests, the clock after its occluder (RTL: 1)");
  TV_UINT("evu.detect.lanes", evu.detect.lanes, "lanes", 1, 1024, "hybrid: pair comparisons issued together");
  TV_UINT("evu.detect.ii", evu.detect.ii, "cycles", 1, 1024, "hybrid: initiation interval of the pair comparison");
  TV_UINT("evu.detect.beside", evu.detect_beside, "-", 0, 1, "hybrid: 1 the detector has its own datapath and works while reject does; 0 it runs before reject on the reject lanes");
  TV_UINT("evu.detection_bin", evu.detection_bin, "pixels", 0, 256, "hybrid: the detector's bins (0: the tile); its work, not its verdict");
  TV_UINT("evu.hybrid_pair_budget", evu.hybrid_pair_budget, "pairs", 0, 0xffffffffu, "hybrid: a tile whose triangles x edges exceed this goes per pixel (0: no budget)");
  TV_UINT("evu.triangle_list_entries", evu.triangle_list_entries, "triangles", 1, 1u << 24, "on-chip triangle list; longer lists take passes");
  TV_UINT("evu.edge_list_entries", evu.edge_list_entries, "edges", 1, 1u << 24, "on-chip edge list; longer lists take passes");

  TV_UINT("hsr.samples_per_clock", hsr.samples_per_clock, "samples/cycle", 1, 4096, "depth tests per clock");
  TV_UINT("hsr.triangles_per_clock", hsr.triangles_per_clock, "triangles/cycle", 1, 64, "triangle setup rate");
  TV_UINT("hsr.latency_cycles", hsr.latency_cycles, "cycles", 0, 100000, "per tile");

  TV_UINT("fragment.raster_samples_per_clock", fragment.raster_samples_per_clock, "samples/cycle", 1, 4096, "rasteriser output");
  TV_UINT("fragment.depth_tests_per_clock", fragment.depth_tests_per_clock, "samples/cycle", 1, 4096, "early depth tests");
  TV_UINT("fragment.shader_lanes", fragment.shader_lanes, "lanes", 1, 65536, "shader ALU lanes (trace cycles per fragment are per lane)");
  TV_REAL("fragment.texels_per_pixel", fragment.texels_per_pixel, "texels", 0.0, 1024.0, "texture footprint per shaded pixel (assumption: about 1 with mip-mapping)");
  TV_UINT("fragment.texel_bytes", fragment.texel_bytes, "bytes", 1, 64, "bytes per texel (assumption: RGBA8)");
  TV_UINT("fragment.texture_line_bytes", fragment.texture_line_bytes, "bytes", 1, 4096, "texture cache line (assumption)");
  TV_UINT("fragment.latency_cycles", fragment.latency_cycles, "cycles", 0, 100000, "per tile");

  TV_UINT("writer.pixels_per_clock", writer.pixels_per_clock, "pixels/cycle", 1, 4096, "tile write-out rate");
  TV_UINT("writer.latency_cycles", writer.latency_cycles, "cycles", 0, 100000, "per tile");
  TV_REAL("writer.colour_compression", writer.colour_compression, "ratio", 0.01, 1.0, "colour bytes written / bytes of the tile (assumption: 1, no compression)");

  TV_REAL("energy.dram_pj_per_byte", energy.dram_pj_per_byte, "pJ", 0.0, 1e6, "DRAM energy per byte (Horowitz, ISSCC 2014)");
  TV_REAL("energy.shader_pj_per_lane_cycle", energy.shader_pj_per_lane_cycle, "pJ", 0.0, 1e6, "shader lane-cycle: one fp32 multiply-add (Horowitz, ISSCC 2014: 3.7 + 0.9 pJ)");
  TV_REAL("energy.evu_pj_per_test", energy.evu_pj_per_test, "pJ", 0.0, 1e6, "one EVU pair, clip or occlusion test (assumption: ~4 integer multiply-adds at Horowitz, ISSCC 2014)");
  TV_REAL("energy.depth_test_pj", energy.depth_test_pj, "pJ", 0.0, 1e6, "one per-sample depth test, HSR or early-Z (assumption: a multiply-add, a compare and an SRAM read at Horowitz, ISSCC 2014)");
}

#undef JEDEC
#undef GEM5
#undef TV_UINT
#undef TV_REAL

// Nested objects flatten to dotted keys: {"evu": {"reject": {"lanes": 8}}} -> evu.reject.lanes.
void flatten(const nlohmann::json& j, const std::string& prefix, std::vector<std::pair<std::string, nlohmann::json>>& out) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
    if (it->is_object()) flatten(*it, key, out);
    else out.emplace_back(key, *it);
  }
}

size_t distance(const std::string& a, const std::string& b) {
  std::vector<size_t> d(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) d[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t prev = d[0];
    d[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t cur = d[j];
      d[j] = std::min({d[j] + 1, d[j - 1] + 1, prev + (a[i - 1] == b[j - 1] ? 0 : 1)});
      prev = cur;
    }
  }
  return d[b.size()];
}

std::string unknown(const std::string& key) {
  std::string best;
  size_t best_d = 4;
  for (const Param& p : Registry::get().params()) {
    const size_t d = distance(key, p.name);
    if (d < best_d) best_d = d, best = p.name;
  }
  return "unknown parameter" + (best.empty() ? std::string(" (see --list-params)") : " (did you mean " + best + "?)");
}

void apply(TilerConfig& c, const std::string& where, const std::string& key, const nlohmann::json& v) {
  const Param* p = Registry::get().find(key);
  if (!p) throw ConfigError(where + ": " + key + ": " + unknown(key));
  const std::string expected = p->set(c, v);
  if (!expected.empty()) throw ConfigError(where + ": " + key + ": expected " + expected + ", got " + v.dump());
}

// Rules between parameters (each alone is in range).
void check(const TilerConfig& c, const std::string& where) {
  auto fail = [&](const std::string& m) { throw ConfigError(where + ": " + m); };
  const DramConfig& d = c.memory.dram;
  if (d.row_bytes % d.burst_bytes) fail("memory.row_bytes must be a multiple of memory.burst_bytes");
  if (d.interleave_bytes % d.burst_bytes) fail("memory.interleave_bytes must be a multiple of memory.burst_bytes");
  if (d.rfc >= d.refi) fail("memory.rfc must be below memory.refi");
  const ControllerConfig& q = c.memory.controller;
  if (q.write_high > q.write_buffer) fail("memory.write_high must not exceed memory.write_buffer");
  if (q.write_low >= q.write_high) fail("memory.write_low must be below memory.write_high");
  const SamplingConfig& sc = c.scheduler.sampling;
  if (sc.geometry_warm >= sc.geometry_cluster)
    fail("sim.sample_geometry_warm must be below sim.sample_geometry_cluster (a cluster would measure nothing)");
  const CacheConfig& k = c.fetch.cache;
  if (k.bytes % (uint64_t(k.line_bytes) * k.ways))
    fail("fetch.cache_bytes must be a multiple of fetch.cache_line_bytes x fetch.cache_ways");
}

}  // namespace

TilerConfig load_config(const std::string& file, const std::vector<std::string>& overrides) {
  TilerConfig c;
  if (!file.empty()) {
    const nlohmann::json j = json::parse_file(file, +[](const std::string& m) { throw ConfigError(m); });
    if (!j.is_object()) throw ConfigError(file + ": $: expected an object of parameters");
    std::vector<std::pair<std::string, nlohmann::json>> flat;
    flatten(j, "", flat);
    // "sim.mode" and {"sim": {"mode": ...}} name one parameter: giving both is an error, not a
    // silent last-one-wins.
    std::set<std::string> given;
    for (const auto& [k, v] : flat) {
      if (!given.insert(k).second)
        throw ConfigError(file + ": $: parameter " + k + " is set twice (as \"" + k + "\" and nested); expected once");
      apply(c, file + ": $", k, v);
    }
  }
  for (const std::string& o : overrides) {
    const size_t eq = o.find('=');
    if (eq == std::string::npos || eq == 0) throw ConfigError("-p " + o + ": expected key=value");
    const std::string key = o.substr(0, eq), text = o.substr(eq + 1);
    nlohmann::json v = nlohmann::json::parse(text, nullptr, false);
    if (v.is_discarded()) v = text;  // bare words: enum values
    apply(c, "-p " + o, key, v);
  }
  check(c, file.empty() ? std::string("config") : file);
  return c;
}

nlohmann::json to_json(const TilerConfig& c) {
  nlohmann::json j = nlohmann::json::object();
  for (const Param& p : Registry::get().params()) {
    nlohmann::json* node = &j;
    std::string rest = p.name;
    for (size_t dot; (dot = rest.find('.')) != std::string::npos; rest = rest.substr(dot + 1))
      node = &(*node)[rest.substr(0, dot)];
    (*node)[rest] = p.get(c);
  }
  return j;
}

std::string list_params() {
  const TilerConfig defaults;
  std::ostringstream os;
  size_t w = 0;
  for (const Param& p : Registry::get().params()) w = std::max(w, p.name.size());
  for (const Param& p : Registry::get().params()) {
    std::string def = p.get(defaults).dump();
    if (def.size() > 2 && def.front() == '"') def = def.substr(1, def.size() - 2);
    os << p.name << std::string(w + 2 - p.name.size(), ' ') << def << std::string(def.size() < 12 ? 12 - def.size() : 1, ' ')
       << (p.unit.empty() ? "-" : p.unit) << "  " << p.help << '\n';
  }
  return os.str();
}

std::vector<std::string> param_names() {
  std::vector<std::string> v;
  for (const Param& p : Registry::get().params()) v.push_back(p.name);
  return v;
}

}  // namespace tilevis::sim
