// The state the stages share: the frame in device memory and every intermediate buffer.
// One file per stage (setup.cu, silhouettes.cu, binning.cu, cull.cu, clip.cu, occlusion.cu,
// raster.cu) fills its part; pipeline.cu runs them, times them and grows buffers on overflow.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "exec.cuh"
#include "poly.cuh"
#include "tilevis/cuda_ref.h"

namespace tilevis::cuda {

inline constexpr uint32_t kNone = 0xffffffffu;
inline constexpr uint32_t kCullLanes = 8;  // culling threads per (tile, triangle) item (cull.cu)

// The tile grid. A tile's rectangle ends at the viewport's right and bottom edges: the last
// column and row of tiles may reach past the screen, and nothing there is visible.
struct TileGrid {
  uint32_t tile_w, tile_h, tiles_x, tiles_y, sb, width, height;
  TV_HD Rect rect(uint32_t tx, uint32_t ty) const {
    const uint32_t x1 = (tx + 1) * tile_w < width ? (tx + 1) * tile_w : width;
    const uint32_t y1 = (ty + 1) * tile_h < height ? (ty + 1) * tile_h : height;
    return {int32_t(tx * tile_w) << sb, int32_t(ty * tile_h) << sb, int32_t(x1) << sb, int32_t(y1) << sb};
  }
  TV_HD Rect rect(uint32_t tile) const { return rect(tile % tiles_x, tile / tiles_x); }
};

// Device-side counters, read back once per run (one small copy).
enum Counter : uint32_t {
  kFrustumCulled,
  kEdgeOn,          // trace triangles whose plane holds the eye (projected to a line): culled
  kClippedTris,
  kDegenerate,
  kBackFacing,
  kFrontFacing,
  kDeepPairs,       // pairs that passed the cheap tests (test 6, bounding boxes, test 4)
  kCandidates,      // pairs that survived tests 1-3
  kClipItems,       // (tile, triangle) items with candidates
  kSlotsUsed,       // piece slots reserved by clipping items
  kEdgesUsed,       // polygon edges allocated by clipping
  kClipOverflow,    // clipping items that ran out of pool room (slots or edges)
  kReserveOverflow, // clipping items with more pieces than their reservation
  kFloatAnomalies,  // float: polygons that outgrew their bound
  kVisibleTriangles,
  kMaxTilePieces,
  kHeavyPieces,     // occlusion of unclipped pieces with finer bins: pieces queued for a warp each
  kFloatRegularized,  // float: splits whose vertex sides were made those of a convex polygon
  kFloatNegativeAreas,  // float: visible pieces whose area came out negative (none: poly.cuh)
  kFloatExactAreas,     // float: visible pieces whose area sign was not proven: the exact region's area
  kBigTris, kBigEdges,  // binning: primitives of wide spans queued for a block each
  kLongFolds,           // visible-area fold: runs of items queued for a warp each
  kHybridLongFolds,     // hybrid's second fold: likewise
  kLongItems,           // clipping items of kLongChain or more candidates, listed for k_clip_long
  kLongTaken,           // k_clip_long: the listed items its blocks have taken
  kCounterCount
};

// A device-sized run (Pipeline::dev): the sizes that a run in the other modes reads on the host
// (setup triangles, silhouette edges, front triangles, (tile, triangle) and (tile, edge) pairs)
// stay on the device. After each stage's scan one thread (take_sizes) clamps the totals to the
// host's upper bounds (Capacities, learned from earlier runs): within them, the counts the next
// kernels read (tagged counts, exec.cuh); past one, kSzOverflow is set and every later count is
// 0, so nothing writes past a buffer, and the run is repeated with host reads once it has ended
// (one check of the counters after the frame). The emit kernels get counts of their own, 0 on
// overflow, so a total past its bound writes nothing.
enum SizeSlot : uint32_t {
  kSzSetup, kSzUses, kSzSetupEmit,                                // after setup's scan
  kSzEdges, kSzTris, kSzFrontBuild, kSzSilScatter,                // after the silhouettes' scans
  kSzItems, kSzTriEmit,                                           // after binning's triangle scan
  kSzTileEdges, kSzEdgeEmit, kSzCullLanes,                        // after its edge scan (and the above)
  kSzOverflow,
  kSzTotals,  // the totals as found, two per stage (for growing the bounds)
  kSizeSlots = kSzTotals + 8
};
// The same kernel pads the key lists the stage's sorts will sort: keys from the count to the
// bound set to all ones (Exec::sort_pairs' padding, done here so that it costs no launch).
struct SizePad {
  uint64_t* keys;
  uint32_t which;  // the count: total 0 or 1
  uint64_t bound;
};
struct SizeArgs {
  uint64_t* sz;
  uint32_t stage;  // 0 setup, 1 silhouettes, 2 binning's triangles, 3 its edges (after 2's take)
  const uint64_t* total[2];
  uint64_t bound[2];
  uint64_t n_triangles, cull_lanes;
  SizePad pad[4];
  uint32_t n_pads;
};
// Whether the stage's totals passed their bounds (or an earlier stage's did). Every thread of
// the kernel computes it; only element 0 writes kSzOverflow, and a thread that reads it before
// that write finds this stage's own reason itself.
TV_HD inline bool sizes_over(const SizeArgs& a) {
  const uint64_t t0 = *a.total[0], t1 = a.total[1] ? *a.total[1] : 0;
  return a.sz[kSzOverflow] != 0 || t0 > a.bound[0] || t1 > a.bound[1];
}
// Padding element i (over every pad's range [count, bound), one after the other).
TV_HD inline void pad_keys(const SizeArgs& a, bool over, uint64_t i) {
  for (uint32_t k = 0; k < a.n_pads; ++k) {
    const SizePad& p = a.pad[k];
    const uint64_t from = over ? 0 : *a.total[p.which];
    if (i < p.bound - from) {
      p.keys[from + i] = ~uint64_t{0};
      return;
    }
    i -= p.bound - from;
  }
}
TV_HD inline void take_sizes(const SizeArgs& a) {
  uint64_t* s = a.sz;
  const uint64_t t0 = *a.total[0], t1 = a.total[1] ? *a.total[1] : 0;
  const bool over = sizes_over(a);
  s[kSzTotals + 2 * a.stage] = t0;
  s[kSzTotals + 2 * a.stage + 1] = t1;
  if (over) s[kSzOverflow] = 1;
  const uint64_t k = over ? 0 : 1;
  switch (a.stage) {
    case 0:
      s[kSzSetup] = k * t0;
      s[kSzUses] = k * 3 * t0;
      s[kSzSetupEmit] = k * a.n_triangles;
      break;
    case 1:
      s[kSzEdges] = k * t0;
      s[kSzTris] = k * t1;
      s[kSzFrontBuild] = k * s[kSzSetup];
      s[kSzSilScatter] = k * s[kSzUses];
      break;
    case 2:
      s[kSzItems] = k * t0;
      s[kSzTriEmit] = k * s[kSzTris];
      break;
    default:  // the edges' take waits for the triangles' (their chains run side by side until cull)
      s[kSzTileEdges] = k * t0;
      s[kSzEdgeEmit] = k * s[kSzEdges];
      // Either bound passed: every count after the chains meet is 0 (the triangle chain's own
      // kernels may have started with theirs, which fit their buffers).
      if (over) s[kSzItems] = 0;
      s[kSzCullLanes] = k * s[kSzItems] * a.cull_lanes;
      break;
  }
}
void queue_take_sizes(Exec& ex, const SizeArgs& a);  // one thread on the stream in use

// The silhouette hash table (silhouettes.cu). A slot: the key + 1 (0: empty) and, in the same 16 bytes (one memory transaction),
// uses (bits 0-15), front-facing uses (16-31) and the bitwise complement of the lowest use
// index (32-63), so an all-zero slot is empty and the payload is updated by one CAS. The two
// counts saturate at 65535 (the rule only asks for 0, 2 and whether they differ).
struct alignas(16) HashSlot {
  uint64_t key1;
  uint64_t payload;
};

// A snapped setup triangle (canonical order: by trace triangle, then fan position).
struct SetupTri {
  Vtx v[3];
  uint32_t id;    // trace triangle
  uint32_t draw;
  uint32_t front;   // negative doubled area in window space
  uint32_t opaque;  // opaque draw without shader depth/discard
  uint32_t cut;     // made by clip-space clipping: its edges are boundaries
};
static_assert(sizeof(SetupTri) % 4 == 0, "records of whole words");
inline constexpr uint32_t kSetupWords = sizeof(SetupTri) / 4;  // a record's 32-bit words (staged copies)


struct DrawInfo {
  uint32_t vertex_offset, vertex_count;
  uint32_t triangle_offset, triangle_count;
  uint32_t opaque, soup;
};

struct FrameDev {
  uint32_t width, height, subpixel_bits, depth_bits, n_samples;
  float depth_near, depth_far;
  uint32_t n_draws;
  uint64_t n_vertices, n_triangles;
};

// What a pipeline run learned about sizes; kept between runs (grow-only), so timed runs
// after the first allocate nothing.
struct Capacities {
  uint64_t deep_pairs = 1 << 16;
  uint64_t candidates = 1 << 14;
  uint64_t clip_slots = 1 << 16;
  uint64_t clip_edges = 1 << 20;
  uint32_t slot_factor = 4;  // piece slots reserved per clipping item: factor * (candidates + 1)
  // Upper bounds of a device-sized run's sizes (SizeSlot), learned from the runs with host reads.
  uint64_t setup = 0, edges = 0, tris = 0, items = 0, tile_edges = 0;
  static void learn(uint64_t& cap, uint64_t v) {
    if (v > cap) cap = v + v / 32 + 32;
  }
  // Every bound a device-sized graph is recorded for (DevGraph: valid while they stay).
  std::vector<uint64_t> graph_bounds() const {
    return {setup, edges, tris, items, tile_edges, deep_pairs, candidates, clip_slots, clip_edges, slot_factor};
  }
};

template <class P>
struct Pipeline {
  Exec& ex;
  CudaConfig cfg;
  FrameDev f{};
  Capacities caps;
  std::vector<DrawInfo> draws_host;

  // Frame (uploaded once).
  Buf<float4> vertices;
  Buf<uint32_t> indices;        // global vertex indices, 3 per triangle
  Buf<uint32_t> tri_draw;       // per trace triangle
  Buf<DrawInfo> draws;
  Buf<uint32_t> sample_xy;      // per sample: x | y << 16
  Buf<uint64_t> counters;       // Counter
  // Device-sized run: the sizes stay on the device (SizeSlot); n_setup, n_edges, n_tris,
  // n_items and n_tile_edges hold the host's upper bounds (caps) instead of the sizes.
  bool dev = false;
  Buf<uint64_t> sizes;
  // The count a kernel, scan or sort gets: `host` itself, or (device-sized) the tagged count of
  // a size slot whose upper bound is `host`.
  uint64_t N(uint32_t slot, uint64_t host) const { return dev ? dev_count(sizes.get() + slot, host) : host; }

  // Setup.
  Buf<uint32_t> fan_count;
  Buf<uint64_t> fan_offset;
  Buf<uint32_t> weld;           // per vertex: lowest index with the same position (soup draws)
  Buf<uint32_t> weld_table;
  Buf<int8_t> tri_facing;       // per trace triangle: clip_facing (setup's count, read by its emit)
  Buf<SetupTri> setup;
  Buf<uint64_t> use_key;        // 3 per setup triangle: edge key, or kBoundary
  Buf<uint32_t> use_forward;    // 3 per setup triangle: 1 where the keyed edge runs from its lower index
  Buf<int4> setup_vtx;          // per vertex: snapped x, y, z and 1 when inside every plane
  uint64_t n_setup = 0;

  // Silhouettes.
  Buf<HashSlot> hash_slots;
  uint64_t hash_cap = 0;
  const HashSlot* hash_clean_at = nullptr;  // the table, all zeros over hash_clean slots
  uint64_t hash_clean = 0;
  Buf<uint32_t> sil_flag;
  Buf<uint64_t> sil_offset;
  Buf<uint64_t> sil_key, sil_key_sorted;
  Buf<uint32_t> sil_use, sil_use_sorted;
  Buf<SilEdge<P>> edges;
  uint64_t n_edges = 0;

  // Front triangles.
  Buf<uint32_t> front_flag;     // per setup triangle: front-facing (written by setup)
  Buf<uint64_t> front_offset;
  Buf<TileTri<P>> tris;
  uint64_t n_tris = 0;

  // Binning.
  uint32_t tiles_x = 0, tiles_y = 0, n_tiles = 0;
  TileGrid grid{};
  Buf<uint32_t> tri_tiles, edge_tiles;        // tiles per triangle / edge
  Buf<uint32_t> big_tris, big_edges;          // binning: the wide ones (a block each)
  Buf<uint32_t> long_folds;                   // the fold's long runs (first entry of each)
  Buf<uint64_t> tri_tiles_off, edge_tiles_off;
  Buf<uint64_t> item_key, item_key_sorted;    // (tile, triangle) pairs by tile
  Buf<uint32_t> item_tri, item_tri_sorted;
  Buf<uint64_t> occ_key, occ_key_sorted;      // the same pairs by (tile, not opaque, z_min)
  Buf<uint32_t> occ_tri, occ_tri_sorted;
  Buf<uint64_t> tedge_key, tedge_key_sorted;  // (tile, edge) pairs by (tile, z_min)
  Buf<uint32_t> tedge_id, tedge_id_sorted;
  Buf<Rect> tedge_box;
  Buf<OccRec> occ_rec;                        // the sorted occluder list as records (streamed by occlusion)                        // the sorted pairs' edge bounding boxes (streamed by cull)
  Buf<uint32_t> tile_item_begin, tile_edge_begin, tile_occ_count;  // n_tiles + 1 (begin of next = end)
  // Finer occlusion bins: per record its bin count and first slot; the (bin, record) pairs by
  // bin (records in tile order within a bin); the records gathered in that order; per global
  // bin (tile * bins_per_tile + bin) its first pair and its count.
  Buf<uint32_t> obin_cnt, obin_val, obin_val_sorted, obin_begin, obin_count;
  Buf<uint64_t> obin_off, obin_key, obin_key_sorted;
  Buf<OccRec> obin_rec;
  uint32_t obins_x = 1, obins_y = 1;  // bins per tile, 1 x 1 when off
  uint32_t obin_w = 0, obin_h = 0;    // bin size in pixels when on
  uint64_t n_obin_pairs = 0;
  Buf<uint64_t> area_key, area_key_sorted;    // items by original id (visible-area fold order)
  Buf<uint32_t> area_item, area_item_sorted;
  uint64_t n_items = 0, n_tile_edges = 0;

  // Per-tile counters, vis::TileCounters::columns() order (kCol* below).
  Buf<int64_t> tile_rows;

  // Cull and clip.
  Buf<uint32_t> piece_count;       // per item
  Buf<uint32_t> cand_count, cand_cursor;
  Buf<uint32_t> cand_offset;       // scan of cand_count (n_items + 1)
  Buf<uint64_t> deep;              // item << 32 | edge
  Buf<uint64_t> cands;             // item << 32 | edge (unordered)
  Buf<uint32_t> cand_edges;        // per item, its candidate edges (ascending after the clip's sort)
  Buf<uint32_t> cand_scratch;
  Buf<uint32_t> clip_items;
  Buf<uint32_t> long_items;        // items of long candidate chains (clip.cu, k_clip_long)
  Buf<uint32_t> item_slot;         // first piece slot of a clipping item
  Buf<uint64_t> slot_poly;         // piece slot: edge offset << 32 | edge count
  Buf<PEdge<P>> clip_edges;

  // Pieces (pieces.cuh): per piece id, n_items + clip_slots of them.
  Buf<uint32_t> slot_item;         // per piece slot, its item (kNone: unused)
  Buf<uint8_t> piece_visible;
  Buf<uint16_t> piece_edges;       // a judged piece's edge count (occlusion; hybrid's fold counts with it)
  Buf<uint64_t> heavy;             // occlusion (unclipped, finer bins): pieces queued for a warp each
  Buf<uint32_t> occ_cells;         // occlusion (finer bins off): the occluder lists' cell masks
  Buf<double> piece_area;

  // Hybrid (hybrid.cu): per tile its verdict and detection work; per occluder position the
  // detector's scratch (and per tile its batch of pairs to test); per item its owned samples
  // in a per-pixel tile.
  Buf<uint32_t> hyb_cause, hyb_crossing, hyb_range, hyb_owned, hyb_heavy;
  Buf<uint4> hyb_active;
  Buf<DetRec> hyb_rec;
  Buf<uint64_t> hyb_screens, hyb_tests, hyb_shaded, hyb_batch, hyb_bin_counts, hyb_pp_sums;
  Buf<uint32_t> hyb_long_folds;  // the hybrid fold's long runs (first entry of each)
  Buf<uint8_t> hyb_flag;

  // Outputs.
  Buf<int32_t> ids;
  Buf<int32_t> hyb_pp_ids;          // hybrid: the per-pixel tiles' ids, until stage_per_pixel_out
  cudaEvent_t hyb_pp_zeroed = nullptr;  // hybrid: the per-pixel counts zeroed (side 5), for the found tiles' pass
  Buf<double> area;                // per trace triangle

  explicit Pipeline(Exec& e) : ex(e) {
    for (auto* b : {&fan_count, &weld, &weld_table, &use_forward, &sil_flag, &sil_use, &sil_use_sorted, &front_flag,
                    &tri_tiles, &edge_tiles, &item_tri, &item_tri_sorted, &occ_tri, &occ_tri_sorted, &tedge_id,
                    &tedge_id_sorted, &tile_item_begin, &tile_edge_begin, &tile_occ_count, &area_item,
                    &area_item_sorted, &piece_count, &cand_count, &cand_cursor, &cand_offset,
                    &cand_edges, &cand_scratch, &clip_items, &long_items, &item_slot, &indices, &tri_draw, &sample_xy,
                    &obin_cnt, &obin_val, &obin_val_sorted, &obin_begin, &obin_count, &slot_item, &occ_cells, &big_tris,
                    &big_edges, &long_folds})
      b->bind(&e);
    for (auto* b : {&sizes, &fan_offset, &use_key, &sil_offset, &sil_key, &sil_key_sorted,
                    &front_offset, &tri_tiles_off, &edge_tiles_off, &item_key, &item_key_sorted, &occ_key,
                    &occ_key_sorted, &tedge_key, &tedge_key_sorted, &area_key, &area_key_sorted, &deep, &cands, &slot_poly, &counters, &heavy,
                    &obin_off, &obin_key, &obin_key_sorted})
      b->bind(&e);
    vertices.bind(&e);
    setup_vtx.bind(&e);
    tedge_box.bind(&e);
    hash_slots.bind(&e);
    occ_rec.bind(&e);
    obin_rec.bind(&e);
    draws.bind(&e);
    setup.bind(&e);
    tri_facing.bind(&e);
    edges.bind(&e);
    tris.bind(&e);
    tile_rows.bind(&e);
    clip_edges.bind(&e);
    piece_visible.bind(&e);
    piece_area.bind(&e);
    piece_edges.bind(&e);
    hyb_long_folds.bind(&e);
    ids.bind(&e);
    hyb_pp_ids.bind(&e);
    area.bind(&e);
    for (auto* b : {&hyb_cause, &hyb_crossing, &hyb_range, &hyb_owned, &hyb_heavy}) b->bind(&e);
    hyb_active.bind(&e);
    hyb_rec.bind(&e);
    hyb_screens.bind(&e);
    hyb_tests.bind(&e);
    hyb_batch.bind(&e);
    hyb_bin_counts.bind(&e);
    hyb_shaded.bind(&e);
    hyb_pp_sums.bind(&e);
    hyb_flag.bind(&e);
  }
};

inline constexpr uint32_t kTileColumns = 10;
enum TileColumn : uint32_t {
  kColTriangles,
  kColEdges,
  kColPairTests,
  kColCandidates,
  kColClips,
  kColPieces,
  kColVisiblePieces,
  kColOcclusionTests,
  kColSamplesCovered,
  kColFragments
};

// Hybrid's budget (cause 3, hybrid_resolver.cpp): a tile whose triangles x edges pass the pair
// budget, or that holds more triangles or edges than the unit's lists, goes per pixel. Decided
// from binning's counts alone, so culling can skip such a tile's analytic work (cause 2, a
// non-opaque triangle, takes precedence in the verdict, but the tile goes per pixel either way).
struct HybridBudget {
  bool on = false;  // hybrid mode
  uint64_t pair_budget = 0;
  uint32_t list_triangles = 0, list_edges = 0;
  TV_HD bool over(const int64_t* row) const {
    const uint64_t tris = uint64_t(row[kColTriangles]), edges = uint64_t(row[kColEdges]);
    return on && ((pair_budget && tris * edges > pair_budget) || (list_triangles && tris > list_triangles) ||
                  (list_edges && edges > list_edges));
  }
};

inline HybridBudget hybrid_budget(const CudaConfig& c) {
  return {c.hybrid, c.pair_budget, c.list_triangles, c.list_edges};
}

inline uint32_t bits_for(uint64_t v) {  // bits to hold values in [0, v]
  uint32_t b = 0;
  while (b < 64 && (v >> b) != 0) ++b;
  return b;
}

// Stages (one file each). Each returns after queueing its work on the stream; those that
// need a size on the host read it (a synchronisation, named where it happens).
void upload_frame_common(Exec& ex, const trace::Frame& frame, uint32_t depth_bits, FrameDev& f,
                         std::vector<DrawInfo>& draws_host, Buf<float4>& vertices, Buf<uint32_t>& indices,
                         Buf<uint32_t>& tri_draw, Buf<DrawInfo>& draws, Buf<uint32_t>& sample_xy);
template <class P>
void stage_setup(Pipeline<P>& p);
template <class P>
void stage_silhouettes(Pipeline<P>& p);
template <class P>
void stage_binning(Pipeline<P>& p);
template <class P>
void stage_cull(Pipeline<P>& p);
template <class P>
bool stage_clip(Pipeline<P>& p);  // false: a buffer overflowed (capacities grown; run again)
// The clipping pools' counters c[0, kFloatAnomalies) checked: false when one overflowed (its
// capacity grown). stage_clip checks them itself, except in a device-sized run.
template <class P>
bool pools_fit(Pipeline<P>& p, const uint64_t* c);
// k_clip_long's walk phases summed over the process (clip.cu, builds with
// TILEVIS_CUDA_WALK_CLOCK; empty otherwise or when the device cannot be read).
std::vector<std::pair<std::string, uint64_t>> walk_clock_totals();
// Occlusion and raster run once per kind of piece (pieces.cuh): the unclipped items' pieces on
// side stream 0 as soon as culling is done (beside the clipping), the clipped ones' after it.
enum class Pass;
template <class P>
void stage_occlusion(Pipeline<P>& p, Pass pass);
template <class P>
void occlusion_cells(Pipeline<P>& p);  // finer bins off: the sorted occluder records' cell masks (binning, side 1)
template <class P>
void raster_begin(Pipeline<P>& p);  // clears the id buffer, before either raster pass
template <class P>
void stage_raster(Pipeline<P>& p, Pass pass);
template <class P>
void stage_fold(Pipeline<P>& p);
// Hybrid mode, beside the analytic stages: the per-pixel tiles that binning's counts decide
// (budget, non-opaque content: cause_of) from the start (side 5), every tile's verdict (side 3,
// the heavy tiles' blocks on side 4; side 3 goes on once both are done), then the per-pixel
// tiles the detector found (side 3), their ids in a buffer of their own; once the occlusion
// passes are done, the visible areas (side 1, instead of stage_fold); last, over the rasters' ids
// and counts, the per-pixel tiles' ids and rows.
enum class PerPixelTiles { counted, found };
template <class P>
void stage_verdicts(Pipeline<P>& p);
template <class P>
void stage_per_pixel(Pipeline<P>& p, PerPixelTiles which);  // counted first: it zeroes the counts
template <class P>
void stage_hybrid(Pipeline<P>& p);
template <class P>
void stage_per_pixel_out(Pipeline<P>& p);

}  // namespace tilevis::cuda
