// Clipping (SVGPU §3.2.2) with the re-check: each (tile, triangle) item with candidate edges
// is clipped by one warp. Candidates go in ascending silhouette id; for each, the warp's lanes
// re-test the current pieces in parallel (32 at a time), and a ballot gives every split piece
// its slot: the inside part replaces its parent, the outside part is appended in parent order,
// exactly the order a sequential loop leaves (the canonical piece order). Items with long
// candidate chains (long_chain(n) or more: 12, or 24 with many items) go to a block each
// instead (k_clip_long): a tree of per-piece walks, a warp each, whose slots are assigned
// afterwards in the same canonical order.
//
// No hand-sized buffers (SVGPU §4.3's failure): piece slots and polygon edges come from pools
// with device-side bump counters. An item that finds its pool exhausted stops and is counted;
// the host grows the pools from the counters and runs the frame again.
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "pipeline.cuh"

namespace tilevis::cuda {
namespace {

template <class P>
struct ClipArgs {
  const TileTri<P>* tris;
  const SilEdge<P>* edges;
  const uint64_t* item_key;
  const uint32_t* item_tri;
  TileGrid grid;
  int64_t* rows;
  const uint64_t* cands;
  const uint32_t* cand_count;
  uint32_t* cand_cursor;
  const uint32_t* cand_offset;
  uint32_t* cand_edges;
  uint32_t* cand_sorted;
  uint64_t cand_cap;  // room in cand_edges / cand_sorted; offsets past it belong to an overflowed run
  uint64_t deep_cap;
  uint32_t* clip_items;
  uint32_t* long_items;  // the items of long_chain(n) or more candidates (unordered), listed by cand_scatter
  uint32_t* item_slot;
  uint64_t* slot_poly;  // edge offset << 32 | edge count
  uint32_t* slot_item;  // the item of each used slot; kNone in reserved slots left unused
  uint64_t slot_cap;
  PEdge<P>* pool;
  uint64_t pool_cap;
  uint32_t* piece_count;
  uint64_t* counters;
  uint32_t slot_factor;
  uint64_t n_items;
  uint32_t spin_ns;  // k_clip_long's tree: a warp's sleep between looks at a piece it waits for
};

// A run whose candidate list overflowed has per-item counts without all their records: it is
// repeated with a larger list, and nothing here may read the incomplete one.
template <class P>
TV_HD inline bool candidates_overflowed(const ClipArgs<P>& a) {
  return a.counters[kCandidates] > a.cand_cap || a.counters[kDeepPairs] > a.deep_cap;
}

// With at least kSmallMinItems items to clip, items of fewer than kSmallChain candidates are
// clipped by a thread each in k_clip_items. Million float, with the occlusion cells: 3.58 ms with
// none, 3.37 below 4, 3.35 below 8, 3.49 below 16 (H200). Exact was slower with it until a step's
// vertex sides became masks (no local array, no spills): million exact 7.71 ms with none, 6.95
// below 4, 6.73 below 8, 6.68 below 16 (H100, outputs byte-identical; the scenes of fewer items,
// which keep a warp each, unchanged). With exact at 8 and kSmallMinItems 4096, dragon_bunnies
// exact (9,376 items) took 3.35 ms against 3.61, armadillo and glass 1 % more; not taken.
inline constexpr uint32_t kSmallChain = 8;
inline constexpr uint32_t kSmallMinItems = 16384;

// Items of long_chain(n) or more candidates are clipped by a block each (k_clip_long, below, says
// why 24), n being the number of items to clip. The candidate that is an item's long_chain(n)-th
// to be scattered lists the item for it. With fewer than kSmallMinItems items (every scene at
// 1080p but million), the longest chains set the stage's length, so shorter ones go to the tree
// too: 12 against 24 (H200, 2026-11-29, one build, the threshold read at run time, outputs
// byte-identical, new frame ms): bunny float 0.406 -> 0.371, exact 0.640 -> 0.608; armadillo
// 0.523 -> 0.506 and 0.834 -> 0.784; glass exact 0.615 -> 0.589; the others within noise (16:
// armadillo float 0.501, bunny 0.378; 8: no better than 12). Million (45,960 items) keeps 24:
// float 2.682 ms at 24, 2.779 at 12, 3.031 at 8.
inline constexpr uint32_t kLongChain = 24, kLongChainFewItems = 12;
TV_HD inline uint32_t long_chain(uint64_t n_clip_items) {
  return n_clip_items >= kSmallMinItems ? kLongChain : kLongChainFewItems;
}
// The number of items to clip, as k_clip_items and k_clip_long count them (cull lists them).
template <class P>
TV_HD inline uint64_t clip_item_count(const ClipArgs<P>& a) {
  const uint64_t n = a.counters[kClipItems];
  return n < a.n_items ? n : a.n_items;
}

template <class P>
TV_HD void cand_scatter(const ClipArgs<P>& a, uint64_t k) {
  const uint64_t d = a.cands[k];
  const uint32_t j = uint32_t(d >> 32);
  const uint32_t pos = atomic_add(&a.cand_cursor[j], 1u);
  const uint64_t at = uint64_t(a.cand_offset[j]) + pos;
  if (at < a.cand_cap) a.cand_edges[at] = uint32_t(d);
  if (pos == long_chain(clip_item_count(a)) - 1) a.long_items[bump_one(&a.counters[kLongItems], ~uint64_t{0})] = j;
}


// The most pieces c lines can cut a convex region into: 1 + c + c (c - 1) / 2.
TV_HD inline uint64_t piece_bound(uint64_t c) { return 1 + c + c * (c - 1) / 2; }

inline constexpr uint32_t kCopyEdges = 12;

// A piece being tested and split (slot: pool offset << 32 | edge count): one of at most
// kCopyEdges edges is copied into a local array, every load issued at once, so that the tests
// and the split walk L1, not the pool (written by an earlier step, so not in L1); a longer one is
// walked in the pool. (A copy in registers, the loops unrolled over it, measured on the H100:
// elephant float 0.707 -> 0.647 ms, million float 3.04 -> 3.29 ms at 8 edges and 3.63 at 12,
// from the registers it takes; not kept.)
template <class P>
struct Piece {
  PEdge<P> copy[kCopyEdges];
  const PEdge<P>* at = nullptr;
  uint32_t n = 0;

  TV_HD void load(const PEdge<P>* pool, uint64_t slot) {
    at = pool + (slot >> 32);
    n = uint32_t(slot);
    if (n > kCopyEdges) return;
    for (uint32_t i = 0; i < kCopyEdges; ++i)
      if (i < n) copy[i] = at[i];
    at = copy;
  }
  TV_HD bool survives(const TileTri<P>& tt, const SilEdge<P>& e, Sides* sides) const {
    return tilevis::cuda::survives<P>(at, n, tt, e, sides);
  }
};

// Piece p (m edges) split by a candidate's line into the pool at `at`: the inside part's edges
// first, the outside part's after them (m + 1 edges each at most). Returns the two polygons' slot
// words (pool offset << 32 | edge count) in `in_slot` and `out_slot`.
template <class P>
TV_HD inline void split_piece(const PEdge<P>* poly, PEdge<P>* pool, uint64_t at, uint32_t m, const typename P::Line& line,
                              const Sides* sides, uint32_t& regularized, uint32_t& anomalies, uint64_t& in_slot,
                              uint64_t& out_slot, PEdge<P>* in_edges = nullptr) {
  PolyOut<P> in{in_edges ? in_edges : pool + at, 0, m + 1, false}, out{pool + at + m + 1, 0, m + 1, false};
  bool regular = false;
  split<P>(poly, m, line, in, out, &regular, sides);
  regularized += regular ? 1 : 0;
  if (in.overflow || out.overflow) {
    ++anomalies;  // only float arithmetic can break convexity
    in.n = tmin(in.n, m + 1);
    out.n = tmin(out.n, m + 1);
  }
  in_slot = (at << 32) | in.n;
  out_slot = ((at + m + 1) << 32) | out.n;
}

// A team's piece slots live in `stage` (the warp's shared memory) while it clips, if they fit,
// and are copied to slot_poly at the end: each step reads and writes them.
inline constexpr uint32_t kStageSlots = 256;

// An item's slots and first chunk of pool edges, when reserved for it beforehand (k_clip_items
// reserves them for a warp's items with one atomic each): the values its own bumps would have
// returned (~0: past the pool), the counters counting the same.
struct ClipReserve {
  bool given;
  uint64_t base, chunk_at;  // chunk: kFirstGrab edges
};
inline constexpr uint64_t kFirstGrab = 2 * kTileCap;

template <class P, class Team>
TV_HD void clip_item(const ClipArgs<P>& a, uint64_t w, Team team, uint64_t* stage, ClipReserve pre = {}) {
  const uint32_t lane = team.lane();
  const uint32_t j = a.clip_items[w];
  const uint32_t c = a.cand_count[j], off = a.cand_offset[j];
  const uint32_t tile = uint32_t(a.item_key[j]);
  const TileTri<P>& tt = a.tris[a.item_tri[j]];
  if (candidates_overflowed(a) || uint64_t(off) + c > a.cand_cap) return;

  // Candidates in ascending silhouette id (the canonical order): each id's rank is its slot.
  for (uint32_t k = lane; k < c; k += Team::kSize) {
    const uint32_t x = a.cand_edges[off + k];
    uint32_t r = 0;
    for (uint32_t m = 0; m < c; ++m) r += a.cand_edges[off + m] < x;
    a.cand_sorted[off + r] = x;
  }

  const uint64_t want = tmin<uint64_t>(piece_bound(c), uint64_t(a.slot_factor) * (c + 1));
  // Polygon edges come from a chunk of the pool the team holds, refilled with one bump (of
  // twice the last, at least what a step needs), so that a step's splits cost no atomic.
  uint64_t chunk_at = 0, chunk_left = 0, next_grab = kFirstGrab;
  auto take = [&](uint64_t total) -> uint64_t {  // uniform over the team; ~0: the pool is exhausted
    if (total > chunk_left) {
      const uint64_t grab = tmax(total, next_grab);
      next_grab = tmin<uint64_t>(2 * next_grab, 1024);
      uint64_t at = 0;
      if (lane == 0) at = bump(&a.counters[kEdgesUsed], grab, a.pool_cap);
      at = team.bcast(at);
      if (at == ~uint64_t{0}) return at;
      chunk_at = at;
      chunk_left = grab;
    }
    const uint64_t at = chunk_at;
    chunk_at += total;
    chunk_left -= total;
    return at;
  };
  uint64_t base = pre.base;
  if (!pre.given) {
    if (lane == 0) base = bump(&a.counters[kSlotsUsed], want, a.slot_cap);
    base = team.bcast(base);
  } else if (base != ~uint64_t{0} && pre.chunk_at != ~uint64_t{0}) {  // take()'s first grab, made
    chunk_at = pre.chunk_at;
    chunk_left = kFirstGrab;
    next_grab = 2 * kFirstGrab;
  }
  const uint64_t poly_at = base == ~uint64_t{0} || (pre.given && pre.chunk_at == ~uint64_t{0}) ? ~uint64_t{0} : take(kTileCap);
  if (poly_at == ~uint64_t{0}) {
    if (lane == 0) atomic_add(&a.counters[kClipOverflow], 1);
    if (base != ~uint64_t{0})
      for (uint64_t k = lane; k < want; k += Team::kSize) a.slot_item[base + k] = kNone;
    return;
  }
  uint64_t* const slots = stage && want <= kStageSlots ? stage : a.slot_poly + base;
  if (lane == 0) {
    bool overflow = false;
    const uint32_t n = tile_polygon<P>(tt, a.grid.rect(tile), a.pool + poly_at, overflow);
    slots[0] = (poly_at << 32) | n;
    a.item_slot[j] = uint32_t(base);
  }
  team.sync();
  uint32_t count = 1, splits = 0, anomalies = 0, regularized = 0;
  bool failed = false;
  // A step waits on nothing it could have loaded earlier: the next step's edge is read during
  // this one, and a piece's polygon (written by an earlier step, so not in L1) is read whole,
  // every load issued at once (Piece).
  SilEdge<P> next_e = a.edges[a.cand_sorted[off]];
  for (uint32_t ci = 0; ci < c && !failed; ++ci) {
    const SilEdge<P> e = next_e;
    if (ci + 1 < c) next_e = a.edges[a.cand_sorted[off + ci + 1]];
    const uint32_t n = count;
    uint32_t appended = 0;
    for (uint32_t k0 = 0; k0 < n; k0 += Team::kSize) {
      const uint32_t k = k0 + lane;
      bool flag = false;
      uint64_t sp = 0;
      Piece<P> piece;
      Sides sides;
      if (k < n) {
        sp = slots[k];
        piece.load(a.pool, sp);
        flag = piece.survives(tt, e, &sides);
      }
      const uint32_t mask = team.ballot(flag);
      const uint32_t rank = popc(mask & ((1u << lane) - 1u));
      const uint64_t dst = uint64_t(n) + appended + rank;
      const uint32_t m = uint32_t(sp);
      const bool room = dst < want;
      if (flag && !room) atomic_add(&a.counters[kReserveOverflow], 1);
      const uint32_t need = flag && room ? 2 * (m + 1) : 0;
      const uint32_t incl = team.scan(need);
      const uint64_t step_at = mask ? take(team.sum(need)) : 0;
      bool fail = flag && (!room || step_at == ~uint64_t{0});
      if (flag && !fail) {
        split_piece<P>(piece.at, a.pool, step_at + incl - need, m, e.line, &sides, regularized, anomalies, slots[k],
                       slots[dst]);
        ++splits;
      }
      appended += popc(mask);
      if (team.ballot(fail) != 0) failed = true;
    }
    team.sync();
    count = n + appended;
  }
  for (uint64_t k = lane; k < want; k += Team::kSize) {
    if (k < count && slots != a.slot_poly + base) a.slot_poly[base + k] = slots[k];
    a.slot_item[base + k] = k < count ? j : kNone;
  }
  team.sync();
  count_add(&a.rows[uint64_t(tile) * kTileColumns + kColClips], splits);
  count_add(&a.counters[kFloatAnomalies], anomalies);
  count_add(&a.counters[kFloatRegularized], regularized);
  if (lane == 0) {
    if (failed) atomic_add(&a.counters[kClipOverflow], 1);
    a.piece_count[j] = count;
    count_add(&a.rows[uint64_t(tile) * kTileColumns + kColPieces], count);
    count_max(&a.counters[kMaxTilePieces], count);
  }
}

// Items with long candidate chains: a block per item. The chain is sequential by definition
// (each candidate splits the pieces the earlier ones left), but within a step the pieces are
// independent: a warp re-tested them 32 at a time, so an item with hundreds of pieces took
// tens of rounds per step and the few such items were the frame (slivers, hot_tile,
// teapot_stadium, armadillo_box, interpenetrating: `k_clip_items` at 2 % occupancy). Here the
// block's threads take kLongBlock pieces a round; the ballots' counts, summed over the warps in
// order, give each outside part the slot a sequential loop gives it (the same canonical order),
// and one bump per round gives the round's polygon edges (from the block's chunk of the pool).
// kLongChain: with the tree below walking a piece a warp at a time, 32 against 96 on the H100
// (new frame, ms, float / exact): teapot_stadium 0.699 / 1.113 against 0.869 / 1.439,
// interpenetrating 0.964 / 1.957 against 1.172 / 1.987, dragon_bunnies 1.697 / 3.371 against
// 1.916 / 3.558, hot_tile and million alike; slivers 3.226 / 5.730 against 2.810 / 5.678 and
// armadillo_box exact 2.715 against 2.537 (more items for k_clip_long's fixed stride over its
// blocks). With the blocks taking listed items as they finish (H100, new frame ms, against the
// fixed stride): slivers 2.345 / 3.572 against 3.154 / 5.713, armadillo_box 1.209 / 2.299
// against 1.450 / 2.690, dragon_bunnies 1.462 / 2.994 against 1.708 / 3.344, the others
// alike. The rounds alone (no tree; every long item in rounds) were slower at 32 and at 96
// on every scene but million and bunny (H100, with the thread-per-walk tree: interpenetrating
// float 1.45 against 1.16 ms). 24 against 32 (H200, 2026-11-28, two calls, each the same
// build with the threshold set at run time; new frame ms, float / exact, 5 runs, outputs
// byte-identical): elephant 0.618 / 1.107 and 0.616 / 1.096 against 0.693 / 1.149 and
// 0.700 / 1.146; bunny 0.446 / 0.729 and 0.452 / 0.729 against 0.471 / 0.745 and 0.469 / 0.751;
// million exact 6.653 and 6.683 against 6.528 and 6.591 (float alike); the other 12 scenes
// within 2.5 %. At 16 million was 2 % (float) and 7 % (exact) slower, at 12 8 % and 11 %; at
// 48, elephant and bunny as at 32 and dragon_bunnies float 12 % slower.
// Exact's block is half float's: its 255 registers a thread (wide arithmetic) fill the SM's
// register file at 256 threads; 512 would spill.
inline constexpr uint32_t kLongBlock = 512, kLongStage = 4096;
template <class P>
inline constexpr uint32_t kLongBlockOf = P::kExact ? kLongBlock / 2 : kLongBlock;
// TILEVIS_CLIP_SPIN_NS=N: the tree's waiting warps (clip_item_tree) sleep N ns between looks at
// the piece they wait for (default 32; 1 to 1,000,000). For compute-sanitizer's racecheck: with
// float's 16 warps a block and 32 ns or 1 us, the waiters' instrumented looks crowded out the
// warp making the piece, and the run made no progress in 120-400 s, on chains of 24, 32 and 48
// quads alike (8 warps: 9-15 s); with 20 us the 48-quad chain takes 42 s, clean (H200).
inline uint32_t clip_spin_ns() {
  static const uint32_t ns = [] {
    const char* v = std::getenv("TILEVIS_CLIP_SPIN_NS");
    if (!v) return 32u;
    char* end = nullptr;
    const unsigned long n = std::strtoul(v, &end, 10);
    if (end == v || *end != '\0' || n < 1 || n > 1000000)
      throw std::runtime_error(std::string("TILEVIS_CLIP_SPIN_NS=") + v + ": expected 1 to 1000000");
    return uint32_t(n);
  }();
  return ns;
}

struct LongShared {
  uint32_t wcnt[kLongBlock / 32], wneed[kLongBlock / 32];
  uint64_t base, poly_at, step_at, chunk_at, chunk_left, next_grab;
};

template <class P>
__device__ uint64_t long_take(const ClipArgs<P>& a, LongShared& sh, uint64_t total) {  // thread 0 only
  if (total > sh.chunk_left) {
    const uint64_t grab = tmax(total, sh.next_grab);
    sh.next_grab = tmin<uint64_t>(2 * sh.next_grab, 1024);
    const uint64_t at = bump(&a.counters[kEdgesUsed], grab, a.pool_cap);
    if (at == ~uint64_t{0}) return at;
    sh.chunk_at = at;
    sh.chunk_left = grab;
  }
  const uint64_t at = sh.chunk_at;
  sh.chunk_at += total;
  sh.chunk_left -= total;
  return at;
}

template <class P>
__device__ void clip_item_block(const ClipArgs<P>& a, uint32_t j, uint64_t* stage, LongShared& sh) {
  const uint32_t t = threadIdx.x, lane = t & 31u, warp = t / 32, n_warps = blockDim.x / 32;
  const uint32_t c = a.cand_count[j], off = a.cand_offset[j];
  const uint32_t tile = uint32_t(a.item_key[j]);
  const TileTri<P>& tt = a.tris[a.item_tri[j]];
  if (candidates_overflowed(a) || uint64_t(off) + c > a.cand_cap) return;
  for (uint32_t k = t; k < c; k += blockDim.x) {
    const uint32_t x = a.cand_edges[off + k];
    uint32_t r = 0;
    for (uint32_t m = 0; m < c; ++m) r += a.cand_edges[off + m] < x;
    a.cand_sorted[off + r] = x;
  }
  const uint64_t want = tmin<uint64_t>(piece_bound(c), uint64_t(a.slot_factor) * (c + 1));
  if (t == 0) {
    sh.chunk_at = sh.chunk_left = 0;
    sh.next_grab = 2 * kTileCap;
    sh.base = bump(&a.counters[kSlotsUsed], want, a.slot_cap);
    sh.poly_at = sh.base == ~uint64_t{0} ? sh.base : long_take(a, sh, kTileCap);
  }
  __syncthreads();  // also: cand_sorted is written
  const uint64_t base = sh.base, poly_at = sh.poly_at;
  if (poly_at == ~uint64_t{0}) {
    if (t == 0) atomic_add(&a.counters[kClipOverflow], 1);
    if (base != ~uint64_t{0})
      for (uint64_t k = t; k < want; k += blockDim.x) a.slot_item[base + k] = kNone;
    return;
  }
  uint64_t* const slots = want <= kLongStage ? stage : a.slot_poly + base;
  if (t == 0) {
    bool overflow = false;
    const uint32_t n = tile_polygon<P>(tt, a.grid.rect(tile), a.pool + poly_at, overflow);
    slots[0] = (poly_at << 32) | n;
    a.item_slot[j] = uint32_t(base);
  }
  __syncthreads();
  uint32_t count = 1, splits = 0, anomalies = 0, regularized = 0;
  bool failed = false;
  SilEdge<P> next_e = a.edges[a.cand_sorted[off]];
  for (uint32_t ci = 0; ci < c && !failed; ++ci) {
    const SilEdge<P> e = next_e;
    if (ci + 1 < c) next_e = a.edges[a.cand_sorted[off + ci + 1]];
    const uint32_t n = count;
    uint32_t appended = 0;
    for (uint32_t k0 = 0; k0 < n; k0 += blockDim.x) {
      const uint32_t k = k0 + t;
      bool flag = false;
      uint64_t sp = 0;
      Piece<P> piece;
      Sides sides;
      if (k < n) {
        sp = slots[k];
        piece.load(a.pool, sp);
        flag = piece.survives(tt, e, &sides);
      }
      const uint32_t mask = __ballot_sync(0xffffffffu, flag);
      if (lane == 0) sh.wcnt[warp] = __popc(mask);
      __syncthreads();
      uint32_t before = 0, total = 0;
      for (uint32_t w = 0; w < n_warps; ++w) {
        const uint32_t v = sh.wcnt[w];
        before += w < warp ? v : 0;
        total += v;
      }
      const uint64_t dst = uint64_t(n) + appended + before + __popc(mask & ((1u << lane) - 1u));
      const uint32_t m = uint32_t(sp);
      const bool room = dst < want;
      if (flag && !room) atomic_add(&a.counters[kReserveOverflow], 1);
      const uint32_t need = flag && room ? 2 * (m + 1) : 0;
      const uint32_t incl = WarpTeam{}.scan(need);
      if (lane == 31) sh.wneed[warp] = incl;
      __syncthreads();
      uint64_t need_before = 0, need_total = 0;
      for (uint32_t w = 0; w < n_warps; ++w) {
        const uint32_t v = sh.wneed[w];
        need_before += w < warp ? v : 0;
        need_total += v;
      }
      if (t == 0 && total) sh.step_at = long_take(a, sh, need_total);
      __syncthreads();
      const uint64_t step_at = total ? sh.step_at : 0;
      const bool fail = flag && (!room || step_at == ~uint64_t{0});
      if (flag && !fail) {
        split_piece<P>(piece.at, a.pool, step_at + need_before + incl - need, m, e.line, &sides, regularized, anomalies,
                       slots[k], slots[dst]);
        ++splits;
      }
      appended += total;
      // Every thread's slots are written before the next round reads them; sh is reused.
      if (__syncthreads_or(fail)) failed = true;
    }
    count = n + appended;
  }
  for (uint64_t k = t; k < want; k += blockDim.x) {
    if (k < count && slots != a.slot_poly + base) a.slot_poly[base + k] = slots[k];
    a.slot_item[base + k] = k < count ? j : kNone;
  }
  count_add(&a.rows[uint64_t(tile) * kTileColumns + kColClips], splits);
  count_add(&a.counters[kFloatAnomalies], anomalies);
  count_add(&a.counters[kFloatRegularized], regularized);
  if (t == 0) {
    if (failed) atomic_add(&a.counters[kClipOverflow], 1);
    a.piece_count[j] = count;
    atomic_add(&a.rows[uint64_t(tile) * kTileColumns + kColPieces], int64_t(count));
    atomic_max(&a.counters[kMaxTilePieces], uint64_t(count));
  }
  __syncthreads();  // the stage and sh are reused by the block's next item
}

// The same items as a tree of walks (the block's warps each walking one piece through the
// remaining candidates). A piece's history is its own: at candidate ci it is tested and maybe
// split, the inside part staying in its slot and the outside part starting at ci + 1; no piece's
// steps read another's. So a warp takes a piece, walks it to the end of the chain, and queues
// the outside parts it cuts off for any warp to take: the longest dependent chain is one
// piece's walk, not every candidate's round over all pieces. The walk's tests are independent
// too (a candidate the piece does not survive leaves it as it is), so the warp's lanes test 32
// candidates at once and the lowest survivor is the next split: a walk takes about
// (candidates / 32 + splits) steps. A thread per walk took 7,500 to 25,000 cycles a candidate
// (clock64 on the H100, interpenetrating's 126-candidate item: waiting threads beside one walker,
// then hundreds of diverging walkers), and that item 0.76 ms. Each
// piece records its parent and the candidate that cut it off; the slots a sequential loop gives
// (at candidate ci the new parts follow the existing pieces in their parents' slot order) are
// then assigned in candidate order, so the canonical piece order, every polygon and every
// counter are those of clip_item. Items whose reservation passes kTreeSlots use the rounds
// above (clip_item_block).
inline constexpr uint32_t kTreeSlots = 4096, kTreeCands = 1024;

struct TreeShared {
  uint32_t n_alloc, finished, head, fail;
  unsigned long long chunk_used;
  uint64_t chunk_at, chunk_size;
};

// What threads hand each other between barriers goes through shared-memory atomics (loads as
// atomic adds of 0), so the hand-off is ordered and compute-sanitizer's racecheck sees no plain
// access racing another.
__device__ inline uint32_t sh_load(uint32_t* p) { return atomicAdd(p, 0u); }
__device__ inline uint64_t sh_load(uint64_t* p) {
  return atomicAdd(reinterpret_cast<unsigned long long*>(p), 0ull);
}
__device__ inline void sh_store(uint32_t* p, uint32_t v) { atomicExch(p, v); }
__device__ inline void sh_store(uint64_t* p, uint64_t v) {
  atomicExch(reinterpret_cast<unsigned long long*>(p), static_cast<unsigned long long>(v));
}

template <class P>
__device__ uint64_t tree_edges(const ClipArgs<P>& a, TreeShared& ts, uint32_t k) {
  const uint64_t o = atomicAdd(&ts.chunk_used, static_cast<unsigned long long>(k));
  if (o + k <= ts.chunk_size) return ts.chunk_at + o;
  return bump(&a.counters[kEdgesUsed], k, a.pool_cap);  // past the block's chunk: its own bump
}

// A value of any trivially copyable type from lane `src`, word by word.
template <class T>
__device__ inline T shfl_value(const T& v, int src) {
  static_assert(sizeof(T) % 4 == 0, "whole words");
  uint32_t w[sizeof(T) / 4];
  memcpy(w, &v, sizeof(T));
  for (uint32_t k = 0; k < sizeof(T) / 4; ++k) w[k] = __shfl_sync(0xffffffffu, w[k], src);
  T r;
  memcpy(&r, w, sizeof(T));
  return r;
}

// Test 3 of one candidate (its sides `sg` of the piece's m <= 32 vertices, from crosses()) with
// the warp's lanes over the piece's edges: lane i makes edge i's chord ends (chord_ends_at),
// and the highest lane that makes each gives it, as chord_of's loop keeps the last: the same
// values, so the same answer, in about one edge's time instead of m edges'.
template <class P>
__device__ inline bool chord_survives_warp(const PEdge<P>* poly, uint32_t m, const TileTri<P>& tt,
                                           const SilEdge<P>& e, const Sides& sg, uint32_t lane) {
  typename P::V vf = poly[0].start, vs = vf;
  bool hf = false, hs = false;
  if (lane < m) {
    const uint32_t h = chord_ends_at<P>(poly, m, e.line, sg, lane, vf, vs);
    hf = (h & 1u) != 0;
    hs = (h & 2u) != 0;
  }
  const uint32_t bf = __ballot_sync(0xffffffffu, hf), bs = __ballot_sync(0xffffffffu, hs);
  // No lane: poly[0].start, which is lane 0's.
  const typename P::V first = shfl_value(vf, bf ? 31 - __clz(bf) : 0);
  const typename P::V second = shfl_value(vs, bs ? 31 - __clz(bs) : 0);
  return chord_nearer<P>(tt, e, first, second);
}

// k_clip_long's walk timed (a build with -DTILEVIS_CUDA_WALK_CLOCK=ON): lane 0 of each warp reads
// clock64() at the walk's phase boundaries and adds the cycles of each phase, and the steps and
// pieces it walked, to g_walk_clock when the tree ends; `tilevis cuda` writes the process's sums
// to stats.json (clip_walk_clock). The reads add instructions to the kernel (it ran about a third
// longer on slivers): the shares are what to read, not the absolute time. Off (the default), the
// marks compile to nothing. reports/cuda/clip_chord_h200.md is what such a build showed.
enum WalkPhase : uint32_t {
  kWalkWait,        // waiting for a piece (or for the tree's end)
  kWalkStage,       // copying it into the warp's stage
  kWalkTestNoSplit, // a step's tests where no candidate survives
  kWalkTestSplit,   // a step's tests where one does
  kWalkAllocate,    // lane `first`'s piece id and edges (a piece past kSideCap: and its one-lane split and publication)
  kWalkSplit,       // the warp's split
  kWalkPublish,     // the fence and the outside part's publication (the warp's split), the inside part handed on
  kWalkStepEnd,     // the inside part kept in the pool, the next step set up
  kWalkPieceEnd,    // the piece's final polygon recorded
  kWalkPhases
};
enum WalkCount : uint32_t { kWalkStepsNoSplit, kWalkStepsSplit, kWalkPieces, kWalkCounts };
#if defined(TILEVIS_CUDA_WALK_CLOCK)
inline constexpr uint32_t kWalkSlots = uint32_t(kWalkPhases) + uint32_t(kWalkCounts);
__device__ unsigned long long g_walk_clock[kWalkSlots];
__device__ inline unsigned long long walk_now() {
#if defined(__CUDA_ARCH__)
  return clock64();
#else
  return 0;  // the host pass of nvcc (never run there)
#endif
}
struct WalkClock {
  unsigned long long last = walk_now(), cycles[kWalkPhases] = {}, counts[kWalkCounts] = {};
  __device__ void mark(WalkPhase p) {
    const unsigned long long now = walk_now();
    cycles[p] += now - last;
    last = now;
  }
  __device__ void count(WalkCount c) { ++counts[c]; }
  __device__ void add(bool lead) const {
    if (!lead) return;
    for (uint32_t k = 0; k < kWalkPhases; ++k) atomicAdd(&g_walk_clock[k], cycles[k]);
    for (uint32_t k = 0; k < kWalkCounts; ++k) atomicAdd(&g_walk_clock[uint32_t(kWalkPhases) + k], counts[k]);
  }
};
#else
struct WalkClock {
  __device__ void mark(WalkPhase) {}
  __device__ void count(WalkCount) {}
  __device__ void add(bool) const {}
};
#endif

template <class P>
__device__ void clip_item_tree(const ClipArgs<P>& a, uint32_t j, uint64_t want, uint8_t* smem, TreeShared& ts,
                               PEdge<P> (*wstage)[2][kCopyEdges], uint32_t* sidx) {
  uint64_t* const sp = reinterpret_cast<uint64_t*>(smem);                  // by piece id: polygon (pool << 32 | n)
  uint32_t* const parent = reinterpret_cast<uint32_t*>(sp + kTreeSlots);  // by piece id
  uint32_t* const born = parent + kTreeSlots;                             // candidate that cut it off
  uint32_t* const slot_of = born + kTreeSlots;
  uint32_t* const order = slot_of + kTreeSlots;
  uint32_t* const hist = order + kTreeSlots;  // kTreeCands + 1
  const uint32_t t = threadIdx.x;
  const uint32_t c = a.cand_count[j], off = a.cand_offset[j];
  const uint32_t tile = uint32_t(a.item_key[j]);
  const TileTri<P>& tt = a.tris[a.item_tri[j]];
  for (uint32_t k = t; k < c; k += blockDim.x) {
    const uint32_t x = a.cand_edges[off + k];
    uint32_t r = 0;
    for (uint32_t m = 0; m < c; ++m) r += a.cand_edges[off + m] < x;
    sidx[r] = x;  // the tree reads its candidates from shared memory only
  }
  for (uint32_t k = t; k < want; k += blockDim.x) sp[k] = ~uint64_t{0};  // ids past want are never made
  for (uint32_t k = t; k <= c; k += blockDim.x) hist[k] = 0;
  __syncthreads();
  if (t == 0) {
    ts.n_alloc = 1;
    ts.finished = ts.head = ts.fail = 0;
    ts.chunk_used = 0;
    ts.chunk_size = 0;
    const uint64_t base = bump(&a.counters[kSlotsUsed], want, a.slot_cap);
    const uint64_t chunk = tmin<uint64_t>(16 * want + kTileCap, 1 << 16);
    const uint64_t at = base == ~uint64_t{0} ? base : bump(&a.counters[kEdgesUsed], chunk, a.pool_cap);
    if (at == ~uint64_t{0}) {
      atomic_add(&a.counters[kClipOverflow], 1);
      ts.fail = 2;  // nothing reserved: the slots (if any) are marked unused below
      ts.chunk_at = base;
    } else {
      ts.chunk_at = at + kTileCap;
      ts.chunk_size = chunk - kTileCap;
      bool overflow = false;
      const uint32_t n = tile_polygon<P>(tt, a.grid.rect(tile), a.pool + at, overflow);
      parent[0] = kNone;
      born[0] = kNone;  // walks from candidate 0
      sp[0] = (at << 32) | n;
      a.item_slot[j] = uint32_t(base);
      slot_of[0] = uint32_t(base);  // (the base, until the slots are assigned)
    }
  }
  __syncthreads();
  if (ts.fail == 2) {
    const uint64_t base = ts.chunk_at;
    if (base != ~uint64_t{0})
      for (uint64_t k = t; k < want; k += blockDim.x) a.slot_item[base + k] = kNone;
    __syncthreads();
    return;
  }
  const uint64_t base = slot_of[0];
  uint32_t splits = 0, anomalies = 0, regularized = 0;
  const uint32_t lane = t & 31u;
  WalkClock clock;
  for (;;) {
    uint32_t id = 0;
    uint64_t cur = ~uint64_t{0};
    if (lane == 0) {
      id = atomicAdd(&ts.head, 1u);
      for (;;) {  // wait for piece `id`, or for the end: every piece made has been walked
        if (id < want && (cur = sh_load(&sp[id])) != ~uint64_t{0}) break;
        const uint32_t fin = sh_load(&ts.finished);
        if (fin == sh_load(&ts.n_alloc)) break;
        __nanosleep(a.spin_ns);
      }
    }
    id = __shfl_sync(0xffffffffu, id, 0);
    cur = __shfl_sync(0xffffffffu, static_cast<unsigned long long>(cur), 0);
    clock.mark(kWalkWait);
    if (cur == ~uint64_t{0}) break;
    clock.count(kWalkPieces);
    // The walked piece lives in one of the warp's two stages in shared memory (its lanes copy
    // it there, an edge each): every lane tests it there and the splitting lane reads it there,
    // with no copy of its own. (A Piece is a copy in each lane's local memory: with it here the
    // kernel's stack frame was 848 bytes a thread in float and 2,752 in exact, 434 KB and 704 KB
    // a block, more than the L1 beside the tree's shared memory; 544 and 1,776 bytes without,
    // ptxas -v for sm_90.) A piece of more than kCopyEdges edges is read from the pool.
    PEdge<P>(*const ws)[kCopyEdges] = wstage[t / 32];
    uint32_t b = 0;
    const PEdge<P>* at = a.pool + (cur >> 32);
    // staged: the piece is ws[b]. The tests and the split then read it through ws[b] itself, so
    // that their loads are shared-memory loads (LDS); through `at`, which may point to either
    // memory, they are generic loads.
    bool staged = uint32_t(cur) <= kCopyEdges;
    if (staged) {
      if (lane < uint32_t(cur)) ws[b][lane] = at[lane];
      at = ws[b];
    }
    __syncwarp();
    clock.mark(kWalkStage);
    // The warp's lanes test the next 32 candidates at once; the lowest that the piece survives is
    // the next that splits it (those before it leave it as it is), and its lane splits it.
    uint32_t ci = (lane == 0 ? sh_load(&born[id]) : 0u);
    ci = __shfl_sync(0xffffffffu, ci, 0) + 1;  // the root's kNone + 1 = 0
    while (ci < c) {
      const uint32_t mine = ci + lane;
      const uint32_t m = uint32_t(cur);
      Sides sides;
      bool flag = false;
      if (m <= kSideCap) {
        // Tests 2 and 1 by each lane (its candidate); test 3 of the lowest candidates that pass
        // them by the whole warp, one candidate at a time (lanes over the piece's edges). Test 3
        // by each lane was most of a split step: its loop over the edges, a division or an exact
        // intersection at each end (clock64 on an H200, slivers: 9,000 cycles of a float split
        // step's 14,100, 20,600 of exact's 29,200; reports/cuda/clip_chord_h200.md).
        const PEdge<P>* const pz = staged ? ws[b] : at;
        bool cross = false;
        if (mine < c) cross = crosses<P>(pz, m, a.edges[sidx[mine]], sides);
        for (uint32_t cm = __ballot_sync(0xffffffffu, cross); cm != 0; cm &= cm - 1u) {
          const uint32_t f = uint32_t(__ffs(cm)) - 1u;
          Sides sf;
          sf.pos = __shfl_sync(0xffffffffu, sides.pos, f);
          sf.neg = __shfl_sync(0xffffffffu, sides.neg, f);
          if (chord_survives_warp<P>(pz, m, tt, a.edges[sidx[ci + f]], sf, lane)) {
            flag = lane == f;
            break;
          }
        }
      } else if (mine < c) {
        const SilEdge<P>& e = a.edges[sidx[mine]];
        flag = survives<P>(at, m, tt, e, &sides);
      }
      const uint32_t mask = __ballot_sync(0xffffffffu, flag);
      if (mask == 0) {
        clock.mark(kWalkTestNoSplit);
        clock.count(kWalkStepsNoSplit);
        ci += 32;
        continue;
      }
      clock.mark(kWalkTestSplit);
      clock.count(kWalkStepsSplit);
      const uint32_t first = uint32_t(__ffs(mask)) - 1u;
      uint64_t next = 0, e_at = 0;
      uint32_t quit = 0, child = 0;
      // The inside part, which this warp walks on with, goes to the other stage when it fits
      // (m + 1 edges at most), and to the pool after it; else to the pool alone.
      PEdge<P>* const st = m < kCopyEdges ? ws[b ^ 1u] : nullptr;
      // A piece of up to kSideCap edges is split by the whole warp (lane i makes edge i's share,
      // split_edge), exact too (measured on an H200: exact slivers 5.8-6.9 % faster than with
      // lane `first` alone, though its frame spills more); longer pieces by lane `first` alone.
      const bool by_warp = m <= kSideCap;
      // Lane `first` records the split and publishes the outside part, piece `child`, for any warp.
      const auto publish = [&](uint64_t out_slot) {
        ++splits;
        sh_store(&parent[child], id);
        sh_store(&born[child], ci + first);
        __threadfence_block();  // the outside part's edges (global) and record before its polygon word
        sh_store(&sp[child], out_slot);
      };
      if (lane == first) {
        child = sh_load(&ts.fail) ? kNone : atomicAdd(&ts.n_alloc, 1u);
        if (child == kNone) {
          quit = 1;
        } else if (child >= want || child >= kTreeSlots) {
          atomic_add(&a.counters[kReserveOverflow], 1);
          sh_store(&ts.fail, 1u);
          atomicAdd(&ts.finished, 1u);  // the id taken stands for no piece
          quit = 1;
        } else {
          e_at = tree_edges(a, ts, 2 * (m + 1));
          if (e_at == ~uint64_t{0}) {
            sh_store(&ts.fail, 1u);
            atomicAdd(&ts.finished, 1u);
            quit = 1;
          } else if (!by_warp) {
            uint64_t out_slot = 0;
            split_piece<P>(at, a.pool, e_at, m, a.edges[sidx[mine]].line, &sides, regularized, anomalies, next,
                           out_slot, st);
            publish(out_slot);
          }
        }
      }
      if (__shfl_sync(0xffffffffu, quit, first) != 0) break;  // the block failed: nothing more is kept
      clock.mark(kWalkAllocate);
      if (by_warp) {
        // Lane `first`'s sides (regularized as split() does, the same in every lane), its line,
        // and each edge's share placed by prefix sums of the counts: split_sides' polygons.
        e_at = __shfl_sync(0xffffffffu, static_cast<unsigned long long>(e_at), first);
        Sides sg;
        sg.pos = __shfl_sync(0xffffffffu, sides.pos, first);
        sg.neg = __shfl_sync(0xffffffffu, sides.neg, first);
        bool regular = false;
        if constexpr (!P::kExact) regular = sg.regularize(m);  // exact sides are a convex polygon's
        const typename P::Line& line = a.edges[sidx[ci + first]].line;
        const uint32_t cnt = lane < m ? split_counts(m, sg, lane) : 0u;
        const uint32_t incl = WarpTeam{}.scan(cnt);  // both halves: no carry, 2 x 32 < 2^16
        const uint32_t total = __shfl_sync(0xffffffffu, incl, 31);
        const uint32_t cap = m + 1;
        if (lane < m) {
          PEdge<P>* const in_e = st ? st : a.pool + e_at;
          PEdge<P>* const out_e = a.pool + e_at + m + 1;
          if (staged)
            split_edge_placed<P>(ws[b], m, line, line.flipped(), sg, lane, incl - cnt, in_e, out_e, cap);
          else
            split_edge_placed<P>(at, m, line, line.flipped(), sg, lane, incl - cnt, in_e, out_e, cap);
        }
        const uint32_t n_in = total & 0xffffu, n_out = total >> 16;
        next = (e_at << 32) | tmin(n_in, cap);
        clock.mark(kWalkSplit);
        __threadfence_block();  // each lane's edges (global) before the warp's barrier
        __syncwarp();  // every lane's edges are written before the outside part is published
        if (lane == first) {
          regularized += regular ? 1 : 0;
          if (n_in > cap || n_out > cap) ++anomalies;  // only float arithmetic can break convexity
          publish(((e_at + m + 1) << 32) | tmin(n_out, cap));
        }
      }
      cur = __shfl_sync(0xffffffffu, static_cast<unsigned long long>(next), first);
      clock.mark(kWalkPublish);
      __syncwarp();  // the inside part's edges, written by lane `first`, before the lanes read them
      if (st) {
        // The pool keeps the part (its final polygon, if no later candidate splits it); the
        // walk goes on from the stage.
        if (lane < uint32_t(cur)) a.pool[(cur >> 32) + lane] = st[lane];
        b ^= 1u;
        at = st;
        staged = true;
      } else {
        at = a.pool + (cur >> 32);
        staged = false;
      }
      ci += first + 1;
      clock.mark(kWalkStepEnd);
    }
    __syncwarp();  // the stages are read before the warp's next piece is copied in
    if (lane == 0) {
      sh_store(&sp[id], cur);  // the piece's final polygon
      __threadfence_block();
      atomicAdd(&ts.finished, 1u);
    }
    clock.mark(kWalkPieceEnd);
  }
  clock.add(lane == 0);
  __syncthreads();
  const bool failed = ts.fail != 0;
  const uint32_t count = failed ? 0 : ts.n_alloc;
  if (!failed) {
    // Slots: the pieces cut off at candidate ci follow all earlier pieces, in their parents'
    // slot order (a parent was made before ci, so its slot is known when ci's turn comes).
    for (uint32_t k = 1 + t; k < count; k += blockDim.x) atomicAdd(&hist[born[k]], 1u);
    __syncthreads();
    if (t == 0) {
      uint32_t run = 0;
      for (uint32_t k = 0; k <= c; ++k) {
        const uint32_t h = hist[k];
        hist[k] = run;
        run += h;
      }
    }
    __syncthreads();
    for (uint32_t k = 1 + t; k < count; k += blockDim.x) order[atomicAdd(&hist[born[k]], 1u)] = k;
    __syncthreads();
    if (t == 0) {
      slot_of[0] = 0;
      uint32_t next = 1, g0 = 0;
      for (uint32_t ci = 0; ci < c; ++ci) {
        const uint32_t g1 = hist[ci];  // after the scatter: the end of ci's group
        for (uint32_t x = g0 + 1; x < g1; ++x) {  // insertion sort by the parent's slot
          const uint32_t v = order[x], key = slot_of[parent[v]];
          uint32_t y = x;
          while (y > g0 && slot_of[parent[order[y - 1]]] > key) {
            order[y] = order[y - 1];
            --y;
          }
          order[y] = v;
        }
        for (uint32_t x = g0; x < g1; ++x) slot_of[order[x]] = next++;
        g0 = g1;
      }
    }
    __syncthreads();
    for (uint32_t k = t; k < count; k += blockDim.x) a.slot_poly[base + slot_of[k]] = sp[k];
  }
  for (uint64_t k = t; k < want; k += blockDim.x) a.slot_item[base + k] = k < count ? j : kNone;
  count_add(&a.rows[uint64_t(tile) * kTileColumns + kColClips], splits);
  count_add(&a.counters[kFloatAnomalies], anomalies);
  count_add(&a.counters[kFloatRegularized], regularized);
  if (t == 0) {
    if (failed) atomic_add(&a.counters[kClipOverflow], 1);
    a.piece_count[j] = count;
    atomic_add(&a.rows[uint64_t(tile) * kTileColumns + kColPieces], int64_t(count));
    atomic_max(&a.counters[kMaxTilePieces], uint64_t(count));
  }
  __syncthreads();  // the shared arrays are reused by the block's next item
}

inline constexpr size_t kTreeSmem = size_t(kTreeSlots) * (8 + 4 * 4) + (kTreeCands + 1) * 4;
static_assert(kTreeSmem >= kLongStage * 8, "the rounds' stage lives in the same memory");

template <class P>
__global__ void __launch_bounds__(kLongBlockOf<P>, 1) k_clip_long(ClipArgs<P> a, const uint64_t* count, uint64_t cap) {
  TV_KERNEL_WAIT();
  extern __shared__ __align__(16) uint8_t smem[];
  __shared__ LongShared sh;
  __shared__ TreeShared ts;
  __shared__ PEdge<P> wstage[kLongBlockOf<P> / 32][2][kCopyEdges];
  __shared__ uint32_t sidx[kTreeCands];
  __shared__ uint32_t taken;
  const uint64_t n = *count < cap ? *count : cap;
  // A block takes the next listed item when it is done with its last: the few long items are
  // the stage, and a fixed stride over the blocks (item w to block w % blocks) left blocks with
  // two or three of them beside idle ones.
  for (;;) {
    if (threadIdx.x == 0) {
      const uint64_t w = atomic_add(&a.counters[kLongTaken], uint64_t{1});
      taken = w < n ? a.long_items[w] : kNone;
    }
    __syncthreads();
    const uint32_t j = taken;
    __syncthreads();  // every thread has read it before thread 0 takes the next
    if (j == kNone) break;
    const uint32_t c = a.cand_count[j];
    if (candidates_overflowed(a) || uint64_t(a.cand_offset[j]) + c > a.cand_cap) continue;
    const uint64_t want = tmin<uint64_t>(piece_bound(c), uint64_t(a.slot_factor) * (c + 1));
    if (want <= kTreeSlots && c <= kTreeCands) clip_item_tree<P>(a, j, want, smem, ts, wstage, sidx);
    else clip_item_block<P>(a, j, reinterpret_cast<uint64_t*>(smem), sh);
  }
}

template <class P>
TV_HD void clip_item_host(const ClipArgs<P>& a, uint64_t w) {
  clip_item<P>(a, w, HostTeam{}, nullptr);
}

template <class P>
__global__ void k_cand_scatter(ClipArgs<P> a, const uint64_t* count, uint64_t cap) {
  TV_KERNEL_WAIT();
  const uint64_t n = *count < cap ? *count : cap;
  TV_GRID_LOOP(i, n) cand_scatter<P>(a, i);
}
inline constexpr uint32_t kClipBlock = 128;

template <class P>
__global__ void k_clip_items(ClipArgs<P> a, const uint64_t* count, uint64_t cap) {
  TV_KERNEL_WAIT();
  const uint64_t n = *count < cap ? *count : cap;
  const uint64_t warp = (uint64_t(blockIdx.x) * blockDim.x + threadIdx.x) / 32;
  const uint64_t warps = uint64_t(gridDim.x) * blockDim.x / 32;
  __shared__ uint64_t stage[kClipBlock / 32][kStageSlots];
  // Many items (million: 45,960 items with candidates at 1080p; the next scene, dragon_bunnies,
  // 9,376; host emulation counts): those of fewer than kSmallChain candidates first, a thread
  // each (the sequential loop, as on the host), their slots and first edges reserved with one
  // atomic per warp; then the others, a warp each.
  // Fewer items (every other scene at 1080p): a warp each, as the longest chains set the
  // stage's length there (measured: a thread per small item made glass's clipping 0.161 ->
  // 0.197 ms at 4 candidates, 0.297 at 8, first or after the warps' items).
  const bool threads_first = n >= kSmallMinItems;
  const uint32_t long_c = long_chain(n);  // n is clip_item_count(a), as cand_scatter counted
  const uint32_t lane = threadIdx.x & 31u;
  if (threads_first && !candidates_overflowed(a)) {  // (overflowed: clip_item returns at once)
    const uint64_t threads = uint64_t(gridDim.x) * blockDim.x;
    for (uint64_t w0 = uint64_t(blockIdx.x) * blockDim.x + (threadIdx.x & ~31u); w0 < n; w0 += threads) {
      const uint64_t w = w0 + lane;
      uint32_t c = kNone;
      if (w < n) {
        const uint32_t j = a.clip_items[w];
        c = a.cand_count[j];
        if (uint64_t(a.cand_offset[j]) + c > a.cand_cap) c = kNone;  // clip_item returns at once
      }
      const bool mine = c < kSmallChain && c < long_c;
      const uint64_t want = mine ? tmin<uint64_t>(piece_bound(c), uint64_t(a.slot_factor) * (c + 1)) : 0;
      uint64_t incl = want;
      for (uint32_t d = 1; d < 32; d <<= 1) {
        const uint64_t t = __shfl_up_sync(0xffffffffu, static_cast<unsigned long long>(incl), d);
        if (lane >= d) incl += t;
      }
      const uint64_t total = __shfl_sync(0xffffffffu, static_cast<unsigned long long>(incl), 31);
      if (total == 0) continue;
      uint64_t at = 0;
      if (lane == 0) at = atomic_add(&a.counters[kSlotsUsed], total);
      at = __shfl_sync(0xffffffffu, static_cast<unsigned long long>(at), 0);
      ClipReserve pre{true, at + incl - want, 0};
      if (pre.base + want > a.slot_cap) pre.base = ~uint64_t{0};
      const uint32_t takes = __ballot_sync(0xffffffffu, mine && pre.base != ~uint64_t{0});
      uint64_t at2 = 0;
      if (lane == 0 && takes) at2 = atomic_add(&a.counters[kEdgesUsed], kFirstGrab * __popc(takes));
      at2 = __shfl_sync(0xffffffffu, static_cast<unsigned long long>(at2), 0);
      pre.chunk_at = at2 + kFirstGrab * __popc(takes & ((1u << lane) - 1u));
      if (pre.chunk_at + kFirstGrab > a.pool_cap) pre.chunk_at = ~uint64_t{0};
      if (mine) clip_item<P>(a, w, HostTeam{}, nullptr, pre);
    }
  }
  for (uint64_t w = warp; w < n; w += warps) {
    const uint32_t c = a.cand_count[a.clip_items[w]];
    if ((!threads_first || c >= kSmallChain) && c < long_c) clip_item<P>(a, w, WarpTeam{}, stage[threadIdx.x / 32]);
  }
}

}  // namespace

template <class P>
bool stage_clip(Pipeline<P>& p) {
  Exec& ex = p.ex;
  const uint64_t ni = p.n_items;
  ClipArgs<P> a{};
  a.tris = p.tris.get();
  a.edges = p.edges.get();
  a.item_key = p.item_key_sorted.get();
  a.item_tri = p.item_tri_sorted.get();
  a.grid = p.grid;
  a.rows = p.tile_rows.get();
  a.cands = p.cands.get();
  a.cand_count = p.cand_count.get();
  a.cand_cursor = p.cand_cursor.get();  // zeroed by cull
  a.cand_offset = p.cand_offset.need(ni + 1);
  a.cand_edges = p.cand_edges.need(p.caps.candidates);
  a.cand_sorted = p.cand_scratch.need(p.caps.candidates);
  a.cand_cap = p.caps.candidates;
  a.deep_cap = p.caps.deep_pairs;
  a.clip_items = p.clip_items.get();  // listed by cull
  a.long_items = p.long_items.need(ni + 1);
  a.item_slot = p.item_slot.need(ni + 1);
  a.slot_poly = p.slot_poly.need(p.caps.clip_slots);
  a.slot_item = p.slot_item.need(p.caps.clip_slots);
  a.slot_cap = p.caps.clip_slots;
  a.pool = p.clip_edges.need(p.caps.clip_edges);
  a.pool_cap = p.caps.clip_edges;
  a.piece_count = p.piece_count.get();
  a.counters = p.counters.get();
  a.slot_factor = p.caps.slot_factor;
  a.n_items = ni;
  a.spin_ns = clip_spin_ns();

  ex.exclusive_scan(a.cand_count, p.cand_offset.get(), p.N(kSzItems, ni), ni);
  ex.launch_dyn(k_cand_scatter<P>, cand_scatter<P>, p.counters.get() + kCandidates, p.caps.candidates, a);
  if (ex.where == Where::cpu) {
    ex.launch_dyn(k_clip_items<P>, clip_item_host<P>, p.counters.get() + kClipItems, ni, a);
  } else {
    // The long chains on side stream 1 (idle from cull to the fold), launched first so that
    // their blocks start at once; the others beside them.
    ex.branch(1);
    ++ex.queued;
    static const bool smem_set = [] {
      TV_CUDA(cudaFuncSetAttribute(k_clip_long<P>, cudaFuncAttributeMaxDynamicSharedMemorySize, int(kTreeSmem)));
      return true;
    }();
    (void)smem_set;
    k_clip_long<P><<<ex.grid_blocks / 2, kLongBlockOf<P>, kTreeSmem, ex.stream>>>(a, p.counters.get() + kLongItems, ni);
    TV_CUDA(cudaGetLastError());
    ex.on_main();
    ++ex.queued;
    k_clip_items<P><<<ex.grid_blocks * 2, kClipBlock, 0, ex.stream>>>(a, p.counters.get() + kClipItems, ni);
    TV_CUDA(cudaGetLastError());
    ex.merge(1);
  }

  // Device-sized: the overflow counters are checked once the frame has ended (pools_fit).
  if (p.dev) return true;
  // sync: the overflow counters (those before kFloatAnomalies: only setup, cull and clip, all
  // finished here, write them; the unclipped pieces' occlusion may be running beside).
  uint64_t c[kFloatAnomalies];
  ex.download(c, p.counters.get(), sizeof(c));
  return pools_fit(p, c);
}

std::vector<std::pair<std::string, uint64_t>> walk_clock_totals() {
  std::vector<std::pair<std::string, uint64_t>> out;
#if defined(TILEVIS_CUDA_WALK_CLOCK)
  unsigned long long g[kWalkSlots] = {};
  if (cudaMemcpyFromSymbol(g, g_walk_clock, sizeof(g)) != cudaSuccess) return out;
  static const char* const names[kWalkSlots] = {
      "wait_cycles",  "stage_cycles",  "test_no_split_cycles", "test_split_cycles",  "allocate_cycles",
      "split_cycles", "publish_cycles", "step_end_cycles",     "piece_end_cycles",   "steps_no_split",
      "steps_split",  "pieces"};
  for (uint32_t k = 0; k < kWalkSlots; ++k) out.emplace_back(names[k], uint64_t(g[k]));
#endif
  return out;
}

template <class P>
bool pools_fit(Pipeline<P>& p, const uint64_t* c) {
  bool ok = true;
  Capacities& caps = p.caps;
  auto grow = [&](uint64_t& cap, uint64_t used) {
    if (used > cap) {
      cap = tmax(2 * cap, used + used / 2);
      ok = false;
    }
  };
  grow(caps.deep_pairs, c[kDeepPairs]);
  grow(caps.candidates, c[kCandidates]);
  if (c[kClipOverflow]) {
    ok = false;
    grow(caps.clip_slots, c[kSlotsUsed]);
    grow(caps.clip_edges, c[kEdgesUsed]);
    if (c[kReserveOverflow]) caps.slot_factor *= 4;  // bounded: reservations never exceed piece_bound(c)
  }
  if (caps.clip_edges >= (uint64_t{1} << 32)) throw std::runtime_error("cuda: clipping needs more than 2^32 polygon edges");
  return ok;
}

template bool stage_clip<ExactP>(Pipeline<ExactP>&);
template bool stage_clip<FloatP>(Pipeline<FloatP>&);
template bool pools_fit<ExactP>(Pipeline<ExactP>&, const uint64_t*);
template bool pools_fit<FloatP>(Pipeline<FloatP>&, const uint64_t*);

}  // namespace tilevis::cuda
