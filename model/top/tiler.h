// The tiler top level: every unit, the memory behind TLM-2.0 sockets, and the queues
// between them, wired for the configured visibility mode and number of tile cores:
//
//   front_end -> setup -> silhouette -> tiling ==(TLM)==> pb ==(TLM)==> memory
//   pb.ready -> scheduler -> core k: fetch -> [evu: reject -> clip -> occlude | hsr | (nothing)]
//                                    -> fragment -> writer          (k = 0 .. sim.cores - 1)
//   writers.done -> scheduler.released -> pb (a rendered segment frees its pages)
//
// prepare() runs the functional steps in pipeline order; then either sc_start() (levels
// tile and primitive: event-driven, one wait per transaction) or run_analytic() (closed
// form per tile from the same cost functions, no events).
#pragma once

#include <memory>
#include <vector>

#include "top/config.h"
#include "units/common/frame_work.h"
#include "units/tile_scheduler/tile_scheduler.h"

namespace tilevis::sim {

class Tiler : public sc_core::sc_module {
 public:
  Tiler(const sc_core::sc_module_name& name, const TilerConfig& config, FrameWork& work, bool trace_signals);
  ~Tiler() override;

  void prepare();
  // Frame cycles by the closed form (fidelity analytic).
  uint64_t run_analytic();
  // Frame cycles after sc_start() (fidelity tile, primitive); 0 if the frame did not finish.
  uint64_t simulated_cycles() const;
  bool frame_done() const;

  // Every unit's stats group, in pipeline order.
  std::vector<const StatsGroup*> stats_groups() const;
  void trace(sc_core::sc_trace_file* tf) const;
  uint64_t dram_bytes() const;
  uint64_t param_buffer_bytes() const;  // written over the frame
  uint64_t param_buffer_peak() const;
  // Event-driven levels: per segment, the cycle its geometry ended (ParameterBuffer::ready_cycles).
  const std::vector<uint64_t>& geometry_end_cycles() const;
  uint64_t evu_busy_cycles() const;
  // After the frame: per core, tiles and work (its busiest unit's busy cycles); the share
  // of frame cycles some unit waited on DRAM (event-driven levels; the closed form's
  // DRAM-limited share at fidelity analytic).
  nlohmann::json cores_json() const;
  double memory_bound_share(uint64_t frame_cycles) const;
  Memory& memory() { return *m_memory; }
  const TileScheduler& scheduler() const { return *m_scheduler; }

 private:
  // One tile core: the render pipeline behind the scheduler.
  struct Core {
    std::unique_ptr<TileFetch> fetch;
    std::unique_ptr<EarlyVisibilityUnit> evu;
    std::unique_ptr<HsrUnit> hsr;
    std::unique_ptr<FragmentUnit> fragment;
    std::unique_ptr<TileWriter> writer;
    std::vector<std::unique_ptr<OccupancyFifo<Item>>> fifos;
    std::unique_ptr<sc_core::sc_fifo<Item>> tiles;
    std::unique_ptr<sc_core::sc_fifo<uint32_t>> done;
    std::vector<const UnitBase*> units() const;
  };
  void build_core(uint32_t k, int render_depth, bool per_primitive);
  // The closed form of one tile on core `c`, its DRAM traffic issued at cycle `at`:
  // returns (the tile's step: slowest unit or DRAM, the rest of its pipeline, DRAM-limited part).
  struct Step {
    uint64_t step = 0, drain = 0, memory_bound = 0;
  };
  Step analytic_tile(Core& c, TileWork* w, uint64_t at, uint64_t& pb_read);

  TilerConfig m_cfg;
  FrameWork& m_work;
  UnitEnv m_env;
  std::unique_ptr<Memory> m_memory;
  std::unique_ptr<GeometryFrontEnd> m_front_end;
  std::unique_ptr<PrimitiveSetup> m_setup;
  std::unique_ptr<SilhouetteUnit> m_silhouette;
  std::unique_ptr<ParameterBuffer> m_pb;
  std::unique_ptr<TilingEngine> m_tiling;
  std::unique_ptr<TileScheduler> m_scheduler;
  std::vector<Core> m_cores;
  std::vector<std::unique_ptr<OccupancyFifo<Item>>> m_fifos;  // geometry queues
  std::unique_ptr<sc_core::sc_fifo<uint32_t>> m_ready, m_released;
  MemoryWaits m_waits;
  uint64_t m_analytic_cycles = 0, m_analytic_memory_bound = 0;
  int m_stream_pb = 0, m_stream_stored = 0, m_stream_colour = 0, m_stream_texture = 0, m_stream_vertex = 0, m_stream_spill = 0;
};

}  // namespace tilevis::sim
