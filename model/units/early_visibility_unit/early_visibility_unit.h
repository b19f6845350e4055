// Early-visibility unit (EVU): the SVGPU algorithm per tile as three pipelined sub-units,
//   Reject  — tests 1–6 of every triangle × silhouette-edge pair (SVGPU §3.2.1),
//   Clip    — splits pieces by surviving edges, both sides kept, children re-checked (§3.2.2),
//   Occlude — a piece's interior point against the tile's opaque triangles (§3.3).
// Each has lanes, an initiation interval and a latency; the functional work is
// model/visibility's GoldenTiler::process_tile(), whose per-triangle counters set the cost.
// A tile whose lists exceed the on-chip capacities is processed in passes (tile fetch
// re-streams the edges and occluders; each extra pass costs a pipeline refill here).
#pragma once

#include <memory>

#include "units/common/stage.h"

namespace tilevis::sim {

// One sub-unit: `lanes` operations issue together every `ii` cycles; a triangle's
// operations take ceil(ops / lanes) issue slots (a triangle with none passes in one
// cycle); the latency drains once per tile.
struct EvuStageConfig {
  uint32_t lanes = 1;
  uint32_t ii = 1;              // initiation interval, cycles between issues of one lane
  uint32_t latency_cycles = 1;  // pipeline depth
};

struct EarlyVisibilityConfig {
  // All EVU figures are assumptions: no such unit exists in silicon. Reject is simple
  // integer compares on bounding boxes and edge functions (8 lanes, 1 per clock, 6 deep);
  // Clip splits polygons with ~100-bit implicit-point arithmetic (2 lanes, a split every
  // 4 clocks, 12 deep); Occlude evaluates three edge functions and a depth compare at a
  // rational point (4 lanes, 1 per clock, 10 deep).
  EvuStageConfig reject{8, 1, 6};
  EvuStageConfig clip{2, 4, 12};
  EvuStageConfig occlude{4, 1, 10};
  // Hybrid's detector: a triangle pair's overlap clipped and its depth compared at the
  // vertices, the clip datapath's kind of work (2 lanes, one every 4 clocks; its latency is
  // hidden under the reject stage's, whose first item of a tile waits for it).
  EvuStageConfig detect{2, 4, 0};
  uint32_t detection_bin = 8;         // hybrid: pixels a side of the detector's bins (0: the tile)
  uint32_t detect_beside = 1;         // hybrid: 1 the detector works beside reject (own datapath), 0 before it
  uint32_t hybrid_pair_budget = 0;    // hybrid: a tile with more triangles x edges goes per pixel (0: none)
  uint32_t triangle_list_entries = 512;  // on-chip triangle list (assumption: 512 x ~64 B = 32 KiB)
  uint32_t edge_list_entries = 256;      // on-chip edge list (assumption: 256 x 24 B = 6 KiB)
  uint32_t pass_overhead_cycles = 32;    // refill of the three pipelines per extra pass (assumption)
};

class EvuReject : public Stage {
 public:
  EvuReject(const sc_core::sc_module_name& name, const UnitEnv& env, const EarlyVisibilityConfig& config);
  Cost cost(const Item& item) const override;

 private:
  const EarlyVisibilityConfig& m_cfg;
};

class EvuClip : public Stage {
 public:
  EvuClip(const sc_core::sc_module_name& name, const UnitEnv& env, const EarlyVisibilityConfig& config);
  Cost cost(const Item& item) const override;

 private:
  const EarlyVisibilityConfig& m_cfg;
};

class EvuOcclude : public Stage {
 public:
  EvuOcclude(const sc_core::sc_module_name& name, const UnitEnv& env, const EarlyVisibilityConfig& config);
  Cost cost(const Item& item) const override;

 private:
  const EarlyVisibilityConfig& m_cfg;
};

class EarlyVisibilityUnit : public UnitBase {
 public:
  sc_core::sc_fifo_in<Item> in;
  sc_core::sc_fifo_out<Item> out;

  EarlyVisibilityUnit(const sc_core::sc_module_name& name, const UnitEnv& env, const EarlyVisibilityConfig& config,
                      int fifo_depth);
  EvuReject& reject() { return *m_reject; }
  EvuClip& clip() { return *m_clip; }
  EvuOcclude& occlude() { return *m_occlude; }
  // Work counters of a resolved tile into the unit's group (both levels call it once per tile).
  void count_tile(const TileWork& w);
  // The analytic level: a tile keeps the EVU busy for its slowest sub-unit (the three
  // pipeline over the tile's triangles); the event-driven levels measure the union.
  void account_analytic(uint64_t cycles) { m_busy.value += double(cycles); }

 private:
  EarlyVisibilityConfig m_cfg;
  std::unique_ptr<EvuReject> m_reject;
  std::unique_ptr<EvuClip> m_clip;
  std::unique_ptr<EvuOcclude> m_occlude;
  std::unique_ptr<OccupancyFifo<Item>> m_reject_to_clip, m_clip_to_occlude;
  Stat& m_pairs;
  Stat& m_candidates;
  Stat& m_clips;
  Stat& m_pieces;
  Stat& m_visible;
  Stat& m_occlusion_tests;
  Stat& m_detection_screens;
  Stat& m_detection_tests;
  Stat& m_tiles;
  Stat& m_multi_pass;

 public:
  OccupancyFifo<Item>& reject_to_clip() { return *m_reject_to_clip; }
  OccupancyFifo<Item>& clip_to_occlude() { return *m_clip_to_occlude; }
};

}  // namespace tilevis::sim
