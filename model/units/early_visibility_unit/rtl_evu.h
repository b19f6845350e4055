// The early-visibility unit's RTL (rtl_ref/units, Verilated) as the cycle reference of
// fidelity `rtl`: a tile job (model/visibility/evu_jobs.h) runs through the Verilated
// TileSequencer (with PairReject's and DepthTest's pipeline behind it), Clip and Occlude, and
// the clocks each unit spent are returned per triangle and per operation. The model schedules
// those operations on its lanes exactly as its calibrated cost functions do, so the difference
// between fidelity `primitive` and `rtl` is the difference between the cost functions and the
// RTL, nothing else.
//
// Built from rtl_ref/ where Verilator is installed; elsewhere (sanitizer and fuzz builds, no
// Verilator) make_rtl_evu() throws, saying why.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "visibility/evu_jobs.h"

namespace tilevis::sim {

struct RtlTriangleClocks {
  uint32_t id = 0;                  // original triangle id (EvuJobTriangle::id)
  uint64_t reject = 0;              // TileSequencer clocks spent issuing the triangle's pair rows
                                    // (the row read ahead and dropped on a test-6 stop included)
  std::vector<uint32_t> splits;     // Clip clocks of each split of the triangle's pieces, in order
  std::vector<uint32_t> pieces;     // Occlude clocks of each piece: interior point, tests, drain
};

struct RtlTileClocks {
  std::vector<RtlTriangleClocks> tris;  // job order: the tile's front-facing triangles, setup order
  uint64_t reject_latency = 0;          // per tile: TileSequencer + PairReject/DepthTest pipeline drain
  uint64_t passes = 1;                  // TileSequencer passes (lists over capacity)
  uint64_t list_load = 0;               // list writes before each pass, max(triangles, edges) clocks a pass
                                        // (tile fetch's time in the model; not in reject or reject_latency)
};

class RtlEvu {
 public:
  virtual ~RtlEvu() = default;
  // Runs one tile job through the Verilated units. Throws std::runtime_error if the RTL's
  // outcome differs from the job's golden counters (a scoreboard mismatch is a bug, never a
  // timing to report).
  virtual RtlTileClocks run(const vis::EvuJob& job) = 0;
};

// The Verilated EVU at the model's configuration. Throws std::runtime_error when this build has
// no Verilated EVU, or when a parameter differs from what the RTL was built with (reject lanes,
// list capacities).
std::unique_ptr<RtlEvu> make_rtl_evu(uint32_t reject_lanes, uint32_t triangle_list_entries, uint32_t edge_list_entries);

// Whether this build holds the Verilated EVU (fidelity rtl available).
bool rtl_evu_available();

}  // namespace tilevis::sim
