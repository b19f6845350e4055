// What flows between the units of the tiler model. Transactions carry no geometry: they
// name a range of work (trace triangles of a segment, or triangles of a tile's list) whose
// functional results live in the FrameWork (frame_work.h), the model's functional back door.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "visibility/tile_counters.h"

namespace tilevis::sim {

// DESIGN.md "Visibility modes": what sits between tile fetch and the fragment unit.
enum class Mode : uint8_t {
  analytic,  // the early-visibility unit (SVGPU silhouette clipping + Roberts occlusion)
  hybrid,    // the EVU, and per-pixel HSR in tiles where the analytic answer can be wrong
  hsr,       // a per-pixel hidden-surface-removal unit (PowerVR ISP-like)
  early_z,   // no visibility unit; early depth test in the fragment path, submission order
  none       // no visibility unit, no early depth test (immediate mode)
};
// DESIGN.md "Fidelity levels".
enum class Fidelity : uint8_t {
  analytic,   // closed-form cycles per tile from counts, no events
  tile,       // one transaction per tile per unit (geometry units: per batch)
  primitive,  // one transaction per primitive, FIFO back-pressure, memory contention
  rtl,        // primitive, with the EVU's clocks from its Verilated RTL (rtl_ref): the reference level
  automatic   // "auto": primitive on a sample of each segment's tiles, the rest estimated (tile_sampler.h)
};

const char* to_string(Mode m);
// Modes with the early-visibility unit (and silhouettes, edge lists, SVGPU counters).
inline bool uses_evu(Mode m) { return m == Mode::analytic || m == Mode::hybrid; }
inline bool uses_hsr(Mode m) { return m == Mode::hsr || m == Mode::hybrid; }
const char* to_string(Fidelity f);

// One binned triangle of a tile: its functional counts, from which every unit's cost follows.
// Its share of the tile's counters is the tile resolver's (vis::TileCounters: SVGPU counters
// in analytic tiles, zero in per-pixel ones; fragments_generated: samples it covers in the
// tile; samples_covered: samples of its visible pieces, or samples it owns after the tile).
struct TriangleWork : vis::TileCounters {
  uint32_t id = 0;     // original (trace) triangle id
  uint32_t draw = 0;
  vis::EvuShape shape;               // what sets its EVU clocks beyond the counters (analytic tiles)
  // Fidelity rtl: the clocks the Verilated EVU spent on it (rtl_evu.h), summed per unit.
  bool rtl = false;
  uint64_t rtl_reject = 0, rtl_clip = 0, rtl_occlude = 0;
  uint32_t depth_tests = 0;          // per-sample depth tests spent on it (HSR, early-Z, partial-render merge)
  uint32_t fragments_shaded = 0;
};

// Units whose per-tile cycles go into tiles.csv, in column order.
enum class TileUnit : uint8_t { fetch, reject, clip, occlude, hsr, fragment, writer, count };
const char* column_name(TileUnit u);

// One tile of one segment (a segment is what the parameter buffer holds between flushes).
struct TileWork {
  uint32_t segment = 0, tile = 0;
  uint32_t tx = 0, ty = 0;
  uint32_t pixels = 0;                // pixels of the tile inside the viewport
  uint32_t edges = 0;                 // silhouette edges binned (analytic mode)
  uint32_t opaque = 0;                // opaque triangles (occluders)
  uint32_t passes = 1;                // EVU passes: list longer than the on-chip capacity
  bool reload = false;                // depth/colour stored by an earlier partial render are read back
  bool store = false;                 // partial render: depth and colour written for a later segment
  std::vector<uint32_t> draws;        // per binned triangle, its draw (what tile fetch needs before visibility)
  std::vector<uint32_t> ids;          // per binned triangle, its trace triangle (where its record lies)
  std::vector<TriangleWork> tris;     // per binned triangle, after resolve (list order)
  bool resolved = false;
  uint8_t per_pixel = 0;              // hybrid: 0 analytic, else why the tile went to the HSR unit
                                      // (1 interpenetration, 2 non-opaque content, 3 work budget)
  uint64_t detection_screens = 0;     // hybrid: triangle pairs the EVU screened to decide that
  uint64_t detection_tests = 0;       // hybrid: pairs past the screen whose planes it compared
  uint64_t rtl_reject_tile = 0;       // fidelity rtl: the TileSequencer's clocks not spent on one triangle
                                      // (list loads, start and end of each pass, pipeline drain)
  uint64_t cycles[size_t(TileUnit::count)] = {};
  uint64_t start_cycle = 0, end_cycle = 0;  // first fetch to last write (event-driven levels)
  // The fragment unit's texture footprint, per binned triangle after resolve: the fragments
  // shaded and texture bytes asked by the triangles of its draw before it in the list (filled
  // on the unit's first item of the tile).
  std::vector<std::pair<uint64_t, double>> texture_before;

  uint32_t triangles() const { return uint32_t(draws.size()); }
};

// A transaction between units: a range of work.
//   geometry: trace triangles [first, first + count) of `segment`; `last` marks the
//             segment's final batch (the parameter buffer then has the whole segment).
//   render:   triangles [first, first + count) of `tile`'s list; `first_of_tile`/`last`
//             mark the tile's first and final item; a segment_end item follows a segment's tiles.
struct Item {
  enum class Kind : uint8_t { work, segment_end };
  Kind kind = Kind::work;
  uint32_t segment = 0;
  uint32_t first = 0, count = 0;
  bool first_of_tile = false, last = false;
  TileWork* tile = nullptr;
};

inline std::ostream& operator<<(std::ostream& os, const Item& i) {
  return os << "item(segment " << i.segment << ", " << i.first << "+" << i.count << ")";
}

}  // namespace tilevis::sim
