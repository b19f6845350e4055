// The pieces occlusion and raster work on, by id: an item (tile, triangle) without candidates
// has one piece, its triangle clipped to the tile (recomputed here rather than stored), with
// id = the item's index; a clipped item's pieces are its piece slots in the clip pools, with
// id = n_items + slot. The two kinds are visited by separate passes: the unclipped items'
// as soon as culling is done (beside the clipping), the slots after it.
#pragma once

#include "pipeline.cuh"

namespace tilevis::cuda {

enum class Pass { unclipped, clipped };

template <class P>
struct PieceSource {
  const TileTri<P>* tris;
  const uint64_t* item_key;
  const uint32_t* item_tri;
  const uint32_t* cand_count;
  const uint32_t* piece_count;
  const uint64_t* slot_poly;
  const uint32_t* slot_item;  // per slot, its item (kNone: reserved, unused)
  const PEdge<P>* pool;
  TileGrid grid;
  uint64_t n_items;            // the first clipped piece's id (device-sized: the items' upper bound)
  const uint64_t* item_count;  // the items there are (device memory)
};

template <class P>
struct PieceView {
  const PEdge<P>* e;
  uint32_t n;  // 0: no piece under this id
  uint32_t item, tile, tri;
};

// `local` must hold kTileCap edges.
template <class P>
TV_HD inline PieceView<P> piece_at(const PieceSource<P>& s, uint64_t id, PEdge<P>* local) {
  PieceView<P> v{local, 0, 0, 0, 0};
  uint64_t sp = 0;
  if (id < s.n_items) {
    v.item = uint32_t(id);
    if (s.cand_count[id] != 0 || s.piece_count[id] == 0) return v;
  } else {
    sp = s.slot_poly[id - s.n_items];
    v.item = s.slot_item[id - s.n_items];
    if (v.item == kNone) return v;
  }
  v.tile = uint32_t(s.item_key[v.item]);
  v.tri = s.item_tri[v.item];
  if (id < s.n_items) {
    bool overflow = false;
    v.n = tile_polygon<P>(s.tris[v.tri], s.grid.rect(v.tile), local, overflow);
  } else {
    v.e = s.pool + (sp >> 32);
    v.n = uint32_t(sp);
  }
  return v;
}

template <class P>
PieceSource<P> piece_source(Pipeline<P>& p) {
  PieceSource<P> s{};
  s.tris = p.tris.get();
  s.item_key = p.item_key_sorted.get();
  s.item_tri = p.item_tri_sorted.get();
  s.cand_count = p.cand_count.get();
  s.piece_count = p.piece_count.get();
  s.slot_poly = p.slot_poly.get();
  s.slot_item = p.slot_item.get();
  s.pool = p.clip_edges.get();
  s.grid = p.grid;
  s.n_items = p.n_items;
  s.item_count = p.dev ? p.sizes.get() + kSzItems : p.tri_tiles_off.get() + p.n_tris;
  return s;
}

// A pass's pieces: ids [base, base + *count), at most cap of them.
struct PassRange {
  uint64_t base;
  const uint64_t* count;
  uint64_t cap;
};

template <class P>
PassRange pass_range(Pipeline<P>& p, Pass pass) {
  if (pass == Pass::unclipped)
    return {0, p.dev ? p.sizes.get() + kSzItems : p.tri_tiles_off.get() + p.n_tris, p.n_items};
  return {p.n_items, p.counters.get() + kSlotsUsed, p.caps.clip_slots};
}

// Runs of more than kFoldLong items go to a warp in both folds (raster.cu says why 16).
inline constexpr uint32_t kFoldLong = 16;

// The visible-area folds (raster.cu's, and hybrid.cu's second one): a thread per original
// triangle's run of items (area_key sorted, ending with a sentinel), except runs of more than
// `longer` items (kFoldLong), which the GPU queues for a warp. At q: 0 not the start of a run, 1 a run for
// the thread, 2 a run queued (its first entry appended to `runs`).
TV_HD inline int fold_run_start(const uint64_t* area_key, uint64_t q, uint64_t n_items, uint32_t longer,
                                uint32_t* runs, uint64_t* run_count) {
  const uint64_t id = area_key[q];
  if (q > 0 && area_key[q - 1] == id) return 0;
  if (q + longer < n_items && area_key[q + longer] == id) {
    runs[bump_one(run_count, ~uint64_t{0})] = uint32_t(q);
    return 2;
  }
  return 1;
}

#if defined(__CUDACC__)
// A warp's share of a queued run: the run's entries among r0 .. r0 + 31 (the list ends with a
// sentinel, so r <= n_items is inside it).
__device__ inline uint32_t fold_run_chunk(const uint64_t* area_key, uint64_t r0, uint64_t n_items, uint64_t id) {
  const uint64_t r = r0 + (threadIdx.x & 31u);
  const unsigned run = __ballot_sync(0xffffffffu, r <= n_items && area_key[r] == id);
  return run == 0xffffffffu ? 32u : uint32_t(__ffs(~run) - 1);
}

// A warp's fold of a clipped item's pieces [base, base + n): the lanes load 32 pieces at a
// time and every lane adds the visible ones' areas to `sum` in canonical order (one left fold:
// every lane's sum is the same double). Returns whether one was visible; with `edges`, each
// lane adds its visible pieces' triangles (edges - 2) to `tris`.
__device__ inline bool warp_fold_pieces(const uint8_t* visible, const double* piece_area, const uint16_t* edges,
                                        uint64_t base, uint32_t n, double& sum, uint32_t& tris) {
  const uint32_t lane = threadIdx.x & 31u;
  bool any = false;
  for (uint32_t k0 = 0; k0 < n; k0 += 32) {
    bool pv = false;
    double px = 0;
    if (k0 + lane < n && visible[base + k0 + lane]) {
      pv = true;
      px = piece_area[base + k0 + lane];
      if (edges) tris += edges[base + k0 + lane] - 2u;
    }
    const uint32_t mm = n - k0 < 32 ? n - k0 : 32;
    for (uint32_t t = 0; t < mm; ++t) {
      const bool v = __shfl_sync(0xffffffffu, pv, t);
      const double xt = __shfl_sync(0xffffffffu, px, t);
      if (v) {
        sum = dadd(sum, xt);
        any = true;
      }
    }
  }
  return any;
}
#endif

}  // namespace tilevis::cuda
