// Tiling engine: front-facing triangles and silhouette edges into the tiles whose interior
// they meet (exact separating-axis tests at the tile corners). Two passes over a
// prefix sum (count, then emit) instead of hand-sized bins, then stable radix sorts give
// each tile its lists in canonical order:
//   items     (tile, triangle)            by tile; within a tile, setup order
//   occluders the same pairs              by (tile, not opaque, z_min); setup order on ties
//   edges     (tile, silhouette edge)     by (tile, z_min); silhouette order on ties
//   area      items                       by original triangle id (visible-area fold order)
#include "pipeline.cuh"

namespace tilevis::cuda {
namespace {

template <class P>
struct BinArgs {
  const TileTri<P>* tris;
  const SilEdge<P>* edges;
  TileGrid grid;
  uint32_t tile_w, tile_h, tiles_x, tiles_y, sb, depth_bits;
  uint32_t* tri_tiles;
  uint32_t* edge_tiles;
  const uint64_t* tri_off;
  const uint64_t* edge_off;
  uint64_t* item_key;
  uint32_t* item_tri;
  uint64_t* occ_key;
  uint32_t* occ_tri;
  uint64_t* tedge_key;
  uint32_t* tedge_id;
  int64_t* rows;
  uint32_t* occ_count;
  uint32_t* big_tris;    // GPU: triangles / edges of wide spans, queued by the count pass
  uint32_t* big_edges;
  uint64_t* counters;    // kBigTris, kBigEdges: their numbers
  uint64_t emit_gate;    // the emit pass's element count (tagged on the device: 0 past a bound)
};

TV_HD inline int64_t floor_div64(int64_t a, int64_t d) { return a >= 0 ? a / d : -((-a + d - 1) / d); }

// Calls fn(tile) for every tile whose closed rectangle the box touches (clamped to the screen)
// and that the primitive overlaps.
// The tiles [tx0, tx1] x [ty0, ty1] whose closed rectangle the box touches, clamped to the
// screen (empty when tx1 < tx0 or ty1 < ty0).
struct TileSpan {
  int64_t tx0, tx1, ty0, ty1;
  TV_HD uint64_t count() const { return tx1 < tx0 || ty1 < ty0 ? 0 : uint64_t(tx1 - tx0 + 1) * uint64_t(ty1 - ty0 + 1); }
};
template <class P>
TV_HD inline TileSpan tile_span(const BinArgs<P>& a, const Rect& b) {
  const int64_t tw = int64_t(a.tile_w) << a.sb, th = int64_t(a.tile_h) << a.sb;
  return {tmax<int64_t>(0, floor_div64(b.x0, tw)), tmin<int64_t>(a.tiles_x - 1, floor_div64(b.x1, tw)),
          tmax<int64_t>(0, floor_div64(b.y0, th)), tmin<int64_t>(a.tiles_y - 1, floor_div64(b.y1, th))};
}

template <class P, class Test, class Fn>
TV_HD inline void for_tiles(const BinArgs<P>& a, const Rect& b, Test&& test, Fn&& fn) {
  const TileSpan s = tile_span(a, b);
  for (int64_t ty = s.ty0; ty <= s.ty1; ++ty)
    for (int64_t tx = s.tx0; tx <= s.tx1; ++tx)
      if (test(a.grid.rect(uint32_t(tx), uint32_t(ty)))) fn(uint32_t(ty * a.tiles_x + tx));
}

template <class P>
TV_HD void bin_tri(const BinArgs<P>& a, uint64_t i, bool emit) {
  const TileTri<P>& t = a.tris[i];
  uint32_t count = 0;
  uint64_t at = emit ? a.tri_off[i] : 0;
  const uint64_t zkey = t.opaque ? t.z_min : (uint64_t{1} << a.depth_bits) | t.z_min;
  for_tiles(
      a, t.bbox, [&](const Rect& r) { return triangle_overlaps_rect(t.v[0].xy(), t.v[1].xy(), t.v[2].xy(), r); },
      [&](uint32_t tile) {
        ++count;
        if (!emit) return;
        a.item_key[at] = tile;
        a.item_tri[at] = uint32_t(i);
        a.occ_key[at] = (uint64_t(tile) << (a.depth_bits + 1)) | zkey;
        a.occ_tri[at] = uint32_t(i);
        ++at;
        count_add(&a.rows[uint64_t(tile) * kTileColumns + kColTriangles], 1);
        if (t.opaque) count_add(&a.occ_count[tile], 1u);
      });
  if (!emit) a.tri_tiles[i] = count;
}

template <class P>
TV_HD void bin_edge(const BinArgs<P>& a, uint64_t i, bool emit) {
  const SilEdge<P>& e = a.edges[i];
  uint32_t count = 0;
  uint64_t at = emit ? a.edge_off[i] : 0;
  for_tiles(
      a, e.bbox, [&](const Rect& r) { return segment_overlaps_rect(e.a.xy(), e.b.xy(), r); },
      [&](uint32_t tile) {
        ++count;
        if (!emit) return;
        a.tedge_key[at] = (uint64_t(tile) << a.depth_bits) | e.z_min;
        a.tedge_id[at] = uint32_t(i);
        ++at;
        count_add(&a.rows[uint64_t(tile) * kTileColumns + kColEdges], 1);
      });
  if (!emit) a.edge_tiles[i] = count;
}

template <class P>
TV_HD void bin_tri_count(const BinArgs<P>& a, uint64_t i) { bin_tri(a, i, false); }
template <class P>
TV_HD void bin_tri_emit(const BinArgs<P>& a, uint64_t i) { bin_tri(a, i, true); }
template <class P>
TV_HD void bin_edge_count(const BinArgs<P>& a, uint64_t i) { bin_edge(a, i, false); }
template <class P>
TV_HD void bin_edge_emit(const BinArgs<P>& a, uint64_t i) { bin_edge(a, i, true); }

// Start of each tile's run in a list sorted by tile (key >> shift).
struct RangeArgs {
  const uint64_t* key;
  uint32_t shift;
  uint64_t n;
  uint32_t* begin;
};
TV_HD void tile_begin(const RangeArgs& a, uint64_t i) {
  const uint64_t t = a.key[i] >> a.shift;
  if (i == 0 || (a.key[i - 1] >> a.shift) != t) a.begin[t] = uint32_t(i);
}

template <class P>
struct BoxArgs {
  const SilEdge<P>* edges;
  const uint32_t* ids;
  Rect* box;
};
template <class P>
TV_HD void gather_box(const BoxArgs<P>& a, uint64_t k) { a.box[k] = a.edges[a.ids[k]].bbox; }

template <class P>
struct OccGatherArgs {
  const TileTri<P>* tris;
  const uint32_t* ids;
  OccRec* rec;
};
template <class P>
TV_HD void gather_occ(const OccGatherArgs<P>& a, uint64_t k) {
  const uint32_t i = a.ids[k];
  const TileTri<P>& t = a.tris[i];
  a.rec[k] = {t.bbox, t.z_min, t.id, i, 0};
}

template <class P>
struct AreaKeyArgs {
  const TileTri<P>* tris;
  const uint32_t* item_tri;
  uint64_t* key;
  uint32_t* item;
};
template <class P>
TV_HD void area_key(const AreaKeyArgs<P>& a, uint64_t j) {
  a.key[j] = a.tris[a.item_tri[j]].id;
  a.item[j] = uint32_t(j);
}

// Finer occlusion bins (SVGPU §4.1), as golden makes them: within a tile, bin (bx, by)
// covers [x0 + bx step_x, x0 + (bx + 1) step_x) and likewise in y, the outer bins open towards
// the outside; an opaque occluder joins every bin its bounding-box test (the test point within
// [bbox.x0 - 1, bbox.x1 + 1], same in y) can pass in. Records keep their tile order in a bin.
struct ObinArgs {
  const OccRec* rec;           // by (tile, not opaque, z_min)
  const uint64_t* occ_key;     // tile << (d + 1) | not opaque << d | z_min
  uint32_t depth_bits;
  TileGrid grid;
  int64_t step_x, step_y;      // bin size in sub-pixel units
  uint32_t bins_x, bins_y;     // per tile
  uint32_t* cnt;               // per record: bins joined
  const uint64_t* off;         // per record: first pair slot (scan of cnt)
  uint64_t* key;               // per pair: global bin
  uint32_t* val;               // per pair: record index
  uint32_t* count;             // per global bin: pairs
};

TV_HD inline uint32_t obin_of(int64_t v, int64_t origin, int64_t step, uint32_t n) {
  const int64_t k = v < origin ? 0 : (v - origin) / step;
  return uint32_t(k < int64_t(n) - 1 ? k : int64_t(n) - 1);
}

// The bins [bx0, bx1] x [by0, by1] record k joins; false for a record that is not an occluder.
TV_HD inline bool obin_span(const ObinArgs& a, uint64_t k, uint32_t& tile, uint32_t& bx0, uint32_t& bx1, uint32_t& by0,
                            uint32_t& by1) {
  const uint64_t key = a.occ_key[k];
  if ((key >> a.depth_bits) & 1) return false;  // not opaque: never occludes
  tile = uint32_t(key >> (a.depth_bits + 1));
  const Rect r = a.grid.rect(tile);
  const Rect& b = a.rec[k].bbox;
  bx0 = obin_of(int64_t(b.x0) - 1, r.x0, a.step_x, a.bins_x);
  bx1 = obin_of(int64_t(b.x1) + 1, r.x0, a.step_x, a.bins_x);
  by0 = obin_of(int64_t(b.y0) - 1, r.y0, a.step_y, a.bins_y);
  by1 = obin_of(int64_t(b.y1) + 1, r.y0, a.step_y, a.bins_y);
  return true;
}

TV_HD void obin_count(const ObinArgs& a, uint64_t k) {
  uint32_t tile, bx0, bx1, by0, by1;
  a.cnt[k] = obin_span(a, k, tile, bx0, bx1, by0, by1) ? (bx1 - bx0 + 1) * (by1 - by0 + 1) : 0;
}

TV_HD void obin_emit(const ObinArgs& a, uint64_t k) {
  uint32_t tile, bx0, bx1, by0, by1;
  if (!obin_span(a, k, tile, bx0, bx1, by0, by1)) return;
  uint64_t at = a.off[k];
  for (uint32_t by = by0; by <= by1; ++by)
    for (uint32_t bx = bx0; bx <= bx1; ++bx) {
      const uint64_t g = (uint64_t(tile) * a.bins_y + by) * a.bins_x + bx;
      a.key[at] = g;
      a.val[at] = uint32_t(k);
      ++at;
      atomic_add(&a.count[g], 1u);
    }
}

struct ObinGatherArgs {
  const OccRec* rec;
  const uint32_t* val;
  OccRec* out;
};
TV_HD void obin_gather(const ObinGatherArgs& a, uint64_t q) { a.out[q] = a.rec[a.val[q]]; }

__global__ void k_obin_count(ObinArgs a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) obin_count(a, i);
}
__global__ void k_obin_emit(ObinArgs a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) obin_emit(a, i);
}
__global__ void k_obin_gather(ObinGatherArgs a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) obin_gather(a, i);
}

// On the GPU a primitive whose bounding box spans more than kBigSpan tiles is binned by a
// whole block (its tiles over the threads) rather than by its own thread: a thread per
// primitive left a full-screen triangle's thousands of tile tests to one thread (hot_tile's
// ground at 4K: 8,160 tiles, 4.6 ms of binning). The count pass's threads queue such
// primitives (device counter, kBigTris / kBigEdges) and a second kernel gives each a block, so
// a scene of few wide triangles (decals: ~160, most of them wide) spreads them over the GPU.
// The block's threads test a chunk of the span each, and an ordered prefix (ballots, then the
// warps' totals) gives each overlapped tile its slot in the primitive's range, in the span's
// row-major order as the thread's loop leaves them (the later stable sorts do not depend on it:
// a primitive meets a tile once). The host emulation runs the thread-per-primitive bodies above.
// kBigSpan 8 rather than 32: broken_mesh's triangles of 9 to 32 tiles each kept one thread
// testing and emitting its tiles one after the other (Nsight Compute: k_bin emit 34 us for its
// 612 front triangles); new frame on the H200, 32 -> 8: broken_mesh float 0.321 -> 0.309 ms,
// decals 0.323 -> 0.297, glass 0.579 -> 0.552, the bunny unchanged.
inline constexpr uint32_t kBinBlock = 256, kBigSpan = 8;

template <class P, bool Edge, bool Emit>
__device__ void bin_block(const BinArgs<P>& a, uint32_t i, uint32_t* warp_tot) {
  const Rect& box = Edge ? a.edges[i].bbox : a.tris[i].bbox;
  const TileSpan s = tile_span(a, box);
  const uint32_t w = uint32_t(s.tx1 - s.tx0 + 1), total = uint32_t(s.count());
  const uint32_t lane = threadIdx.x & 31u, warp = threadIdx.x / 32;
  uint64_t at = 0;
  uint64_t zkey = 0;
  bool opaque = false;
  if constexpr (Emit) {
    at = Edge ? a.edge_off[i] : a.tri_off[i];
    if constexpr (!Edge) {
      const TileTri<P>& t = a.tris[i];
      opaque = t.opaque != 0;
      zkey = opaque ? t.z_min : (uint64_t{1} << a.depth_bits) | t.z_min;
    } else {
      zkey = a.edges[i].z_min;
    }
  }
  uint32_t count = 0;
  for (uint32_t base = 0; base < total; base += blockDim.x) {
    const uint32_t q = base + threadIdx.x;
    bool hit = false;
    uint32_t tile = 0;
    if (q < total) {
      const uint32_t tx = uint32_t(s.tx0) + q % w, ty = uint32_t(s.ty0) + q / w;
      const Rect r = a.grid.rect(tx, ty);
      if constexpr (Edge) {
        const SilEdge<P>& e = a.edges[i];
        hit = segment_overlaps_rect(e.a.xy(), e.b.xy(), r);
      } else {
        const TileTri<P>& t = a.tris[i];
        hit = triangle_overlaps_rect(t.v[0].xy(), t.v[1].xy(), t.v[2].xy(), r);
      }
      tile = ty * a.tiles_x + tx;
    }
    if constexpr (!Emit) {
      count += uint32_t(__syncthreads_count(hit));
      continue;
    }
    const uint32_t ballot = __ballot_sync(0xffffffffu, hit);
    if (lane == 0) warp_tot[warp] = __popc(ballot);
    __syncthreads();
    uint32_t before = 0, chunk = 0;
    for (uint32_t k = 0; k < blockDim.x / 32; ++k) {
      before += k < warp ? warp_tot[k] : 0;
      chunk += warp_tot[k];
    }
    if (hit) {
      const uint64_t o = at + count + before + __popc(ballot & ((1u << lane) - 1u));
      if constexpr (Edge) {
        a.tedge_key[o] = (uint64_t(tile) << a.depth_bits) | zkey;
        a.tedge_id[o] = i;
        atomic_add(&a.rows[uint64_t(tile) * kTileColumns + kColEdges], int64_t{1});
      } else {
        a.item_key[o] = tile;
        a.item_tri[o] = i;
        a.occ_key[o] = (uint64_t(tile) << (a.depth_bits + 1)) | zkey;
        a.occ_tri[o] = i;
        atomic_add(&a.rows[uint64_t(tile) * kTileColumns + kColTriangles], int64_t{1});
        if (opaque) atomic_add(&a.occ_count[tile], 1u);
      }
    }
    count += chunk;
    __syncthreads();  // warp_tot is rewritten by the next chunk
  }
  if constexpr (!Emit) {
    if (threadIdx.x == 0) (Edge ? a.edge_tiles : a.tri_tiles)[i] = count;
  }
}

// A thread per primitive; those of a wide span are queued (count pass) or left (emit pass) for
// k_bin_big.
template <class P, bool Edge, bool Emit>
__global__ void k_bin(BinArgs<P> a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) {
    const Rect& box = Edge ? a.edges[i].bbox : a.tris[i].bbox;
    if (tile_span(a, box).count() > kBigSpan) {
      if constexpr (!Emit) {
        const uint64_t at = bump_one(&a.counters[Edge ? kBigEdges : kBigTris], ~uint64_t{0});
        (Edge ? a.big_edges : a.big_tris)[at] = uint32_t(i);
      }
    } else if constexpr (Edge) {
      bin_edge<P>(a, i, Emit);
    } else {
      bin_tri<P>(a, i, Emit);
    }
  }
}

template <class P, bool Edge, bool Emit>
__global__ void __launch_bounds__(kBinBlock) k_bin_big(BinArgs<P> a, const uint64_t* count, uint64_t cap) {
  TV_KERNEL_WAIT();
  __shared__ uint32_t warp_tot[kBinBlock / 32];
  if (Emit && count_of(a.emit_gate) == 0) return;  // a frame past its bounds emits nothing
  const uint64_t n = *count < cap ? *count : cap;
  const uint32_t* list = Edge ? a.big_edges : a.big_tris;
  for (uint64_t w = blockIdx.x; w < n; w += gridDim.x) bin_block<P, Edge, Emit>(a, list[w], warp_tot);
}
template <class P>
void bin_big_host(const BinArgs<P>&, uint64_t) {}  // the host's thread bodies bin every primitive

__global__ void k_tile_begin(RangeArgs a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) tile_begin(a, i);
}
template <class P>
__global__ void k_gather_box(BoxArgs<P> a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) gather_box<P>(a, i);
}
template <class P>
__global__ void k_gather_occ(OccGatherArgs<P> a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) gather_occ<P>(a, i);
}
template <class P>
__global__ void k_area_key(AreaKeyArgs<P> a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) area_key<P>(a, i);
}

}  // namespace

template <class P>
void stage_binning(Pipeline<P>& p) {
  Exec& ex = p.ex;
  const CudaConfig& c = p.cfg;
  p.tiles_x = (p.f.width + c.tile_w - 1) / c.tile_w;
  p.tiles_y = (p.f.height + c.tile_h - 1) / c.tile_h;
  p.n_tiles = p.tiles_x * p.tiles_y;
  p.grid = {c.tile_w, c.tile_h, p.tiles_x, p.tiles_y, p.f.subpixel_bits, p.f.width, p.f.height};
  const uint32_t tiles = p.n_tiles;
  int64_t* rows = p.tile_rows.need(uint64_t(tiles) * kTileColumns);
  ex.zero(rows, uint64_t(tiles) * kTileColumns * 8);
  uint32_t* occ_count = p.tile_occ_count.need(tiles);
  ex.zero(occ_count, tiles * 4ull);

  BinArgs<P> a{};
  a.tris = p.tris.get();
  a.edges = p.edges.get();
  a.grid = p.grid;
  a.tile_w = c.tile_w;
  a.tile_h = c.tile_h;
  a.tiles_x = p.tiles_x;
  a.tiles_y = p.tiles_y;
  a.sb = p.f.subpixel_bits;
  a.depth_bits = p.f.depth_bits;
  a.tri_tiles = p.tri_tiles.need(p.n_tris + 1);
  a.edge_tiles = p.edge_tiles.need(p.n_edges + 1);
  a.tri_off = p.tri_tiles_off.need(p.n_tris + 1);
  a.edge_off = p.edge_tiles_off.need(p.n_edges + 1);
  a.rows = rows;
  a.occ_count = occ_count;
  a.big_tris = p.big_tris.need(p.n_tris + 1);
  a.big_edges = p.big_edges.need(p.n_edges + 1);
  a.counters = p.counters.get();
  uint64_t* const big_tris = p.counters.get() + kBigTris;
  uint64_t* const big_edges = p.counters.get() + kBigEdges;
  // Triangles on the main stream; edges on side stream 0 (on from the silhouettes, which left
  // them there) until cull; the occluder lists (side 1) until occlusion; the visible-area order
  // (side 2) until the fold.
  const uint64_t n_tris = p.N(kSzTris, p.n_tris), n_edges = p.N(kSzEdges, p.n_edges);
  ex.launch(k_bin<P, false, false>, bin_tri_count<P>, n_tris, a, kBinBlock);
  ex.launch_dyn(k_bin_big<P, false, false>, bin_big_host<P>, big_tris, p.n_tris, a, kBinBlock);
  ex.exclusive_scan(a.tri_tiles, p.tri_tiles_off.get(), n_tris, p.n_tris);
  ex.resume(0);
  ex.launch(k_bin<P, true, false>, bin_edge_count<P>, n_edges, a, kBinBlock);
  ex.launch_dyn(k_bin_big<P, true, false>, bin_big_host<P>, big_edges, p.n_edges, a, kBinBlock);
  ex.exclusive_scan(a.edge_tiles, p.edge_tiles_off.get(), n_edges, p.n_edges);
  ex.on_main();
  if (p.dev) {  // the counts stay on the device, within the learned bounds: each chain takes its own
    p.n_items = p.caps.items;
    p.n_tile_edges = p.caps.tile_edges;
    const uint64_t ni = p.n_items, ne = p.n_tile_edges;
    queue_take_sizes(ex, SizeArgs{p.sizes.get(), 2, {p.tri_tiles_off.get() + p.n_tris, nullptr}, {ni, 0}, 0, 0,
                                  {{p.item_key.need(ni + 1), 0, ni}, {p.occ_key.need(ni + 1), 0, ni},
                                   {p.area_key.need(ni + 1), 0, ni}}, 3});
    const cudaEvent_t items_taken = ex.record();
    ex.resume(0);
    ex.wait(items_taken);
    queue_take_sizes(ex, SizeArgs{p.sizes.get(), 3, {p.edge_tiles_off.get() + p.n_edges, nullptr}, {ne, 0}, 0,
                                  kCullLanes, {{p.tedge_key.need(ne + 1), 0, ne}}, 1});
    ex.on_main();
  } else {
    // sync: the numbers of (tile, triangle) and (tile, edge) pairs (host reads on the main
    // stream: the edges' chain joins it there, and branches off again after).
    ex.merge(0);
    ex.read_many({{&p.n_items, p.tri_tiles_off.get() + p.n_tris}, {&p.n_tile_edges, p.edge_tiles_off.get() + p.n_edges}});
    Capacities::learn(p.caps.items, p.n_items);
    Capacities::learn(p.caps.tile_edges, p.n_tile_edges);
    ex.branch(0);
    ex.on_main();
  }
  if (p.n_items >= 0xffffffffull) throw std::runtime_error("cuda: more than 2^32 - 2 (tile, triangle) pairs");
  const uint64_t n_items = p.N(kSzItems, p.n_items), n_tedges = p.N(kSzTileEdges, p.n_tile_edges);

  const uint64_t ni = p.n_items, ne = p.n_tile_edges;
  a.item_key = p.item_key.need(ni + 1);
  a.item_tri = p.item_tri.need(ni + 1);
  a.occ_key = p.occ_key.need(ni + 1);
  a.occ_tri = p.occ_tri.need(ni + 1);
  a.tedge_key = p.tedge_key.need(ne + 1);
  a.tedge_id = p.tedge_id.need(ne + 1);
  const int tile_bits = int(bits_for(tiles));
  const int d = int(p.f.depth_bits);
  uint32_t* item_begin = p.tile_item_begin.need(tiles);
  uint32_t* edge_begin = p.tile_edge_begin.need(tiles);
  ex.resume(0);
  ex.launch(k_bin<P, true, true>, bin_edge_emit<P>, p.N(kSzEdgeEmit, p.n_edges), a, kBinBlock);
  a.emit_gate = p.N(kSzEdgeEmit, p.n_edges);
  ex.launch_dyn(k_bin_big<P, true, true>, bin_big_host<P>, big_edges, p.n_edges, a, kBinBlock);
  ex.sort_pairs(a.tedge_key, p.tedge_key_sorted.need(ne + 1), a.tedge_id, p.tedge_id_sorted.need(ne + 1), n_tedges,
                tile_bits + d, ne, true);
  ex.zero(edge_begin, tiles * 4ull);
  ex.launch(k_tile_begin, tile_begin, n_tedges, RangeArgs{p.tedge_key_sorted.get(), uint32_t(d), ne, edge_begin});
  ex.launch(k_gather_box<P>, gather_box<P>, n_tedges, BoxArgs<P>{p.edges.get(), p.tedge_id_sorted.get(), p.tedge_box.need(ne + 1)});
  ex.on_main();

  ex.launch(k_bin<P, false, true>, bin_tri_emit<P>, p.N(kSzTriEmit, p.n_tris), a, kBinBlock);
  a.emit_gate = p.N(kSzTriEmit, p.n_tris);
  ex.launch_dyn(k_bin_big<P, false, true>, bin_big_host<P>, big_tris, p.n_tris, a, kBinBlock);
  ex.branch(1);
  ex.sort_pairs(a.occ_key, p.occ_key_sorted.need(ni + 1), a.occ_tri, p.occ_tri_sorted.need(ni + 1), n_items,
                tile_bits + d + 1, ni, true);
  ex.launch(k_gather_occ<P>, gather_occ<P>, n_items, OccGatherArgs<P>{p.tris.get(), p.occ_tri_sorted.get(), p.occ_rec.need(ni + 1)});
  const uint32_t bw = c.occlusion_bin_w && c.occlusion_bin_w < c.tile_w ? c.occlusion_bin_w : c.tile_w;
  const uint32_t bh = c.occlusion_bin_h && c.occlusion_bin_h < c.tile_h ? c.occlusion_bin_h : c.tile_h;
  if (bw == c.tile_w && bh == c.tile_h) occlusion_cells(p);
  ex.on_main();
  ex.sort_pairs(a.item_key, p.item_key_sorted.need(ni + 1), a.item_tri, p.item_tri_sorted.need(ni + 1), n_items,
                tile_bits, ni, true);
  ex.zero(item_begin, tiles * 4ull);
  ex.launch(k_tile_begin, tile_begin, n_items, RangeArgs{p.item_key_sorted.get(), 0, ni, item_begin});

  // Finer occlusion bins: (bin, record) pairs counted, emitted in record order, sorted
  // stably by bin (so records keep their tile order in each bin), gathered.
  p.obins_x = p.obins_y = 1;
  if (bw != c.tile_w || bh != c.tile_h) {
    if (p.dev) throw std::runtime_error("cuda: finer occlusion bins read a size on the host (no device-sized run)");
    ex.merge(1);  // on the main stream: the pair count is read
    p.obin_w = bw;
    p.obin_h = bh;
    p.obins_x = (c.tile_w + bw - 1) / bw;
    p.obins_y = (c.tile_h + bh - 1) / bh;
    const uint64_t n_bins = uint64_t(tiles) * p.obins_x * p.obins_y;
    ObinArgs o{};
    o.rec = p.occ_rec.get();
    o.occ_key = p.occ_key_sorted.get();
    o.depth_bits = p.f.depth_bits;
    o.grid = p.grid;
    o.step_x = int64_t(bw) << p.f.subpixel_bits;
    o.step_y = int64_t(bh) << p.f.subpixel_bits;
    o.bins_x = p.obins_x;
    o.bins_y = p.obins_y;
    o.cnt = p.obin_cnt.need(ni + 1);
    o.off = p.obin_off.need(ni + 1);
    o.count = p.obin_count.need(n_bins + 1);
    ex.zero(o.count, n_bins * 4);
    ex.launch(k_obin_count, obin_count, ni, o);
    ex.exclusive_scan(o.cnt, p.obin_off.get(), ni);
    p.n_obin_pairs = ex.read(p.obin_off.get() + ni);  // sync: the number of (bin, occluder) pairs
    const uint64_t np = p.n_obin_pairs;
    o.key = p.obin_key.need(np + 1);
    o.val = p.obin_val.need(np + 1);
    ex.launch(k_obin_emit, obin_emit, ni, o);
    ex.sort_pairs(o.key, p.obin_key_sorted.need(np + 1), o.val, p.obin_val_sorted.need(np + 1), np,
                  int(bits_for(n_bins)));
    uint32_t* begin = p.obin_begin.need(n_bins + 1);
    ex.zero(begin, n_bins * 4);
    ex.launch(k_tile_begin, tile_begin, np, RangeArgs{p.obin_key_sorted.get(), 0, np, begin});
    ex.launch(k_obin_gather, obin_gather, np, ObinGatherArgs{p.occ_rec.get(), p.obin_val_sorted.get(),
                                                            p.obin_rec.need(np + 1)});
  }

  AreaKeyArgs<P> ak{p.tris.get(), p.item_tri_sorted.get(), p.area_key.need(ni + 1), p.area_item.need(ni + 1)};
  ex.branch(2);
  ex.launch(k_area_key<P>, area_key<P>, n_items, ak);
  ex.sort_pairs(ak.key, p.area_key_sorted.need(ni + 1), ak.item, p.area_item_sorted.need(ni + 1), n_items,
                int(bits_for(p.f.n_triangles)), ni, true);
  // The key list ends with a sentinel no id equals, so a run's walk in the fold stops there
  // (device-sized: the padding keys past the count, all ones, are sentinels too).
  ex.fill_ones(p.area_key_sorted.get() + ni, 8);
  ex.on_main();
  ex.merge(0);  // cull reads the edge lists
}

template void stage_binning<ExactP>(Pipeline<ExactP>&);
template void stage_binning<FloatP>(Pipeline<FloatP>&);

}  // namespace tilevis::cuda
