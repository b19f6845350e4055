// Early-visibility unit (EVU): the SVGPU algorithm per tile as three pipelined sub-units,
//   Reject  — tests 1–6 of every triangle × silhouette-edge pair (SVGPU §3.2.1),
//   Clip    — splits pieces by surviving edges, both sides kept, children re-checked (§3.2.2),
//   Occlude — a piece's interior point against the tile's opaque triangles (§3.3).
// The functional work is model/visibility's analytic resolver, whose per-triangle counters and
// work shape (vis::EvuShape) set the cost. The cost functions have the shape of the RTL in
// rtl_ref/units and their defaults are its measured clocks (reports/rtl/README.md):
//   Reject  — TileSequencer: per pass, the lists loaded through one write port each
//             (max(triangles, edges) clocks) and a start and an end clock; per triangle, its
//             rows of `lanes` edges, one row per `ii` clocks, at least one row, and the row read
//             ahead and dropped when test 6 stops it before its last row (unless it is the
//             pass's last triangle); PairReject and
//             DepthTest behind it drain once per tile (latency).
//   Clip    — per split of a parent of n edges: `split_cycles` to start and finish, n clocks to
//             classify its vertices, n more to emit both children when the line crosses it;
//             re-checking a piece against a candidate edge, `check_cycles`.
//   Occlude — per piece: `piece_cycles` for its interior point, `ii` per occluder test and
//             `drain_cycles` for the last verdicts when it had any test.
// Clip and Occlude lanes are independent copies of the one-lane RTL: a triangle's clocks are
// spread over them (ceil(clocks / lanes)). At fidelity rtl the clocks come from the Verilated
// RTL itself (rtl_evu.h) and are spread over the lanes the same way.
#pragma once

#include <memory>

#include "units/common/stage.h"

namespace tilevis::sim {

// One sub-unit: `lanes` copies; `ii` clocks per row (reject), per occluder test (occlude) or per
// parent edge (clip); `latency_cycles` drain once per tile.
struct EvuStageConfig {
  uint32_t lanes = 1;
  uint32_t ii = 1;
  uint32_t latency_cycles = 1;
};

struct EarlyVisibilityConfig {
  // Lane counts are design choices; clocks are the RTL's (rtl_ref, reports/rtl/README.md).
  EvuStageConfig reject{8, 1, 6};   // TileSequencer x8, then PairReject (latency 3) and DepthTest (latency 3)
  EvuStageConfig clip{2, 1, 0};     // Clip: one vertex a clock
  EvuStageConfig occlude{4, 1, 0};  // Occlude: one occluder a clock
  uint32_t reject_pass_cycles = 2;  // TileSequencer: start and end clocks of a pass
  uint32_t reject_readahead_rows = 1;  // the row read ahead and dropped when test 6 stops a triangle
  uint32_t list_load_per_cycle = 1;    // list entries written per clock per list (one write port)
  uint32_t clip_split_cycles = 2;      // Clip: start and done clocks of a split
  uint32_t clip_emit_per_edge = 1;     // Clip: clocks per parent edge to emit both children of a crossing split
  uint32_t clip_check_cycles = 1;      // tests 1-3 re-run on a piece while clipping (assumption: not in the RTL)
  uint32_t occlude_piece_cycles = 2;   // Occlude: the interior point of a piece
  uint32_t occlude_drain_cycles = 1;   // Occlude: the last verdict, the clock after its occluder's
  // Hybrid's detector: a triangle pair's overlap clipped and its depth compared at the
  // vertices, the clip datapath's kind of work (2 lanes, one every 4 clocks; its latency is
  // hidden under the reject stage's, whose first item of a tile waits for it). Assumption.
  EvuStageConfig detect{2, 4, 0};
  uint32_t detection_bin = 8;         // hybrid: pixels a side of the detector's bins (0: the tile)
  uint32_t detect_beside = 1;         // hybrid: 1 the detector works beside reject (own datapath), 0 before it
  uint32_t hybrid_pair_budget = 0;    // hybrid: a tile with more triangles x edges goes per pixel (0: none)
  uint32_t triangle_list_entries = 512;  // on-chip triangle list (assumption: 512 x ~64 B = 32 KiB)
  uint32_t edge_list_entries = 256;      // on-chip edge list (assumption: 256 x 24 B = 6 KiB)
};

// The cost functions, plain functions of the work so that tests, the RTL comparison and the
// closed form use the same ones. `rtl` selects the Verilated clocks where the tile has them.
// Rows the TileSequencer issues for a triangle with `pairs` pairs of a list of `edges` edges.
// `last`: the list's last triangle, after which nothing is read ahead.
uint64_t reject_rows(uint64_t pairs, bool test6_stop, uint64_t edges, bool last, const EarlyVisibilityConfig& c);
// Clocks of a tile's triangle in each sub-unit (before the lanes of clip and occlude).
uint64_t reject_clocks(const TriangleWork& t, uint64_t edges, bool last, const EarlyVisibilityConfig& c);
uint64_t clip_clocks(const TriangleWork& t, const EarlyVisibilityConfig& c);
uint64_t occlude_clocks(const TriangleWork& t, const EarlyVisibilityConfig& c);
// The reject stage's clocks per tile not spent on a triangle: list loads, pass start and end,
// pipeline drain.
uint64_t reject_tile_clocks(const TileWork& w, const EarlyVisibilityConfig& c);

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
