// Tile scheduler: hands a segment's tiles to the tile cores (each: fetch, EVU or HSR,
// fragment, writer) and joins them at the segment's end.
//   row_major: tiles in row-major order, tile i to core i mod N (static);
//   morton:    tiles in Morton (Z) order, tile i to core i mod N (static);
//   dynamic:   Morton order, each tile to the first core that takes one (a core's queue
//              holds one tile beyond the one it fetches).
// At a segment's end every core gets a segment_end; when all have written their last
// tile the scheduler closes the segment and releases its parameter-buffer pages.
#pragma once

#include <vector>

#include <nlohmann/json.hpp>

#include "units/common/unit_base.h"
#include "units/geometry_front_end/geometry_front_end.h"
#include "units/tile_scheduler/tile_sampler.h"

namespace tilevis::sim {

enum class Schedule : uint8_t { row_major, morton, dynamic };
const char* to_string(Schedule s);

struct TileSchedulerConfig {
  uint32_t cores = 1;
  Schedule policy = Schedule::row_major;
  bool sampled = false;     // fidelity auto: render a sample of each segment's tiles (tile_sampler.h)
  SamplingConfig sampling;
};

class TileScheduler : public UnitBase {
 public:
  sc_core::sc_fifo_in<uint32_t> ready;                  // segments the parameter buffer holds
  sc_core::sc_vector<sc_core::sc_fifo_out<Item>> to_core;
  sc_core::sc_vector<sc_core::sc_fifo_in<uint32_t>> done;  // per core: it finished a segment
  sc_core::sc_fifo_out<uint32_t> released;              // segments rendered: free their pages

  SC_HAS_PROCESS(TileScheduler);
  TileScheduler(const sc_core::sc_module_name& name, const UnitEnv& env, const TileSchedulerConfig& config);

  // The segment's non-empty tiles in this policy's order (both levels).
  std::vector<uint32_t> order(const std::vector<uint32_t>& row_major) const;
  // Static policies: the core of the i-th tile in order.
  uint32_t static_core(size_t i) const { return uint32_t(i % m_cfg.cores); }
  const TileSchedulerConfig& config() const { return m_cfg; }
  // Counts a tile given to `core` (both levels).
  void count(uint32_t core);
  uint64_t frame_end_cycle() const { return m_frame_end; }
  bool frame_done() const { return m_done; }
  // Sampled: the frame's cycles as estimated (the simulated end, each segment's sampled
  // render replaced by its estimate) and the interval's half-width; per segment, stats.json's
  // "sampling". Not sampled: the simulated end, width 0.
  double frame_estimate() const;
  double frame_half_width() const;
  nlohmann::json sampling_json() const;
  // Fidelity auto, a one-segment frame whose geometry is sampled too: its estimate replaces
  // its simulated rounds in the frame, and the frame's budget is shared between it and the
  // render at the least host cost (allocate(); the geometry grows between render rounds).
  void share_budget(GeometryFrontEnd* geometry) { m_geometry = geometry; }
  // TileWriter's tile ends wake a sampled round's wait.
  sc_core::sc_event& tile_closed() { return m_tile_closed; }

 private:
  void dispatch();
  void dispatch_sampled(uint32_t segment, const std::vector<uint32_t>& tiles);
  void join();
  uint32_t free_core();
  // Opens `tile` and hands it to a core (the i-th of its dispatch, for static policies); returns the core.
  uint32_t send(uint32_t segment, uint32_t tile, size_t i);

  TileSchedulerConfig m_cfg;
  uint64_t m_frame_end = 0;
  bool m_done = false;
  std::vector<Stat*> m_core_tiles;
  sc_core::sc_event m_tile_closed;
  double m_correction = 0;  // sampled: sum over segments of (estimated - simulated render)
  struct SegmentSample {
    uint32_t segment = 0;
    RenderEstimate estimate;
    uint64_t rounds = 0, simulated_render = 0, start_cycle = 0, certain_tiles = 0;
    uint64_t warmup_tiles = 0;  // simulated for detailed warming, not measured
    double cost = 0;            // host cost of the clusters simulated (SamplingConfig::tile_triangle_cost)
  };
  std::vector<SegmentSample> m_samples;
  GeometryFrontEnd* m_geometry = nullptr;
  // The frame's cycles as estimated while a segment renders: `before` (what precedes its
  // render, the sampled geometry as simulated until then) with the geometry's estimate in
  // place of its simulated rounds, and `render`.
  double frame_so_far(const SegmentSample& rec, uint64_t geometry_simulated_before, double render) const;
};

}  // namespace tilevis::sim
