// The one way to drive each Verilated unit of the early-visibility library (tilevis_rtl_evu):
// the TileSequencer at the model's reject lanes and list capacities, Clip and Occlude at one
// lane. The testbenches (rtl_ref/tb: tb_tile_sequencer, tb_clip, tb_occlude) and fidelity
// rtl's RtlEvu (rtl_evu.cpp) both drive the RTL through these classes; the Verilated models
// stay behind them (no Verilator header here).
//
// Clocks are counted from the clock that starts the unit's operation to the clock that ends it,
// as each unit's header states (rtl_ref/units). An assertion of the RTL that fails (a width
// bound, a protocol rule) throws std::runtime_error naming the unit.
#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "geom/clip.h"
#include "geom/polygon.h"
#include "scoreboard.h"
#include "visibility/svgpu.h"

namespace tilevis::rtl {

// The parameters the library's RTL is Verilated with (rtl_ref/CMakeLists.txt): the model's
// defaults evu.reject lanes, evu.triangle_list_entries, evu.edge_list_entries.
inline constexpr uint32_t kSeqLanes = 8, kSeqTriCap = 512, kSeqEdgeCap = 256;
inline constexpr uint32_t kClipNW = 12;  // Clip's NW: the bits of a parent's edge count n
// PairReject and DepthTest: one pair per clock per lane, fixed latency (their testbenches
// check it on every vector), so their time is stated, not simulated.
inline constexpr uint32_t kPairRejectLatency = 3, kDepthTestLatency = 3;

// TileSequencer ×kSeqLanes (lists kSeqTriCap / kSeqEdgeCap): one tile's walk in passes
// (triangle chunks outer, edge chunks inner), each pass loaded through the write ports.
class TileSequencerDriver {
 public:
  struct Result {
    // (triangle, edge) in issue order: indices into the lists given to run().
    std::vector<std::pair<uint32_t, uint32_t>> issued;
    // Per triangle, summed over passes: the walk clocks from the pass's third on whose issue
    // row is the triangle's (stage A's row read ahead and dropped after a test-6 stop shows
    // as the triangle's row issuing nothing): rows = max(1, ceil(edges / L)) when it meets
    // every edge of the pass; min(floor(p / L) + 2, rows) when test 6 stops it after p pairs,
    // but floor(p / L) + 1 for the pass's last triangle (`done` comes with its stopping row).
    std::vector<uint64_t> tri_clocks;
    uint64_t passes = 0;
    uint64_t load_clocks = 0;  // list writes, one entry per list per clock: max(triangles, edges) per pass
    uint64_t walk_clocks = 0;  // from each pass's start to its done: the triangles' clocks + 2 per pass
    uint64_t stopped = 0;      // triangles stopped by test 6 (once each, in the first pass that stops them)
  };
  TileSequencerDriver();
  ~TileSequencerDriver();
  TileSequencerDriver(const TileSequencerDriver&) = delete;
  TileSequencerDriver& operator=(const TileSequencerDriver&) = delete;
  // tri_zmax: the triangles' z_max in list order (at least one); edge_zmin: the edges' z_min,
  // ascending (the sequencer's edge list is sorted).
  Result run(const std::vector<uint32_t>& tri_zmax, const std::vector<uint32_t>& edge_zmin);

 private:
  struct Impl;
  std::unique_ptr<Impl> m;
};

// Clip ×1: one split of a convex polygon by a silhouette edge's line. The lane holds no copy of
// the parent: its edges are streamed twice, to classify and (when the line crosses) to emit.
class ClipDriver {
 public:
  struct Split {
    int status = 0;                       // 0 the line crosses (both children emitted), 1 inside, 2 outside
    geom::ConvexPolygon inside, outside;  // the emitted children (status 0 only)
    uint32_t clocks = 0;                  // start to done: 2n + 2 when the line crosses, n + 2 otherwise
  };
  ClipDriver();
  ~ClipDriver();
  ClipDriver(const ClipDriver&) = delete;
  ClipDriver& operator=(const ClipDriver&) = delete;
  // Throws std::invalid_argument for a parent of fewer than 3 edges or too many for n's
  // kClipNW bits (2^kClipNW - 1 = 4,095 edges: 7 for the triangle in its tile and one a split).
  Split split(const geom::ConvexPolygon& poly, const vis::svgpu::Edge& e);

 private:
  struct Impl;
  std::unique_ptr<Impl> m;
};

// The status geom::split's result has (what Clip must report), and whether the RTL's split is
// geom::split's bit for bit: status, and for a crossing both children's lines and vertex
// representations in canonical order.
int split_status(const geom::SplitResult& want);
bool split_matches(const ClipDriver::Split& got, const geom::SplitResult& want);

// Occlude ×1: a piece's interior point, then the exact test against occluders in order.
class OccludeDriver {
 public:
  struct Occluder {
    const vis::svgpu::Triangle* u = nullptr;
    uint32_t id = 0;
  };
  struct Result {
    uint32_t tests = 0;         // occluders streamed: up to and including the first that occludes
    bool occluded = false;      // the RTL's verdict for the piece
    bool q_matches = true;      // the RTL's interior point is geom::interior_point's, bit for bit
    uint32_t verdict_mismatches = 0;  // verdicts that differ from svgpu::occludes
    uint32_t clocks = 0;        // 2 for the interior point, then with tests > 0: one a test + 1 for the last verdict
  };
  OccludeDriver();
  ~OccludeDriver();
  OccludeDriver(const OccludeDriver&) = delete;
  OccludeDriver& operator=(const OccludeDriver&) = delete;
  // Streams `occ` one a clock until the first occluder that svgpu::occludes says hides the
  // piece (the analytic resolver's scan; the stream's control is the scoreboard's verdict,
  // which the RTL's must equal), then waits for the outstanding verdicts.
  Result run(const geom::ConvexPolygon& piece, const vis::svgpu::Triangle& t, uint32_t t_id,
             const std::vector<Occluder>& occ);

 private:
  struct Impl;
  std::unique_ptr<Impl> m;
};

// The tile's opaque triangles as indices into r.triangles, nearest z_min first (stable), as
// TileFrame::occluders orders them.
std::vector<uint32_t> occluder_order(const ReplayedJob& r);
// The occluders the analytic resolver tests exactly for a piece of `rt` with interior point q
// (analytic_resolver.cpp, occluded(): its screens, in `order`); the exact tests go to the RTL.
void screened_occluders(const ReplayedJob& r, const std::vector<uint32_t>& order, const ReplayedTriangle& rt,
                        const geom::RationalPoint& q, std::vector<OccludeDriver::Occluder>& out);

// A testbench's main: runs `bench`, and reports an exception (the RTL stopped: an assertion, a
// pass that never ends) with exit status 1.
int run_bench(int (*bench)(int, char**), int argc, char** argv);

}  // namespace tilevis::rtl
