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

// Runs of more than kFoldLong items go to a block in both folds (raster.cu says why 16).
inline constexpr uint32_t kFoldLong = 16;

// The visible-area folds (raster.cu's, and hybrid.cu's second one): a thread per original
// triangle's run of items (area_key sorted, ending with a sentinel), except runs of more than
// `longer` items (kFoldLong), which the GPU queues for a block. At q: 0 not the start of a run, 1 a run for
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
// A block's left fold of one queued run, the same double as the thread's loop (fold_area,
// hybrid_fold) without its chain of dependent loads. The run's entries are taken kFoldBlock at a
// time: each thread reads its entry (src.entry(r, n): what the entry's terms need, and n, how many
// terms it adds), a block scan places the entries' terms in canonical order, and the terms are
// loaded a window at a time, a thread per term (its entry found by binary search over the
// scan), so an item of many pieces costs no thread a chain of loads. Thread 0 then adds the
// window's terms in order. A piece that is not visible is the term -0.0: x + -0.0 == x for every
// double x under round to nearest, so it changes no bit of the sum. A term repeated m times is
// add_repeated's (m dadd in a row). Blocks of kFoldBlock threads; returns the sum on thread 0.
inline constexpr uint32_t kFoldBlock = 512, kFoldWindow = 2048;

template <class Src>
__device__ double block_fold_run(const uint64_t* area_key, uint64_t q0, uint64_t n_items, Src& src) {
  using Entry = typename Src::Entry;
  __shared__ double term[kFoldWindow];
  __shared__ uint32_t repeat[Src::kRepeats ? kFoldWindow : 1];
  __shared__ uint32_t repeated[Src::kRepeats ? kFoldWindow / 32 : 1];  // bit k % 32 of word k / 32: repeat[k] != 1
  __shared__ Entry entry[kFoldBlock];
  __shared__ uint32_t first[kFoldBlock + 1];  // entry i's terms: [first[i], first[i + 1])
  __shared__ uint32_t warp_total[kFoldBlock / 32];
  const uint32_t tid = threadIdx.x, lane = tid & 31u, warp = tid / 32u;
  const uint64_t id = area_key[q0];
  double sum = 0;
  for (uint64_t r0 = q0;; r0 += kFoldBlock) {
    const uint64_t r = r0 + tid;
    const bool in = r <= n_items && area_key[r] == id;  // the run is contiguous: a prefix of the chunk
    uint32_t n = 0;
    if (in) entry[tid] = src.entry(r, n);
    uint32_t incl = n;  // the block's inclusive scan of n
    for (uint32_t d = 1; d < 32; d <<= 1) {
      const uint32_t y = __shfl_up_sync(0xffffffffu, incl, d);
      if (lane >= d) incl += y;
    }
    if (lane == 31) warp_total[warp] = incl;
    const uint32_t entries = uint32_t(__syncthreads_count(in));
    for (uint32_t w = 0; w < warp; ++w) incl += warp_total[w];
    first[tid + 1] = incl;
    if (tid == 0) first[0] = 0;
    __syncthreads();
    const uint32_t total = first[entries];
    for (uint32_t w0 = 0; w0 < total; w0 += kFoldWindow) {
      const uint32_t end = tmin(total - w0, kFoldWindow);
      // Whole warps (a warp's k are 32 consecutive, a word of `repeated`).
      for (uint32_t k = tid; k < (end + 31u) / 32u * 32u; k += kFoldBlock) {
        uint32_t m = 1;
        if (k < end) {
          const uint32_t t = w0 + k;
          uint32_t lo = 0, hi = entries;  // the last entry whose first term is at most t
          while (hi - lo > 1) {
            const uint32_t mid = (lo + hi) / 2;
            if (first[mid] <= t) lo = mid;
            else hi = mid;
          }
          term[k] = src.term(entry[lo], t - first[lo], m);
        }
        if constexpr (Src::kRepeats) {
          repeat[k] = m;
          const unsigned bits = __ballot_sync(0xffffffffu, m != 1);
          if (lane == 0) repeated[k / 32u] = bits;
        }
      }
      __syncthreads();
      if (tid == 0) {
        if constexpr (Src::kRepeats) {
          // The plain terms up to the next repeated one (the word's next set bit) in a loop with
          // no branch on the term, so their loads run ahead of the chain of additions.
          for (uint32_t k = 0; k < end;) {
            const uint32_t bits = repeated[k / 32u] >> (k % 32u);
            const uint32_t stop = bits ? k + uint32_t(__ffs(bits)) - 1u : tmin(end, (k | 31u) + 1u);
#pragma unroll 8
            for (uint32_t j = k; j < stop; ++j) sum = dadd(sum, term[j]);
            k = stop;
            if (bits) {
              sum = add_repeated(sum, term[k], repeat[k]);
              ++k;
            }
          }
        } else {
#pragma unroll 8
          for (uint32_t k = 0; k < end; ++k) sum = dadd(sum, term[k]);
        }
      }
      __syncthreads();
    }
    if (entries < kFoldBlock) break;
    __syncthreads();  // first[] is read before the next chunk writes it
  }
  return sum;
}
#endif

}  // namespace tilevis::cuda
