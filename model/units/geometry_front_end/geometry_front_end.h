// Geometry front end: index and vertex fetch of the trace's draws (DESIGN.md pipeline,
// first stage). The trace holds post-vertex-shader clip-space positions, so the unit
// models the fetch and a post-transform vertex cache, not vertex shading.
#pragma once

#include <memory>
#include <vector>

#include "units/common/stage.h"
#include "units/tile_scheduler/tile_sampler.h"

namespace tilevis::sim {

struct GeometryFrontEndConfig {
  // Post-transform vertex cache: 32 entries, FIFO replacement (assumption: the size
  // Forsyth's "Linear-Speed Vertex Cache Optimisation" (2006) designs for; PowerVR's is
  // not public).
  uint32_t vertex_cache_entries = 32;
  uint32_t index_bytes = 4;            // 32-bit indices (trace format)
  uint32_t position_bytes = 16;        // clip-space float4 per vertex (trace format)
  uint32_t vertices_per_clock = 1;     // vertex fetch rate (assumption)
  uint32_t latency_cycles = 16;        // fetch pipeline depth, once per segment (assumption)
};

// Fidelity auto: when each trace triangle sent reaches the parameter buffer (its last unit).
struct GeometryArrivals {
  std::vector<std::pair<uint32_t, uint64_t>> log;  // (item's first trace triangle, cycle)
  sc_core::sc_event arrived;
};

// Fidelity auto's geometry estimate: the segment's geometry cycles as estimated, as simulated
// (the rounds' spans), and the interval's half-width.
struct GeometryEstimate {
  RenderEstimate estimate;  // tiles = trace triangles, clusters of sampling.geometry_cluster
  uint64_t rounds = 0, simulated = 0, warmup = 0;
  uint64_t rounds_before_render = 0;  // the rest were asked for between the render's rounds
};

class GeometryFrontEnd : public UnitBase {
 public:
  sc_core::sc_fifo_out<Item> out;
  tlm_utils::simple_initiator_socket<UnitBase> mem;

  SC_HAS_PROCESS(GeometryFrontEnd);
  GeometryFrontEnd(const sc_core::sc_module_name& name, const UnitEnv& env, const GeometryFrontEndConfig& config,
                   uint32_t batch_triangles);

  // Runs the vertex cache over the frame (after setup: culled triangles are fetched too).
  void prepare();
  Cost cost(const Item& item) const;
  // Index and vertex bytes trace triangles [first, end) read.
  uint64_t read_bytes(uint32_t first, uint32_t end) const { return m_bytes_prefix[end] - m_bytes_prefix[first]; }
  void account(const Item& item, const Cost& c);
  // Vertices trace triangle `id` missed in the cache (new vertices the parameter buffer stores).
  uint32_t vertex_misses(uint32_t id) const { return m_misses[id]; }
  // The batches the unit issues, in order (what the analytic level also walks).
  std::vector<Item> batches() const;

  // Fidelity auto: sample the geometry of a one-segment frame (tile_sampler.h) instead of
  // sending every triangle; `aux` per trace triangle is the regression's auxiliary (its DRAM
  // bytes). A first round goes before the segment's last item (more rounds while its variance
  // is unknown); the tile scheduler, which shares the frame's budget between the geometry and
  // the render, asks for more rounds between the render's (grow()).
  void sample(const SamplingConfig& config, std::vector<double> aux);
  bool sampled() const { return m_sampling_on; }
  const GeometryEstimate& geometry_estimate() const { return m_estimate; }
  // The sample for allocate(): its curve, its cost per cluster in triangles sent (warm-up
  // included), its clusters taken and in all.
  SampledPart sampled_part() const;
  // One more round of `clusters` clusters; grown() fires when it is measured.
  void grow(uint64_t clusters);
  sc_core::sc_event& grown() { return m_grown; }
  GeometryArrivals& arrivals() { return m_arrivals; }

 private:
  void run();
  void run_sampled();
  void send(const Item& it);
  void sample_round(uint64_t clusters);
  bool m_sampling_on = false;
  SamplingConfig m_sampling;
  std::vector<double> m_aux;
  std::unique_ptr<TileSampler> m_sampler;
  GeometryEstimate m_estimate;
  uint64_t m_grow = 0;
  sc_core::sc_event m_grow_asked, m_grown;
  GeometryArrivals m_arrivals;
  GeometryFrontEndConfig m_cfg;
  uint32_t m_batch;
  std::vector<uint32_t> m_misses;
  std::vector<uint64_t> m_cycles, m_bytes_prefix;  // prefix sums over trace triangles
  Stat& m_triangles;
  Stat& m_vertex_misses;
};

}  // namespace tilevis::sim
