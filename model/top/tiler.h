// The tiler top level: every unit, the memory behind TLM-2.0 sockets, and the queues
// between them, wired for the configured visibility mode:
//
//   front_end -> setup -> silhouette -> tiling ==(TLM)==> pb ==(TLM)==> memory
//   pb.ready -> fetch -> [evu: reject -> clip -> occlude | hsr | (nothing)] -> fragment -> writer
//   writer.released -> pb (a rendered segment frees its pages)
//
// prepare() runs the functional steps in pipeline order; then either sc_start() (levels
// tile and primitive: event-driven, one wait per transaction) or run_analytic() (closed
// form per tile from the same cost functions, no events).
#pragma once

#include <memory>
#include <vector>

#include "top/config.h"
#include "units/common/frame_work.h"

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
  uint64_t evu_busy_cycles() const;

 private:
  TilerConfig m_cfg;
  FrameWork& m_work;
  UnitEnv m_env;
  std::unique_ptr<Memory> m_memory;
  std::unique_ptr<GeometryFrontEnd> m_front_end;
  std::unique_ptr<PrimitiveSetup> m_setup;
  std::unique_ptr<SilhouetteUnit> m_silhouette;
  std::unique_ptr<ParameterBuffer> m_pb;
  std::unique_ptr<TilingEngine> m_tiling;
  std::unique_ptr<TileFetch> m_fetch;
  std::unique_ptr<EarlyVisibilityUnit> m_evu;
  std::unique_ptr<HsrUnit> m_hsr;
  std::unique_ptr<FragmentUnit> m_fragment;
  std::unique_ptr<TileWriter> m_writer;
  std::vector<std::unique_ptr<OccupancyFifo<Item>>> m_fifos;
  std::unique_ptr<sc_core::sc_fifo<uint32_t>> m_ready, m_released;
  uint64_t m_analytic_cycles = 0;
};

}  // namespace tilevis::sim
