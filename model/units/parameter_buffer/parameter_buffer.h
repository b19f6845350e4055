// Parameter buffer: the DRAM region the tiling engine fills with primitive blocks and
// per-tile control streams, and tile fetch reads back. It has a size: when the next
// primitive would not fit, the tiler renders what it holds (a partial render, as PowerVR
// does when its free list runs out), the render frees the pages and tiling goes on.
// The flush points follow from the byte counts below; the buffer blocks writes (a
// stall upstream) until the partial render has released the space.
#pragma once

#include <vector>

#include <tlm_utils/multi_passthrough_target_socket.h>

#include "units/common/stage.h"
#include "units/geometry_front_end/geometry_front_end.h"
#include "units/memory/traffic.h"

namespace tilevis::sim {

struct ParameterBufferConfig {
  // Mesa's PowerVR Vulkan driver grows the global free list (the parameter buffer's
  // pages) up to 256 MiB (PVR_GLOBAL_FREE_LIST_MAX_SIZE, src/imagination/vulkan/
  // pvr_device.c); a partial render is needed only beyond that.
  uint64_t capacity_bytes = 256ull << 20;
  uint32_t triangle_bytes = 12;   // primitive block entry: three 32-bit vertex indices (assumption)
  uint32_t vertex_bytes = 12;     // screen-space vertex: x, y (16.8 fixed) and z, 32 bits each (assumption), + varyings
  uint32_t reference_bytes = 4;   // one 32-bit control-stream word per tile per primitive (assumption)
  uint32_t edge_bytes = 24;       // a silhouette edge: two snapped vertices (analytic mode)
};

class ParameterBuffer : public UnitBase {
 public:
  tlm_utils::multi_passthrough_target_socket<ParameterBuffer> socket;  // tiling engine writes, tile fetch reads
  tlm_utils::simple_initiator_socket<UnitBase> mem;
  sc_core::sc_fifo_in<Item> in;            // batches the tiling engine has written
  sc_core::sc_fifo_out<uint32_t> ready;    // segments complete: render them
  sc_core::sc_fifo_in<uint32_t> released;  // segments rendered: their pages are free

  SC_HAS_PROCESS(ParameterBuffer);
  ParameterBuffer(const sc_core::sc_module_name& name, const UnitEnv& env, const ParameterBufferConfig& config);

  // Bytes each trace triangle adds (after binning and the front end's vertex cache), and
  // the flush plan, handed to FrameWork::set_segments. Throws when one triangle alone
  // does not fit.
  void prepare(const GeometryFrontEnd& front_end);
  uint64_t bytes(uint32_t first, uint32_t end) const { return m_prefix[end] - m_prefix[first]; }
  // Where trace triangle `id` of segment `k` starts in DRAM: each segment fills the buffer
  // from its start (its positions, then its new vertices' varyings, then its edges).
  uint64_t address(uint32_t k, uint32_t id) const {
    return region::parameters + m_prefix[id] - m_prefix[m_work.segment_first(k)];
  }
  uint64_t segment_bytes(uint32_t k) const { return m_segment_bytes[k]; }
  // What tile fetch reads for one triangle of a tile's list: its positions only (the ISP
  // "only fetches screen-space position data", docs.imgtec.com, PowerVR architecture,
  // "Per-Tile Rasterization"); varyings are read for shading, by the fragment unit.
  uint64_t position_record_bytes() const { return m_cfg.triangle_bytes + 3ull * m_cfg.vertex_bytes; }
  uint64_t varying_bytes(uint32_t draw) const;
  const ParameterBufferConfig& config() const { return m_cfg; }
  // The analytic level's bookkeeping (no simulated time).
  void account_analytic(uint64_t written, uint64_t read);
  // Fidelity auto's sampled geometry: arrivals logged here (not owned; null: none).
  GeometryArrivals* arrivals = nullptr;
  uint64_t total_bytes() const;  // every segment's bytes (what the frame writes)
  // Event-driven levels: per segment, the cycle its last triangle reached the buffer (the
  // end of its geometry; fidelity auto: of the simulated rounds, not the estimate).
  const std::vector<uint64_t>& ready_cycles() const { return m_ready_cycles; }

 private:
  void b_transport(int id, tlm::tlm_generic_payload& p, sc_core::sc_time& delay);
  void collect();
  void release();

  ParameterBufferConfig m_cfg;
  std::vector<uint64_t> m_prefix;
  std::vector<uint64_t> m_segment_bytes;
  uint64_t m_used = 0;
  std::vector<uint64_t> m_ready_cycles;
  sc_core::sc_event m_freed;
  Stat& m_written;
  Stat& m_read;
  Stat& m_peak;
  Stat& m_partial;
  Stat& m_capacity;
};

}  // namespace tilevis::sim
