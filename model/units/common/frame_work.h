// The functional side of the tiler model: one frame's setup, binning, parameter-buffer
// segments and per-tile visibility results, computed by calling model/visibility and
// model/geom. Units own the steps (PrimitiveSetup calls run_setup(), TilingEngine
// run_binning() and prepare_segment(), the visibility stage resolve_tile(), ...) and add
// time; the results are the golden pipeline's, bit for bit, whatever the fidelity level.
//
// Partial renders (a parameter buffer too small for the frame) split the frame into
// segments of consecutive trace triangles. In analytic mode each segment is resolved by
// the golden pipeline on its own triangles (its own silhouettes: edges whose neighbour is
// in another segment become boundaries) and merged per sample into the depth stored by the
// earlier partial renders, as a TBDR does after a flush: ties keep the earlier (lower id)
// triangle, golden's rule. The per-pixel modes keep the stored depth across segments too.
//
// Setup, binning and each segment's tile lists are computed into a FunctionalRecord
// (functional_record.h), and the units' questions are answered from it; a run that records
// keeps each tile's visibility there too, and a run that replays loads one and computes none
// of it: every tile's results, samples and visible areas come from the record.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include <nlohmann/json.hpp>

#include "geom/depth.h"
#include "geom/predicates.h"
#include "geom/tile_grid.h"
#include "tilevis/outputs.h"
#include "tilevis/trace.h"
#include "units/common/functional_record.h"
#include "units/common/work.h"
#include "visibility/golden.h"
#include "visibility/setup.h"
#include "visibility/zbuffer.h"

namespace tilevis::sim {

class RtlEvu;

struct FrameWorkConfig {
  Mode mode = Mode::analytic;
  uint32_t tile_w = 32, tile_h = 32;
  uint32_t depth_bits = 24;
  // EVU on-chip list capacities: a tile with more triangles or edges takes several passes.
  uint32_t evu_triangle_entries = 512, evu_edge_entries = 256;
  // Hybrid: a tile whose triangles x edges exceed this goes per pixel (0: no budget).
  uint64_t hybrid_pair_budget = 0;
  uint32_t detection_bin = 8;  // hybrid: the detector's bins, pixels (0: the tile)
  // Fidelity auto: only a sample of the tiles is rendered; tiles.csv marks them ("simulated").
  bool sampled = false;
  // Fidelity rtl: the Verilated EVU whose clocks analytic tiles take (not owned; null: none).
  RtlEvu* rtl = nullptr;
  // Called after each tile's visibility with (tiles resolved, tiles binned so far).
  std::function<void(uint64_t, uint64_t)> progress;
  // Keep every tile's visibility in record() (sim.functional_record: a run that records).
  bool record = false;
  // The record's key (functional_key(frame, *this)): needed to record or replay (not owned).
  const FunctionalKey* key = nullptr;
};

class FrameWork {
 public:
  static constexpr uint32_t kNone = 0xffffffffu;

  // `frame` must outlive the FrameWork (it is read, not copied: a trace can be large).
  // With `replay`, a record of this frame and functional configuration (else it throws,
  // naming what differs), setup, binning and visibility are not computed: every answer is
  // the record's (functional_record.h). Fidelity rtl cannot replay (config.rtl: throws).
  FrameWork(const trace::Frame& frame, const FrameWorkConfig& config,
            std::unique_ptr<FunctionalRecord> replay = nullptr);
  FrameWork(trace::Frame&&, const FrameWorkConfig&) = delete;
  ~FrameWork();
  FrameWork(const FrameWork&) = delete;
  FrameWork& operator=(const FrameWork&) = delete;

  const trace::Frame& frame() const { return m_frame; }
  const FrameWorkConfig& config() const { return m_cfg; }
  Mode mode() const { return m_cfg.mode; }
  uint32_t trace_triangles() const { return m_trace_triangles; }
  uint32_t samples() const { return uint32_t(m_frame.samples.size()); }
  // What this run computed (config.record: every resolved tile too); what it replays.
  const FunctionalRecord& record() const { return m_rec; }

  // --- PrimitiveSetup: clipping, snapping, facing and silhouettes of the whole frame.
  void run_setup();
  const vis::Setup& setup() const { return m_setup; }
  // First setup triangle of trace triangle `id` (id == trace_triangles(): the end).
  uint32_t setup_begin(uint32_t id) const { return m_setup_begin[id]; }
  uint32_t draw_of(uint32_t id) const { return m_setup.triangle_draw[id]; }

  // --- TilingEngine: exact binning of the whole frame.
  void run_binning();
  uint32_t tiles_x() const { return m_grid.tiles_x(); }
  uint32_t tiles_y() const { return m_grid.tiles_y(); }
  uint32_t tile_count() const { return m_grid.tile_count(); }
  const geom::TileGrid& grid() const { return m_grid; }
  uint32_t tile_refs(uint32_t setup_triangle) const { return m_tri_refs[setup_triangle]; }
  uint32_t tile_tests(uint32_t setup_triangle) const { return m_tri_tests[setup_triangle]; }
  uint32_t edge_refs(uint32_t edge) const { return m_edge_refs[edge]; }
  uint32_t edge_tests(uint32_t edge) const { return m_edge_tests[edge]; }
  // Silhouette edges carried into the parameter buffer with trace triangle `id` (the
  // first front-facing triangle of the edge's draw that has it as an edge).
  std::pair<const uint32_t*, const uint32_t*> owned_edges(uint32_t id) const {
    return {m_owned.data() + m_owned_begin[id], m_owned.data() + m_owned_begin[id + 1]};
  }

  // --- ParameterBuffer: the flush plan. first_ids[0] == 0, ascending.
  void set_segments(std::vector<uint32_t> first_ids);
  uint32_t segment_count() const { return uint32_t(m_seg_first.size()); }
  uint32_t segment_first(uint32_t k) const { return m_seg_first[k]; }
  uint32_t segment_end(uint32_t k) const {
    return k + 1 < m_seg_first.size() ? m_seg_first[k + 1] : m_trace_triangles;
  }

  // --- Render of one segment (one at a time, in order).
  void prepare_segment(uint32_t k);                          // binning of the segment
  const std::vector<uint32_t>& segment_tiles() const { return m_seg_tiles; }  // non-empty, row-major
  uint32_t tile_triangle_count(uint32_t tile) const;        // binned in the open segment (before open_tile)
  uint32_t tile_edge_count(uint32_t tile) const;            // silhouette edges binned likewise (0: per-pixel modes)
  uint64_t tile_pair_tests(uint32_t tile) const;            // pairs test 6 lets through, likewise (vis::TileFrame::pair_tests)
  TileWork* open_tile(uint32_t tile);                        // TileFetch
  // Tiles of the open segment about to be opened, in about that order: their visibility is
  // resolved meanwhile on the host's other threads (the EVU modes; the same results).
  void resolve_ahead(const std::vector<uint32_t>& tiles);
  void resolve_tile(TileWork& w);                            // the mode's visibility step
  void close_tile(TileWork* w);                              // TileWriter: results kept, work freed
  bool tile_closed(uint32_t tile) const;                     // in the open segment
  uint64_t tile_end_cycle(uint32_t tile) const { return m_tile_end[tile]; }  // its last close
  void finish_segment();

  // What stopped the simulation early (fidelity rtl: the RTL failed a tile), empty if nothing.
  const std::string& failure() const { return m_failure; }

  // Host seconds of the calling thread spent in this functional model (setup, binning, every
  // tile's list, visibility and results; with the other threads' work it waits for) and, at
  // fidelity rtl, in the Verilated EVU (not in the former). The rest of a run's host time is the
  // timing model's: SystemC, the units' cost functions, the memory system.
  double host_functional_seconds() const { return m_functional_s - m_rtl_s; }
  double host_rtl_seconds() const { return m_rtl_s; }

  // --- Results, after finish().
  void finish();
  const std::vector<int32_t>& ids() const { return m_ids; }
  const std::vector<double>& visible_area() const { return m_visible_area; }  // empty after partial renders
  outputs::TileTable tile_table() const;
  nlohmann::json totals() const;        // canonical totals (DESIGN.md "Canonical outputs")
  nlohmann::json triangle_accounts() const;  // every trace triangle, step by step
  uint64_t fragments_shaded() const { return m_shaded; }

 private:
  struct Segment;
  // A front-facing setup triangle's coverage and depth plane (the frame's binning has them).
  const vis::FrontTriangle& raster(uint32_t setup_triangle) const;
  // Does the triangle's draw shade once per sample (trace::kSampleRateShading)?
  bool sample_rate(const TriangleWork& t) const { return m_frame.draws[t.draw].sample_rate(); }
  void bin_segment(Segment& sg);
  // The open segment's list of a tile (frame setup triangles), empty if it has none.
  std::pair<const uint32_t*, const uint32_t*> tile_list(uint32_t tile) const;
  // The frame-sized per-sample buffer tiles' visibility writes: golden's ids (analytic modes,
  // one segment) or the stored depth's owners (m_owner).
  int32_t* sample_buffer();
  void record_tile(const TileWork& w);
  void replay_tile(TileWork& w);
  uint32_t covering_fan(uint32_t id, geom::Point p);
  void resolve_analytic(TileWork& w);
  void take_rtl_clocks(TileWork& w);
  void take_rtl_clocks_or_throw(TileWork& w);
  std::string m_failure;
  void resolve_pixels(TileWork& w);
  class HostTime;  // adds the wall time of the outermost timed call to a total
  double m_functional_s = 0, m_rtl_s = 0;
  int m_functional_depth = 0, m_rtl_depth = 0;

  const trace::Frame& m_frame;
  FrameWorkConfig m_cfg;
  uint32_t m_trace_triangles = 0;
  // Setup, binning and segments live in the record (computed into it, or loaded); the
  // names below are its fields.
  FunctionalRecord m_rec;
  bool m_replay = false;
  vis::Setup& m_setup = m_rec.setup;
  std::vector<uint32_t>& m_setup_begin = m_rec.setup_begin;

  vis::GoldenConfig m_gcfg;
  vis::GoldenResult m_full;  // the whole frame's golden result (one segment: the output)
  std::unique_ptr<vis::GoldenTiler> m_full_tiler;
  geom::TileGrid m_grid;
  std::vector<uint32_t> m_front_of;      // per setup triangle: index into the frame's front triangles, kNone
  std::vector<uint32_t>& m_tri_refs = m_rec.tri_refs;
  std::vector<uint32_t>& m_tri_tests = m_rec.tri_tests;
  std::vector<uint32_t>& m_edge_refs = m_rec.edge_refs;
  std::vector<uint32_t>& m_edge_tests = m_rec.edge_tests;
  std::vector<uint32_t>& m_owned_begin = m_rec.owned_begin;
  std::vector<uint32_t>& m_owned = m_rec.owned;

  std::vector<uint32_t> m_seg_first;
  std::unique_ptr<Segment> m_seg;
  std::vector<uint32_t> m_seg_tiles;
  std::vector<uint32_t> m_seg_pos;       // per tile: its place in the open segment's tiles, kNone
  RecordedTile m_replayed_tile;          // replay: the tile being replayed, decoded from the record
  std::vector<uint32_t> m_seg_result;    // replay, per tile: its place in the open segment's results, kNone
  // Replay, per tile: the last earlier segment that resolved it, in the record and in this run.
  std::vector<uint32_t> m_recorded_last, m_replayed_last;
  vis::TileOutput m_tile_added;          // recording: what the last analytic tile added to m_full
  std::vector<bool> m_stored;            // per tile: a partial render stored its depth/colour
  std::vector<uint32_t> m_owner;         // per sample: setup triangle in front (stored depth), kNone
  std::vector<vis::TileTriangleWork> m_per_tri;

  // Accumulated results.
  std::vector<std::vector<int64_t>> m_rows;  // per tile: functional counters then cycles
  std::vector<std::string> m_columns;
  size_t m_cycles_col = 0;
  std::vector<int32_t> m_ids;
  std::vector<double> m_visible_area;
  std::vector<uint64_t> m_tile_end;
  std::vector<uint32_t> m_closed_in;  // per tile: 1 + the segment it was last closed in (0: never)
  size_t m_simulated_col = 0;
  uint64_t m_shaded = 0, m_depth_tests = 0, m_tiles_rendered = 0, m_passes_extra = 0, m_per_pixel_tiles = 0,
           m_detection_screens = 0, m_detection_tests = 0;
  uint64_t m_tiles_resolved = 0, m_tiles_binned = 0;  // progress
  std::vector<uint64_t> m_seg_front;     // front-facing triangles per segment
  uint64_t m_visible_triangles = 0;
  bool m_finished = false;
};

}  // namespace tilevis::sim
