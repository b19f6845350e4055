// Z-buffer rasterisers of a trace frame (cuda_ref.h, run_cuda_zbuffer): the baselines the
// analytic pipeline is measured against on the same GPU.
//
// tiled (exact, equal to the z-buffer truth), in the manner of CudaRaster (Laine & Karras 2011):
// binned, tile-local, hierarchical coverage, and no size read on the host between its stages.
//  1. vertices: a thread per vertex: inside every clip plane?, and if so its snapped position
//     (setup.cuh: the pipeline's own arithmetic, so a vertex snaps as in setup.cu).
//  2. triangles: a thread per trace triangle: exact facing (a double filter, else setup.cuh's
//     expansion), clipping where a vertex is outside (setup.cuh), the front opaque setup
//     triangles appended as 48-byte records. A triangle whose pixel box spans at most
//     kInlineTiles tiles of 64 samples (8x8 pixels at 1 sample) bins itself: per tile, the
//     exact edge test over the tile's rectangle, then a rank in the tile's list (atomic count)
//     and a (tile, rank, record) pair. A larger one appends a unit per coarse bin of 8x8 tiles.
//  3. units: a warp per (big triangle, coarse bin): the coarse bin's rectangle first (one edge
//     test for 64 tiles), then its tiles, a lane per two, as in 2.
//  4. an exclusive scan of the tiles' counts; a thread per pair puts its record at offset + rank.
//  5. raster: a warp per tile, a lane per two samples: the tile's records staged 32 at a time
//     in shared memory, edge functions (int64, top-left rule) and the exact depth test per
//     sample, the nearest kept in registers. The order of a tile's list does not matter: at
//     equal depth the earlier setup triangle (trace triangle, then fan position) wins, as in
//     the truth (zbuffer.h: strictly nearer replaces). A list longer than kSegment is split:
//     the tile's warp takes the first kSegment records and queues the rest as helper items; a
//     warp per helper merges its nearest into the tile's per-sample owner word by CAS (the
//     order is total, so the merge is order-free), and the last helper of a tile writes its ids.
// Per sample the depth numerator N = alpha x + beta y + gamma (area z) is exact: with depth
// bits D <= 26 every plane is "small" (geom/depth.h): |N| < 2^(51+D), |N area| < 2^(100+D) <=
// 2^126: I128. Every buffer is sized from capacities learned by earlier frames; device counters
// keep counting past them and the host reads them once, after the frame: an overflow grows the
// buffers and the frame runs again.
//
// naive: a thread per trace triangle, from clip space in float, snapped to the sub-pixel grid,
// top-left coverage, float depth, one 64-bit atomicMin of (depth bits << 32 | id) per sample.
#include <algorithm>
#include <chrono>
#include <cstring>

#include "setup.cuh"

namespace tilevis::cuda {
namespace {

constexpr uint32_t kTileSamples = 64;  // a fine tile: a warp, two samples a lane
constexpr uint32_t kCoarse = 8;        // a coarse bin: 8x8 tiles (a big triangle's unit of work)
constexpr uint32_t kInlineTiles = 16;  // at most this many tiles in its box: a triangle bins itself
constexpr uint32_t kRasterBlock = 128;
constexpr uint32_t kWarpsPerBlock = kRasterBlock / 32;

// Device counters (ZArgs::ctr).
// Device counters (ZArgs::ctr): kZRecords counts the clipped pool's records (a trace triangle's
// own record is slot t), then kZSpread words of the drawn triangles' count (spread: no word is
// shared by every thread), then the tiles' counts (uint32), all in one allocation, one memset.
// kZBig: big triangles << 40 | their units (one atomic takes both, so a big triangle's first
// unit grows with its index and a unit finds its triangle by binary search); kZTiles: the tiles
// with a non-empty list (the first entry of a tile appends it).
enum ZCounter : uint32_t { kZRecords, kZPairs, kZBig, kZHelpers, kZRare, kZTiles, kZCounterCount };
constexpr uint32_t kZUnitBits = 40;
constexpr uint64_t kZUnitMask = (uint64_t{1} << kZUnitBits) - 1;
constexpr uint32_t kZSpread = 32;
constexpr uint32_t kZCounterWords = kZCounterCount + kZSpread;

// A front opaque setup triangle (48 bytes): its snapped vertices and its setup order,
// trace triangle << 3 | fan position (a fan has at most 7 triangles).
struct alignas(16) ZRec {
  Vtx v[3];
  uint32_t order;
  uint32_t pad[3];
};

// A record as the raster tests it (edges with inside > 0, the top-left rule's owned edges,
// the depth plane, the pixel box), staged in shared memory.
struct alignas(16) ZDer {
  I128 gamma;
  int64_t c[3];
  int64_t alpha, beta, area;
  int32_t a[3], b[3];
  int32_t px0, py0, px1, py1;
  uint32_t order, owns, slot;
  uint32_t full;  // staged for one tile: the tile lies inside all three edges (every sample covered)
};

struct ZArgs {
  FrameDev f;
  double gx, gy;
  const float4* vertices;
  const uint32_t* indices;
  const uint32_t* tri_draw;
  const DrawInfo* draws;
  const uint32_t* sample_xy;
  int4* vtx;            // per vertex: snapped x, y, z, 1 when inside every plane
  ZRec* rec;
  uint64_t* ctr;        // ZCounter
  uint32_t* tile_count; // per tile: its list's length
  uint32_t* tile_off;   // exclusive scan of tile_count (n_tiles + 1)
  uint64_t* pair;       // tile << 32 | rank
  uint32_t* pair_rec;
  uint32_t* big_slot;   // per big triangle: its record, and its first unit (increasing)
  uint32_t* big_u0;
  uint32_t* tiles;      // the tiles with a non-empty list (kZTiles of them)
  uint32_t* sorted;     // the tiles' lists, one after another
  uint64_t* helper;     // tile << 32 | first entry
  uint32_t* owner;      // per sample of a split tile: the nearest record so far (kNone: none)
  uint32_t* tile_need;  // per split tile: its helpers, and how many are done
  uint32_t* tile_done;
  int32_t* ids;
  uint32_t* rare;       // trace triangles left to k_zb_rare (clipped, or facing not settled by the filter)
  uint64_t rec_cap, pair_cap, unit_cap, big_cap, helper_cap, rare_cap;
  uint64_t n_samples;
  uint32_t width, height, samples, sb, tw, th, tiles_x, tiles_y, coarse_x, segment;
  uint32_t ls, ltw, lth;  // log2 of samples, tw, th (powers of two: shifts, no division per sample)
};

TV_HD inline bool overflowed(const ZArgs& a) {
  return a.ctr[kZRecords] > a.rec_cap || a.ctr[kZPairs] > a.pair_cap || (a.ctr[kZBig] & kZUnitMask) > a.unit_cap ||
         (a.ctr[kZBig] >> kZUnitBits) > a.big_cap ||
         a.ctr[kZHelpers] > a.helper_cap || a.ctr[kZRare] > a.rare_cap;
}

// ---- 1, 2: setup and binning -----------------------------------------------------------

TV_HD void zb_vertex(const ZArgs& a, uint64_t i) { a.vtx[i] = snapped_vertex(a.f, a.gx, a.gy, a.vertices, i); }

struct Edges {
  ILine e[3];  // inside: eval > 0, or 0 on an owned edge
};

TV_HD inline Edges edges_of(const Vtx& v0, const Vtx& v1, const Vtx& v2) {
  Edges r;
  if (orient2d(v0.xy(), v1.xy(), v2.xy()) > 0) {
    r.e[0] = ILine::through(v0.xy(), v1.xy());
    r.e[1] = ILine::through(v1.xy(), v2.xy());
    r.e[2] = ILine::through(v2.xy(), v0.xy());
  } else {
    r.e[0] = ILine::through(v0.xy(), v2.xy());
    r.e[1] = ILine::through(v2.xy(), v1.xy());
    r.e[2] = ILine::through(v1.xy(), v0.xy());
  }
  return r;
}

// The closed rectangle of tile (tx, ty) in sub-pixel units: every sample of the tile lies in it.
TV_HD inline Rect tile_rect(const ZArgs& a, int64_t tx0, int64_t ty0, int64_t tx1, int64_t ty1) {
  return {int32_t(tx0 << (a.ltw + a.sb)), int32_t(ty0 << (a.lth + a.sb)), int32_t((tx1 + 1) << (a.ltw + a.sb)),
          int32_t((ty1 + 1) << (a.lth + a.sb))};
}

// Hierarchical coverage: no sample of r can be inside when an edge is negative over all of r.
TV_HD inline bool may_cover(const Edges& t, const Rect& r) {
  return t.e[0].max_over(r) >= 0 && t.e[1].max_over(r) >= 0 && t.e[2].max_over(r) >= 0;
}

// The pixel box of a triangle cut at the screen, in tiles; false when it leaves the screen.
struct TileBox {
  int64_t px0, py0, px1, py1, tx0, ty0, tx1, ty1;
};
TV_HD inline bool tile_box(const ZArgs& a, const Vtx& v0, const Vtx& v1, const Vtx& v2, TileBox& b) {
  b.px0 = tmax<int64_t>(0, tmin(tmin(v0.x, v1.x), v2.x) >> a.sb);
  b.py0 = tmax<int64_t>(0, tmin(tmin(v0.y, v1.y), v2.y) >> a.sb);
  b.px1 = tmin<int64_t>(int64_t(a.width) - 1, tmax(tmax(v0.x, v1.x), v2.x) >> a.sb);
  b.py1 = tmin<int64_t>(int64_t(a.height) - 1, tmax(tmax(v0.y, v1.y), v2.y) >> a.sb);
  if (b.px0 > b.px1 || b.py0 > b.py1) return false;
  b.tx0 = b.px0 >> a.ltw;  // px0, py0 >= 0 here
  b.ty0 = b.py0 >> a.lth;
  b.tx1 = b.px1 >> a.ltw;
  b.ty1 = b.py1 >> a.lth;
  return true;
}

// A rank in the tile's list: the lanes of a warp that bin into the same tile take their ranks
// with one atomic (neighbouring triangles of a mesh share tiles).
TV_HD inline uint32_t tile_rank(const ZArgs& a, uint32_t tile) {
#if defined(__CUDA_ARCH__)
  const unsigned peers = __match_any_sync(__activemask(), tile);
  const int leader = __ffs(peers) - 1;
  const unsigned lane = threadIdx.x & 31u;
  uint32_t base = 0;
  if (int(lane) == leader) base = atomicAdd(&a.tile_count[tile], uint32_t(__popc(peers)));
  base = __shfl_sync(peers, base, leader);
  const uint32_t rank = base + uint32_t(__popc(peers & ((1u << lane) - 1u)));
#else
  const uint32_t rank = a.tile_count[tile]++;
#endif
  if (rank == 0) a.tiles[bump_one(&a.ctr[kZTiles], ~uint64_t{0})] = tile;  // at most every tile once
  return rank;
}

TV_HD inline void put_pair(const ZArgs& a, uint64_t p, uint32_t tile, uint32_t slot) {
  const uint32_t rank = tile_rank(a, tile);
  if (p >= a.pair_cap) return;  // the frame runs again with more room
  a.pair[p] = uint64_t(tile) << 32 | rank;
  a.pair_rec[p] = slot;
}



// A small triangle's tiles: those of its box (at most kInlineTiles) that the exact edge test
// keeps, as bits of the box in row-major order.
struct Inline {
  uint32_t slot = kNone, mask = 0, drawn = 0;
  int32_t tx0 = 0, ty0 = 0, w = 1, h = 1;
  TV_HD uint32_t count() const { return popc(mask); }
  // Pairs p, p + 1, ... for the kept tiles in row-major order (no division by the box's width).
  TV_HD void put(const ZArgs& a, uint64_t p) const;
};

TV_HD inline void Inline::put(const ZArgs& a, uint64_t p) const {
  uint32_t bit = 0;
  for (int32_t y = 0; y < h && (mask >> bit) != 0; ++y)
    for (int32_t x = 0; x < w; ++x, ++bit)
      if ((mask >> bit) & 1u) put_pair(a, p++, uint32_t(ty0 + y) * a.tiles_x + uint32_t(tx0 + x), slot);
}

// The counters every thread adds to: one of kZSpread words picked by the block (on the host:
// the first), summed after the frame.
TV_HD inline uint64_t* spread(const ZArgs& a, uint32_t which) {
#if defined(__CUDA_ARCH__)
  return a.ctr + kZCounterCount + which * kZSpread + (blockIdx.x % kZSpread);
#else
  return a.ctr + kZCounterCount + which * kZSpread;
#endif
}

// One setup triangle (fan position k of trace triangle t) into record `slot` (kNone: take one
// from the clipped pool), if front-facing (facing > 0 is the trace triangle's; the snapped
// triangle must turn the same way: negative area, y down). A small one returns its tiles in
// `in` (its pairs are the caller's); a big one queues a unit per coarse bin; `now`: emit a small
// one's pairs here (the clipped path, rare).
TV_HD inline void zb_triangle(const ZArgs& a, uint64_t t, uint32_t k, const Vtx& v0, const Vtx& v1, const Vtx& v2,
                              uint32_t slot, Inline& in, bool now) {
  if (!(orient2d(v0.xy(), v1.xy(), v2.xy()) < 0)) return;
  if (now) count_add(spread(a, 0), 1);  // else the caller counts in.drawn
  in.drawn = 1;
  TileBox b;
  if (!tile_box(a, v0, v1, v2, b)) return;
  if (slot == kNone) {
    const uint64_t c = bump(&a.ctr[kZRecords], 1, a.rec_cap);
    if (c == ~uint64_t{0}) return;
    slot = uint32_t(a.f.n_triangles + c);
  }
  ZRec r;
  r.v[0] = v0;
  r.v[1] = v1;
  r.v[2] = v2;
  r.order = uint32_t(t) << 3 | k;
  r.pad[0] = r.pad[1] = r.pad[2] = 0;
  const uint64_t n_tiles = uint64_t(b.tx1 - b.tx0 + 1) * uint64_t(b.ty1 - b.ty0 + 1);
  if (n_tiles > kInlineTiles) {
    const int64_t cx0 = b.tx0 / kCoarse, cx1 = b.tx1 / kCoarse, cy0 = b.ty0 / kCoarse, cy1 = b.ty1 / kCoarse;
    const uint64_t n_units = uint64_t(cx1 - cx0 + 1) * uint64_t(cy1 - cy0 + 1);
    a.rec[slot] = r;
    const uint64_t old = atomic_add(&a.ctr[kZBig], uint64_t{1} << kZUnitBits | n_units);
    const uint64_t e = old >> kZUnitBits, u0 = old & kZUnitMask;
    if (e >= a.big_cap || u0 + n_units > a.unit_cap) return;  // the frame runs again with more room
    a.big_slot[e] = slot;
    a.big_u0[e] = uint32_t(u0);
    return;
  }
  a.rec[slot] = r;
  const Edges e = edges_of(v0, v1, v2);
  in.slot = slot;
  in.tx0 = int32_t(b.tx0);
  in.ty0 = int32_t(b.ty0);
  in.w = int32_t(b.tx1 - b.tx0 + 1);
  in.h = int32_t(b.ty1 - b.ty0 + 1);
  in.mask = 0;
  uint32_t bit = 0;
  for (int64_t ty = b.ty0; ty <= b.ty1; ++ty)
    for (int64_t tx = b.tx0; tx <= b.tx1; ++tx, ++bit)
      if (n_tiles == 1 || may_cover(e, tile_rect(a, tx, ty, tx, ty))) in.mask |= 1u << bit;
  if (now) {
    const uint64_t p0 = bump(&a.ctr[kZPairs], in.count(), a.pair_cap);
    in.put(a, p0 == ~uint64_t{0} ? a.pair_cap : p0);
    in.mask = 0;
  }
}

TV_HD inline Vtx vtx_of(const int4& q) { return {q.x, q.y, uint32_t(q.z)}; }

TV_HD __noinline__ void zb_clipped(const ZArgs& a, uint64_t t) {
  ClipV poly[kMaxClipVerts];
  bool cut = false;
  const uint32_t n = clip_triangle(a.vertices, a.indices, a.gx, a.gy, t, poly, cut);
  Vtx sv[kMaxClipVerts];
  for (uint32_t k = 0; k < n; ++k) sv[k] = snap(a.f, a.gx, a.gy, poly[k]);
  for (uint32_t k = 1; k + 1 < n; ++k) {
    Inline unused;
    zb_triangle(a, t, k - 1, sv[0], sv[k], sv[k + 1], kNone, unused, true);
  }
}

// A trace triangle: its record is slot t unless clipping cuts it into a fan (the clipped pool).
// `defer`: a triangle that needs clipping or the exact facing goes to the rare list instead, so
// the common path carries neither the clipper's nor the expansion's arrays (k_zb_rare).
TV_HD Inline zb_trace_triangle(const ZArgs& a, uint64_t t, bool defer) {
  Inline in;
  if (!a.draws[a.tri_draw[t]].opaque) return in;
  const uint32_t i0 = a.indices[3 * t], i1 = a.indices[3 * t + 1], i2 = a.indices[3 * t + 2];
  const int4 q0 = a.vtx[i0], q1 = a.vtx[i1], q2 = a.vtx[i2];
  int facing = facing_filter(a.vertices[i0], a.vertices[i1], a.vertices[i2]);
  if (facing < 0) return in;  // back-facing
  if (defer && (facing == 0 || !(q0.w & q1.w & q2.w))) {
    const uint64_t r = bump_one(&a.ctr[kZRare], a.rare_cap);
    if (r != ~uint64_t{0}) a.rare[r] = uint32_t(t);
    return in;
  }
  if (facing == 0) facing = clip_facing(a.vertices[i0], a.vertices[i1], a.vertices[i2]);
  if (facing <= 0) return in;  // back-facing or edge-on
  if (q0.w & q1.w & q2.w) zb_triangle(a, t, 0, vtx_of(q0), vtx_of(q1), vtx_of(q2), uint32_t(t), in, false);
  else zb_clipped(a, t);
  return in;
}

// A deferred trace triangle: as zb_trace_triangle, its pairs emitted here.
TV_HD void zb_rare(const ZArgs& a, uint64_t r) {
  const uint64_t t = a.rare[r];
  const Inline in = zb_trace_triangle(a, t, false);
  if (in.drawn) count_add(spread(a, 0), 1);
  const uint64_t p0 = bump(&a.ctr[kZPairs], in.count(), a.pair_cap);
  in.put(a, p0 == ~uint64_t{0} ? a.pair_cap : p0);
}

// Host emulation: the pairs as they come.
void zb_trace_triangle_host(const ZArgs& a, uint64_t t) {
  const Inline in = zb_trace_triangle(a, t, false);
  if (in.drawn) count_add(spread(a, 0), 1);
  const uint64_t p0 = bump(&a.ctr[kZPairs], in.count(), a.pair_cap);
  in.put(a, p0 == ~uint64_t{0} ? a.pair_cap : p0);
}

#if defined(__CUDACC__)
// A block of 256 trace triangles at a time: the block's pairs take one atomic (a scan over the
// block gives each thread its first), so no counter is shared by every thread of the frame.
constexpr uint32_t kTriBlock = 256;
__global__ void __launch_bounds__(kTriBlock, 3) k_zb_triangles(ZArgs a, uint64_t n) {
  TV_KERNEL_WAIT();
  __shared__ uint32_t warp_total[kTriBlock / 32];
  __shared__ uint64_t block_base;
  const uint32_t lane = threadIdx.x & 31u, w = threadIdx.x / 32;
  for (uint64_t base = uint64_t(blockIdx.x) * kTriBlock; base < n; base += uint64_t(gridDim.x) * kTriBlock) {
    const uint64_t t = base + threadIdx.x;
    const Inline in = t < n ? zb_trace_triangle(a, t, true) : Inline{};
    const uint32_t c = in.count();
    uint32_t incl = c;
    for (uint32_t d = 1; d < 32; d <<= 1) {
      const uint32_t v = __shfl_up_sync(0xffffffffu, incl, d);
      if (lane >= d) incl += v;
    }
    if (lane == 31) warp_total[w] = incl;
    const int drawn = __syncthreads_count(in.drawn);
    if (threadIdx.x == 0 && drawn) atomicAdd(reinterpret_cast<unsigned long long*>(spread(a, 0)), uint64_t(drawn));
    if (threadIdx.x == 0) {
      uint32_t sum = 0;
      for (uint32_t k = 0; k < kTriBlock / 32; ++k) {
        const uint32_t v = warp_total[k];
        warp_total[k] = sum;
        sum += v;
      }
      block_base = sum ? atomicAdd(reinterpret_cast<unsigned long long*>(&a.ctr[kZPairs]), sum) : 0;
    }
    __syncthreads();
    in.put(a, block_base + warp_total[w] + incl - c);
    __syncthreads();
  }
}
#endif

// A big triangle's unit: the coarse bin's tiles inside its box, lane, lane + lanes, ...
TV_HD void zb_unit(const ZArgs& a, uint64_t u, uint32_t lane, uint32_t lanes) {
  uint64_t lo = 0, hi = a.ctr[kZBig] >> kZUnitBits;  // the last big triangle whose first unit <= u
  while (hi - lo > 1) {
    const uint64_t mid = (lo + hi) / 2;
    if (a.big_u0[mid] <= u) lo = mid;
    else hi = mid;
  }
  const uint32_t slot = a.big_slot[lo];
  const ZRec& r = a.rec[slot];
  TileBox b{};
  tile_box(a, r.v[0], r.v[1], r.v[2], b);
  const int64_t cx0 = b.tx0 / kCoarse, cx1 = b.tx1 / kCoarse, cy0 = b.ty0 / kCoarse;
  const uint32_t k = uint32_t(u - a.big_u0[lo]), cw = uint32_t(cx1 - cx0 + 1);
  const int64_t cx = cx0 + int64_t(k % cw), cy = cy0 + int64_t(k / cw);
  const int64_t tx0 = tmax(b.tx0, cx * kCoarse), tx1 = tmin(b.tx1, cx * kCoarse + kCoarse - 1);
  const int64_t ty0 = tmax(b.ty0, cy * kCoarse), ty1 = tmin(b.ty1, cy * kCoarse + kCoarse - 1);
  const Edges e = edges_of(r.v[0], r.v[1], r.v[2]);
  if (!may_cover(e, tile_rect(a, tx0, ty0, tx1, ty1))) return;
  const int64_t w = tx1 - tx0 + 1, n = w * (ty1 - ty0 + 1);
  for (int64_t i = lane; i < n; i += lanes) {
    const int64_t tx = tx0 + i % w, ty = ty0 + i / w;
    if (may_cover(e, tile_rect(a, tx, ty, tx, ty))) {
      const uint64_t p = bump_one(&a.ctr[kZPairs], a.pair_cap);
      put_pair(a, p == ~uint64_t{0} ? a.pair_cap : p, uint32_t(ty * a.tiles_x + tx), slot);
    }
  }
}

// ---- 4: the tiles' lists ------------------------------------------------------------------

TV_HD void zb_scatter(const ZArgs& a, uint64_t i) {
  const uint64_t p = a.pair[i];
  a.sorted[a.tile_off[p >> 32] + uint32_t(p)] = a.pair_rec[i];
}

// ---- 5: raster ------------------------------------------------------------------------------

TV_HD inline ZDer derive(const ZRec& r, uint32_t slot, uint32_t sb) {
  const Vtx &v0 = r.v[0], &v1 = r.v[1], &v2 = r.v[2];
  const Edges e = edges_of(v0, v1, v2);
  ZDer d;
  d.owns = 0;
  for (int k = 0; k < 3; ++k) {
    d.a[k] = int32_t(e.e[k].a);
    d.b[k] = int32_t(e.e[k].b);
    d.c[k] = e.e[k].c;
    d.owns |= e.e[k].owns_boundary() ? 1u << k : 0u;
  }
  const exact::IntPlane q = exact::int_plane_of(v0, v1, v2);
  d.alpha = q.alpha;
  d.beta = q.beta;
  d.gamma = q.gamma;
  d.area = q.area;
  // The pixel box (not cut at the screen: samples outside the screen are never written).
  d.px0 = tmin(tmin(v0.x, v1.x), v2.x) >> sb;
  d.py0 = tmin(tmin(v0.y, v1.y), v2.y) >> sb;
  d.px1 = tmax(tmax(v0.x, v1.x), v2.x) >> sb;
  d.py1 = tmax(tmax(v0.y, v1.y), v2.y) >> sb;
  d.order = r.order;
  d.slot = slot;
  d.full = 0;
  return d;
}

// Per sample: the nearest covering record so far.
struct Owner {
  I128 n = 0;
  int64_t area = 0;
  uint32_t order = kNone, slot = kNone;
};

// Nearer than o: smaller depth n / area (areas > 0), or equal depth and earlier in setup order.
TV_HD inline bool nearer(const I128& n, int64_t area, uint32_t order, const Owner& o) {
  if (o.order == kNone) return true;
  const I128 l = n * o.area, r = o.n * area;
  return l < r || (l == r && order < o.order);
}

// A sample of a tile: u = pixel_in_tile * samples + k.
struct ZSample {
  int32_t px, py;
  int64_t x, y;
  uint64_t out;
  bool inside;
};

TV_HD inline ZSample sample_of(const ZArgs& a, uint64_t tile, uint32_t u) {
  const uint32_t k = u & (a.samples - 1), p = u >> a.ls;
  const uint32_t ty = uint32_t(tile) / a.tiles_x, tx = uint32_t(tile) - ty * a.tiles_x;
  ZSample s;
  s.px = int32_t((tx << a.ltw) + (p & (a.tw - 1)));
  s.py = int32_t((ty << a.lth) + (p >> a.ltw));
  s.inside = s.px < int32_t(a.width) && s.py < int32_t(a.height);
  const uint32_t sxy = a.sample_xy[k];
  s.x = (int64_t(s.px) << a.sb) + (sxy & 0xffffu);
  s.y = (int64_t(s.py) << a.sb) + (sxy >> 16);
  s.out = (uint64_t(s.py) * a.width + uint64_t(s.px)) * a.samples + k;
  return s;
}

TV_HD inline void test_sample(const ZDer& d, const ZSample& s, Owner& o) {
  if (!d.full) {
    if (s.px < d.px0 || s.px > d.px1 || s.py < d.py0 || s.py > d.py1) return;
    for (int k = 0; k < 3; ++k) {
      const int64_t e = int64_t(d.a[k]) * s.x + int64_t(d.b[k]) * s.y + d.c[k];
      if (e < 0 || (e == 0 && !((d.owns >> k) & 1u))) return;
    }
  }
  const I128 n = I128{d.alpha} * s.x + I128{d.beta} * s.y + d.gamma;
  if (nearer(n, d.area, d.order, o)) {
    o.n = n;
    o.area = d.area;
    o.order = d.order;
    o.slot = d.slot;
  }
}

TV_HD inline int32_t id_of(uint32_t order) { return order == kNone ? -1 : int32_t(order >> 3); }

// Merges a helper's nearest into the tile's owner word of the sample: replaced while nearer (a
// total order: the result does not depend on which helper comes first).
TV_HD inline void merge_owner(const ZArgs& a, const ZSample& s, const Owner& o) {
  if (o.slot == kNone) return;
  uint32_t cur = a.owner[s.out];
  while (true) {
    if (cur != kNone) {
      const ZDer c = derive(a.rec[cur], cur, a.sb);
      const I128 n = I128{c.alpha} * s.x + I128{c.beta} * s.y + c.gamma;
      const Owner co{n, c.area, c.order, cur};
      if (!nearer(o.n, o.area, o.order, co)) return;
    }
    const uint32_t seen = atomic_cas(&a.owner[s.out], cur, o.slot);
    if (seen == cur) return;
    cur = seen;
  }
}

// After a tile's list: ids written (the whole list done), or the owner words and its helpers
// queued (first: the first entry after this warp's part).
TV_HD inline void queue_helpers(const ZArgs& a, uint64_t tile, uint64_t first, uint64_t end) {
  const uint64_t n = (end - first + a.segment - 1) / a.segment;
  a.tile_need[tile] = uint32_t(n);
  a.tile_done[tile] = 0;
  const uint64_t h0 = bump(&a.ctr[kZHelpers], n, a.helper_cap);
  if (h0 == ~uint64_t{0}) return;
  for (uint64_t h = 0; h < n; ++h) a.helper[h0 + h] = tile << 32 | (first + h * a.segment);
}

// Host emulation: a tile's part [begin, end) for every sample of the tile.
void host_part(const ZArgs& a, uint64_t tile, uint64_t begin, uint64_t end, Owner* o) {
  std::vector<ZDer> ds;
  for (uint64_t j = begin; j < end; ++j) {
    const uint32_t slot = a.sorted[j];
    ds.push_back(derive(a.rec[slot], slot, a.sb));
  }
  for (uint32_t u = 0; u < kTileSamples; ++u) {
    const ZSample s = sample_of(a, tile, u);
    for (const ZDer& d : ds) test_sample(d, s, o[u]);
  }
}

void zb_tile_host(const ZArgs& a, uint64_t tile) {
  const uint64_t begin = a.tile_off[tile], end = a.tile_off[tile + 1];
  const uint64_t cut = tmin<uint64_t>(end, begin + a.segment);
  Owner o[kTileSamples];
  host_part(a, tile, begin, cut, o);
  for (uint32_t u = 0; u < kTileSamples; ++u) {
    const ZSample s = sample_of(a, tile, u);
    if (!s.inside) continue;
    if (cut < end) a.owner[s.out] = o[u].slot;
    else a.ids[s.out] = id_of(o[u].order);
  }
  if (cut < end) queue_helpers(a, tile, cut, end);
}

void zb_helper_host(const ZArgs& a, uint64_t h) {
  const uint64_t tile = a.helper[h] >> 32, begin = uint32_t(a.helper[h]);
  const uint64_t end = tmin<uint64_t>(a.tile_off[tile + 1], begin + a.segment);
  Owner o[kTileSamples];
  host_part(a, tile, begin, end, o);
  for (uint32_t u = 0; u < kTileSamples; ++u) {
    const ZSample s = sample_of(a, tile, u);
    if (s.inside) merge_owner(a, s, o[u]);
  }
  if (++a.tile_done[tile] != a.tile_need[tile]) return;
  for (uint32_t u = 0; u < kTileSamples; ++u) {
    const ZSample s = sample_of(a, tile, u);
    if (s.inside) a.ids[s.out] = a.owner[s.out] == kNone ? -1 : id_of(a.rec[a.owner[s.out]].order);
  }
}

#if defined(__CUDACC__)
// A sample's nearest so far, in a warp's shared memory (Owner without initialisers).
struct alignas(16) OwnerS {
  I128 n;
  int64_t area;
  uint32_t order, slot;
};

// Whether the tile at pixel (x0, y0) lies strictly inside all three edges (every sample covered).
__device__ inline bool tile_inside(const ZArgs& a, const ZDer& d, int32_t x0, int32_t y0) {
  const int32_t tx1 = x0 + int32_t(a.tw) - 1, ty1 = y0 + int32_t(a.th) - 1;
  if (d.px0 > x0 || d.px1 < tx1 || d.py0 > y0 || d.py1 < ty1) return false;
  const int64_t rx0 = int64_t(x0) << a.sb, ry0 = int64_t(y0) << a.sb;
  const int64_t rx1 = int64_t(tx1 + 1) << a.sb, ry1 = int64_t(ty1 + 1) << a.sb;
  return rect_inside_edges(d.a, d.b, d.c, rx0, ry0, rx1, ry1);
}

// The samples of a tile that a record covers, as bits u = pixel_in_tile * samples + k, by the
// same tests as test_sample; a tile inside all three edges is covered whole (`screen`: its
// samples on the screen). Only the record's box is visited.
__device__ inline uint64_t coverage(const ZArgs& a, const ZDer& d, int32_t x0, int32_t y0, uint64_t screen) {
  const int32_t tx1 = x0 + int32_t(a.tw) - 1, ty1 = y0 + int32_t(a.th) - 1;
  if (tile_inside(a, d, x0, y0)) return screen;
  const int32_t px0 = tmax(d.px0, x0), px1 = tmin(tmin(d.px1, tx1), int32_t(a.width) - 1);
  const int32_t py0 = tmax(d.py0, y0), py1 = tmin(tmin(d.py1, ty1), int32_t(a.height) - 1);
  uint64_t m = 0;
  for (int32_t py = py0; py <= py1; ++py)
    for (int32_t px = px0; px <= px1; ++px)
      for (uint32_t k = 0; k < a.samples; ++k) {
        const uint32_t sxy = a.sample_xy[k];
        const int64_t x = (int64_t(px) << a.sb) + (sxy & 0xffffu), y = (int64_t(py) << a.sb) + (sxy >> 16);
        bool in = true;
        for (int e = 0; e < 3; ++e) {
          const int64_t v = int64_t(d.a[e]) * x + int64_t(d.b[e]) * y + d.c[e];
          in &= v > 0 || (v == 0 && ((d.owns >> e) & 1u));
        }
        if (in) m |= uint64_t{1} << ((((uint32_t(py - y0) << a.ltw) + uint32_t(px - x0)) << a.ls) + k);
      }
  return m;
}

// A warp's part [begin, end) of a tile's list, in the manner of CudaRaster's fine raster: a
// lane per record. A small record (at most kFragMax samples of its box in the tile) is
// rastered fragment-parallel: its coverage over the tile's samples, then rounds in which every
// lane takes its next covered sample and lanes meeting at one sample take turns. The large ones
// are staged in shared memory and every lane tests its two samples against each (a large
// triangle's fragments would otherwise fall on one lane). The nearest per sample lives in shared
// memory; the order does not matter (nearer is a total order).
constexpr uint32_t kFragMax = 16;
__device__ inline void warp_part(const ZArgs& a, uint64_t tile, uint64_t begin, uint64_t end, OwnerS* sm,
                                 ZDer* stage, uint64_t screen, const ZSample& s0, const ZSample& s1) {
  const uint32_t lane = threadIdx.x & 31u;
  const uint32_t ty = uint32_t(tile) / a.tiles_x, tx = uint32_t(tile) - ty * a.tiles_x;
  const int32_t x0 = int32_t(tx << a.ltw), y0 = int32_t(ty << a.lth);
  const int32_t tx1 = tmin(x0 + int32_t(a.tw), int32_t(a.width)) - 1, ty1 = tmin(y0 + int32_t(a.th), int32_t(a.height)) - 1;
  for (uint64_t c = begin; c < end; c += 32) {
    const uint32_t m = uint32_t(tmin<uint64_t>(32, end - c));
    ZDer d{};
    uint64_t cov = 0;
    bool large = false;
    if (lane < m) {
      const uint32_t slot = a.sorted[c + lane];
      d = derive(a.rec[slot], slot, a.sb);
      const int32_t nx = tmin(d.px1, tx1) - tmax(d.px0, x0) + 1, ny = tmin(d.py1, ty1) - tmax(d.py0, y0) + 1;
      if (nx > 0 && ny > 0) {
        if ((uint32_t(nx * ny) << a.ls) <= kFragMax) {
          cov = coverage(a, d, x0, y0, screen);
        } else {
          large = true;
          d.full = tile_inside(a, d, x0, y0) ? 1u : 0u;
        }
      }
    }
    const unsigned lm = __ballot_sync(0xffffffffu, large);
    if (large) stage[__popc(lm & ((1u << lane) - 1u))] = d;
    warp_fragment_rounds<I128>(
        cov,
        [&](uint32_t u) {
          const uint32_t k = u & (a.samples - 1), p = u >> a.ls;
          const uint32_t sxy = a.sample_xy[k];
          const int64_t x = (int64_t(x0 + int32_t(p & (a.tw - 1))) << a.sb) + (sxy & 0xffffu);
          const int64_t y = (int64_t(y0 + int32_t(p >> a.ltw)) << a.sb) + (sxy >> 16);
          return I128{d.alpha} * x + I128{d.beta} * y + d.gamma;
        },
        [&](uint32_t u, const I128& n) {
          OwnerS& o = sm[u];
          const Owner cur{o.n, o.area, o.order, o.slot};
          if (nearer(n, d.area, d.order, cur)) {
            o.n = n;
            o.area = d.area;
            o.order = d.order;
            o.slot = d.slot;
          }
        });
    __syncwarp();  // the staged records before phase B reads them (also when there was no round)
    if (lm) {
      Owner o0{sm[lane].n, sm[lane].area, sm[lane].order, sm[lane].slot};
      Owner o1{sm[lane + 32].n, sm[lane + 32].area, sm[lane + 32].order, sm[lane + 32].slot};
      for (uint32_t j = 0, nl = uint32_t(__popc(lm)); j < nl; ++j) {
        test_sample(stage[j], s0, o0);
        test_sample(stage[j], s1, o1);
      }
      sm[lane] = {o0.n, o0.area, o0.order, o0.slot};
      sm[lane + 32] = {o1.n, o1.area, o1.order, o1.slot};
      __syncwarp();
    }
  }
}

__device__ inline void sm_clear(OwnerS* sm) {
  const uint32_t lane = threadIdx.x & 31u;
  for (uint32_t u : {lane, lane + 32}) {
    sm[u].order = kNone;
    sm[u].slot = kNone;
    sm[u].n = 0;
    sm[u].area = 0;
  }
  __syncwarp();
}

// A warp per tile of the non-empty list (the id buffer was set to -1 beside the vertices).
__global__ void __launch_bounds__(kRasterBlock, 5) k_zb_tiles(ZArgs a) {
  TV_KERNEL_WAIT();
  __shared__ OwnerS sm[kWarpsPerBlock][kTileSamples];
  __shared__ ZDer stage[kWarpsPerBlock][32];
  if (overflowed(a)) return;
  const uint32_t lane = threadIdx.x & 31u, w = threadIdx.x / 32;
  const uint64_t n = a.ctr[kZTiles];
  for (uint64_t i = uint64_t(blockIdx.x) * kWarpsPerBlock + w; i < n; i += uint64_t(gridDim.x) * kWarpsPerBlock) {
    const uint64_t tile = a.tiles[i];
    const uint64_t begin = a.tile_off[tile], end = a.tile_off[tile + 1];
    const uint64_t cut = tmin<uint64_t>(end, begin + a.segment);
    const ZSample s0 = sample_of(a, tile, lane), s1 = sample_of(a, tile, lane + 32);
    const uint64_t screen =
        uint64_t(__ballot_sync(0xffffffffu, s0.inside)) | uint64_t(__ballot_sync(0xffffffffu, s1.inside)) << 32;
    sm_clear(sm[w]);
    warp_part(a, tile, begin, cut, sm[w], stage[w], screen, s0, s1);
    const OwnerS &o0 = sm[w][lane], &o1 = sm[w][lane + 32];
    if (cut == end) {
      if (s0.inside) a.ids[s0.out] = id_of(o0.order);
      if (s1.inside) a.ids[s1.out] = id_of(o1.order);
    } else {
      if (s0.inside) a.owner[s0.out] = o0.slot;
      if (s1.inside) a.owner[s1.out] = o1.slot;
      if (lane == 0) queue_helpers(a, tile, cut, end);
    }
    __syncwarp();
  }
}

__global__ void __launch_bounds__(kRasterBlock, 5) k_zb_helpers(ZArgs a) {
  TV_KERNEL_WAIT();
  __shared__ OwnerS sm[kWarpsPerBlock][kTileSamples];
  __shared__ ZDer stage[kWarpsPerBlock][32];
  if (overflowed(a)) return;
  const uint32_t lane = threadIdx.x & 31u, w = threadIdx.x / 32;
  const uint64_t n = a.ctr[kZHelpers];
  for (uint64_t h = uint64_t(blockIdx.x) * kWarpsPerBlock + w; h < n; h += uint64_t(gridDim.x) * kWarpsPerBlock) {
    const uint64_t tile = a.helper[h] >> 32, begin = uint32_t(a.helper[h]);
    const uint64_t end = tmin<uint64_t>(a.tile_off[tile + 1], begin + a.segment);
    const ZSample s0 = sample_of(a, tile, lane), s1 = sample_of(a, tile, lane + 32);
    const uint64_t screen =
        uint64_t(__ballot_sync(0xffffffffu, s0.inside)) | uint64_t(__ballot_sync(0xffffffffu, s1.inside)) << 32;
    sm_clear(sm[w]);
    warp_part(a, tile, begin, end, sm[w], stage[w], screen, s0, s1);
    const OwnerS &o0 = sm[w][lane], &o1 = sm[w][lane + 32];
    if (s0.inside) merge_owner(a, s0, Owner{o0.n, o0.area, o0.order, o0.slot});
    if (s1.inside) merge_owner(a, s1, Owner{o1.n, o1.area, o1.order, o1.slot});
    __threadfence();
    __syncwarp();
    uint32_t last = 0;
    if (lane == 0) last = atomicAdd(&a.tile_done[tile], 1u) + 1 == a.tile_need[tile];
    if (!__shfl_sync(0xffffffffu, last, 0)) continue;
    __threadfence();
    for (const ZSample* s : {&s0, &s1}) {
      if (!s->inside) continue;
      const uint32_t ow = atomicAdd(&a.owner[s->out], 0u);  // after every helper's merge
      a.ids[s->out] = ow == kNone ? -1 : id_of(a.rec[ow].order);
    }
  }
}

__global__ void k_zb_rare(ZArgs a) {
  TV_KERNEL_WAIT();
  if (a.ctr[kZRare] > a.rare_cap) return;
  TV_GRID_LOOP(r, a.ctr[kZRare]) zb_rare(a, r);
}

__global__ void k_zb_units(ZArgs a) {
  TV_KERNEL_WAIT();
  if (overflowed(a)) return;
  const uint64_t n = a.ctr[kZBig] & kZUnitMask;
  TV_WARP_LOOP(u, n) zb_unit(a, u, threadIdx.x & 31u, 32);
}

__global__ void k_zb_scatter(ZArgs a) {
  TV_KERNEL_WAIT();
  if (overflowed(a)) return;
  TV_GRID_LOOP(i, a.ctr[kZPairs]) zb_scatter(a, i);
}
#endif

// The vertices, and the id buffer set to -1 (every sample no tile list touches keeps it).
__global__ void k_zb_vertex(ZArgs a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) zb_vertex(a, i);
  int4* ids4 = reinterpret_cast<int4*>(a.ids);
  TV_GRID_LOOP(j, a.n_samples / 4) ids4[j] = make_int4(-1, -1, -1, -1);
  TV_GRID_LOOP(k, a.n_samples % 4) a.ids[a.n_samples / 4 * 4 + k] = -1;
}

// ---- naive ----------------------------------------------------------------------------------

struct NaiveArgs {
  FrameDev f;
  const float4* vertices;
  const uint32_t* indices;
  const uint32_t* tri_draw;
  const DrawInfo* draws;
  const uint32_t* sample_xy;
  unsigned long long* zkey;  // per sample: float depth bits << 32 | id; all ones: empty
  int32_t* ids;
  unsigned long long* counters;  // 0: drawn, 1: skipped
};

TV_HD void naive_triangle(const NaiveArgs& a, uint64_t t) {
  if (!a.draws[a.tri_draw[t]].opaque) return;
  const float half_w = 0.5f * float(a.f.width), half_h = 0.5f * float(a.f.height);
  const float sub = float(1u << a.f.subpixel_bits);
  const float range = a.f.depth_far - a.f.depth_near;
  int64_t x[3], y[3];
  float z[3];
  for (int k = 0; k < 3; ++k) {
    const float4 v = a.vertices[a.indices[3 * t + k]];
    const float inv = 1.0f / v.w;
    const float xw = (v.x * inv + 1.0f) * half_w, yw = (1.0f - v.y * inv) * half_h;
    if (!(v.w > 0.0f) || !(xw > -32768.0f && xw < 32768.0f && yw > -32768.0f && yw < 32768.0f)) {
#if defined(__CUDA_ARCH__)
      atomicAdd(&a.counters[1], 1ull);
#else
      ++a.counters[1];
#endif
      return;
    }
    x[k] = int64_t(rintf(xw * sub));
    y[k] = int64_t(rintf(yw * sub));
    z[k] = a.f.depth_near + range * 0.5f * (v.z * inv + 1.0f);
  }
  // Front-facing: negative doubled area in window space (y down), as setup.cu decides it.
  const int64_t area = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
  if (area >= 0) return;
  // Counter-clockwise in orient2d's sense: swap 1 and 2 so that every edge function is >= 0 inside.
  const int64_t X[3] = {x[0], x[2], x[1]}, Y[3] = {y[0], y[2], y[1]};
  const float Z[3] = {z[0], z[2], z[1]};
  int64_t ea[3], eb[3], ec[3], floor[3];
  for (int k = 0; k < 3; ++k) {
    const int j = (k + 1) % 3;
    ea[k] = Y[k] - Y[j];
    eb[k] = X[j] - X[k];
    ec[k] = X[k] * Y[j] - Y[k] * X[j];
    floor[k] = (ea[k] > 0 || (ea[k] == 0 && eb[k] > 0)) ? -1 : 0;
  }
#if defined(__CUDA_ARCH__)
  atomicAdd(&a.counters[0], 1ull);
#else
  ++a.counters[0];
#endif
  const uint32_t sb = a.f.subpixel_bits;
  const int64_t px0 = tmax<int64_t>(0, tmin(tmin(X[0], X[1]), X[2]) >> sb);
  const int64_t px1 = tmin<int64_t>(int64_t(a.f.width) - 1, tmax(tmax(X[0], X[1]), X[2]) >> sb);
  const int64_t py0 = tmax<int64_t>(0, tmin(tmin(Y[0], Y[1]), Y[2]) >> sb);
  const int64_t py1 = tmin<int64_t>(int64_t(a.f.height) - 1, tmax(tmax(Y[0], Y[1]), Y[2]) >> sb);
  const float inv_area = 1.0f / float(-area);
  for (int64_t py = py0; py <= py1; ++py)
    for (int64_t px = px0; px <= px1; ++px)
      for (uint32_t k = 0; k < a.f.n_samples; ++k) {
        const uint32_t sxy = a.sample_xy[k];
        const int64_t sx = (px << sb) + (sxy & 0xffffu), sy = (py << sb) + (sxy >> 16);
        int64_t e[3];
        bool in = true;
        for (int i = 0; i < 3; ++i) {
          e[i] = ea[i] * sx + eb[i] * sy + ec[i];
          in &= e[i] > floor[i];
        }
        if (!in) continue;
        // e[i] is the doubled area opposite vertex i + 2 (mod 3).
        const float d = (float(e[1]) * Z[0] + float(e[2]) * Z[1] + float(e[0]) * Z[2]) * inv_area;
        const float dz = d < 0.0f ? 0.0f : d;
        uint32_t bits;
        memcpy(&bits, &dz, 4);
        const unsigned long long key = (static_cast<unsigned long long>(bits) << 32) | t;
        unsigned long long* slot = &a.zkey[(uint64_t(py) * a.f.width + uint64_t(px)) * a.f.n_samples + k];
#if defined(__CUDA_ARCH__)
        atomicMin(slot, key);
#else
        if (key < *slot) *slot = key;
#endif
      }
}

TV_HD void naive_resolve(const NaiveArgs& a, uint64_t k) {
  const unsigned long long key = a.zkey[k];
  a.ids[k] = key == ~0ull ? -1 : int32_t(uint32_t(key));
}

__global__ void k_naive_triangle(NaiveArgs a, uint64_t n) { TV_KERNEL_WAIT(); TV_GRID_LOOP(i, n) naive_triangle(a, i); }
__global__ void k_naive_resolve(NaiveArgs a, uint64_t n) { TV_KERNEL_WAIT(); TV_GRID_LOOP(i, n) naive_resolve(a, i); }

double median_of(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Marks on the stream: CUDA events on the GPU, the host clock on the cpu path.
class Marks {
 public:
  explicit Marks(Exec& ex, int n) : m_ex(ex), m_ev(size_t(n)), m_host(size_t(n)) {
    if (ex.where == Where::gpu)
      for (auto& e : m_ev) TV_CUDA(cudaEventCreate(&e));
  }
  ~Marks() {
    for (auto e : m_ev)
      if (e) cudaEventDestroy(e);
  }
  void mark(int k) {
    if (m_ex.where == Where::gpu) TV_CUDA(cudaEventRecord(m_ev[size_t(k)], m_ex.main_stream));
    else m_host[size_t(k)] = std::chrono::steady_clock::now();
  }
  double ms(int a, int b) {
    if (m_ex.where == Where::gpu) {
      TV_CUDA(cudaEventSynchronize(m_ev[size_t(b)]));
      float t = 0;
      TV_CUDA(cudaEventElapsedTime(&t, m_ev[size_t(a)], m_ev[size_t(b)]));
      return t;
    }
    return std::chrono::duration<double, std::milli>(m_host[size_t(b)] - m_host[size_t(a)]).count();
  }

 private:
  Exec& m_ex;
  std::vector<cudaEvent_t> m_ev;
  std::vector<std::chrono::steady_clock::time_point> m_host;
};

struct ZBufs {
  Buf<int4> vtx;
  Buf<ZRec> rec;
  Buf<uint64_t> ctr;  // kZCounterWords counters, then the tiles' counts (uint32)
  Buf<uint32_t> tile_off, pair_rec, big_slot, big_u0, tiles, sorted, owner, tile_need, tile_done, rare;
  Buf<uint64_t> pair, helper;
  Buf<unsigned long long> zkey, ncount;
  explicit ZBufs(Exec& e) {
    for (auto* b : {&tile_off, &pair_rec, &big_slot, &big_u0, &tiles, &sorted, &owner, &tile_need, &tile_done, &rare})
      b->bind(&e);
    for (auto* b : {&ctr, &pair, &helper}) b->bind(&e);
    vtx.bind(&e);
    rec.bind(&e);
    zkey.bind(&e);
    ncount.bind(&e);
  }
};

// Capacities the frames so far needed (grow-only).
struct ZCaps {
  uint64_t rec = 0, pair = 0, unit = 0, big = 0, helper = 0, rare = 0;
};

}  // namespace

ZBufferResult run_cuda_zbuffer(const trace::Frame& frame, const CudaConfig& cfg, ZBufferKind kind) {
  const uint32_t S = uint32_t(frame.samples.size());
  if (S == 0 || S > 16 || (S & (S - 1)) != 0) throw std::runtime_error("cuda zbuffer: samples must be 1, 2, 4, 8 or 16");
  if (cfg.depth_bits < 1 || cfg.depth_bits > 26) throw std::runtime_error("cuda zbuffer: depth bits must be 1..26");
  if (cfg.device == Device::gpu) {
    std::string why;
    if (!cuda_available(&why)) throw std::runtime_error("cuda: no usable GPU (" + why + ")");
  }
  Exec ex(cfg.device == Device::cpu ? Where::cpu : Where::gpu, cfg.shuffle_cpu);
  Pipeline<ExactP> p(ex);
  p.cfg = cfg;
  upload_frame_common(ex, frame, cfg.depth_bits, p.f, p.draws_host, p.vertices, p.indices, p.tri_draw, p.draws,
                      p.sample_xy);
  if (p.f.n_triangles >= (uint64_t{1} << 29)) throw std::runtime_error("cuda zbuffer: 2^29 trace triangles or more");
  ex.sync();
  ZBufs z(ex);
  ZBufferResult r;
  r.device_name = ex.device_name;
  r.width = p.f.width;
  r.height = p.f.height;
  r.samples = S;
  const uint64_t n_samples = uint64_t(r.width) * r.height * S;
  int32_t* ids = p.ids.need(n_samples + 1);
  // Tiles of 64 samples: 8x8 pixels at 1 sample, 8x4 at 2, 4x4 at 4, 4x2 at 8, 2x2 at 16.
  uint32_t tw = 8, th = 8;
  for (uint32_t s = S; s > 1; s >>= 1) (tw > th ? tw : th) >>= 1;
  r.bin_w = tw;
  r.bin_h = th;
  const uint32_t tiles_x = (r.width + tw - 1) / tw, tiles_y = (r.height + th - 1) / th;
  const uint64_t n_tiles = uint64_t(tiles_x) * tiles_y;
  const uint64_t n_tri = p.f.n_triangles;
  // Tests start from tiny capacities (grow and retry) and short list segments (helpers).
  const bool tiny = cfg.initial_pool != 0;
  ZCaps caps;
  caps.rec = tiny ? cfg.initial_pool : n_tri / 8 + 1024;  // the clipped pool (records n_tri, ...)
  caps.pair = tiny ? cfg.initial_pool : 2 * n_tri + n_tiles + 4096;
  caps.unit = tiny ? cfg.initial_pool : n_tri / 8 + 1024;
  caps.big = tiny ? cfg.initial_pool : n_tri / 64 + 256;
  caps.helper = tiny ? cfg.initial_pool : caps.pair / 64 + 1024;
  caps.rare = tiny ? cfg.initial_pool : n_tri / 16 + 1024;
  const uint32_t segment = tiny ? 8 : 256;

  const bool naive = kind == ZBufferKind::naive;
  const int n_marks = naive ? 2 : 4;
  Marks marks(ex, n_marks);
  std::vector<std::vector<double>> stage(size_t(n_marks - 1));
  std::vector<double> total;
  uint64_t got[kZCounterWords] = {};
  // One frame; false when a pool overflowed (capacities grown: run it again).
  auto once = [&]() -> bool {
    ex.syncs = 0;
    marks.mark(0);
    if (naive) {
      NaiveArgs na{p.f, p.vertices.get(), p.indices.get(), p.tri_draw.get(), p.draws.get(), p.sample_xy.get(),
                   z.zkey.need(n_samples + 1), ids, z.ncount.need(2)};
      ex.fill_ones(na.zkey, n_samples * 8);
      ex.zero(na.counters, 16);
      ex.launch(k_naive_triangle, naive_triangle, p.f.n_triangles, na);
      ex.launch(k_naive_resolve, naive_resolve, n_samples, na);
      marks.mark(1);
      return true;
    }
    if (caps.pair >= 0xffffffffull || n_tri + caps.rec >= 0xffffffffull || caps.unit >= 0xffffffffull)
      throw std::runtime_error("cuda zbuffer: 2^32 bin entries or more");
    ZArgs a{};
    a.f = p.f;
    a.gx = guard_band(p.f.width);
    a.gy = guard_band(p.f.height);
    a.vertices = p.vertices.get();
    a.indices = p.indices.get();
    a.tri_draw = p.tri_draw.get();
    a.draws = p.draws.get();
    a.sample_xy = p.sample_xy.get();
    a.vtx = z.vtx.need(p.f.n_vertices + 1);
    a.rec = z.rec.need(n_tri + caps.rec + 1);
    a.ctr = z.ctr.need(kZCounterWords + (n_tiles + 1) / 2 + 1);
    a.tile_count = reinterpret_cast<uint32_t*>(a.ctr + kZCounterWords);
    a.tile_off = z.tile_off.need(n_tiles + 1);
    a.pair = z.pair.need(caps.pair + 1);
    a.pair_rec = z.pair_rec.need(caps.pair + 1);
    a.big_slot = z.big_slot.need(caps.big + 1);
    a.big_u0 = z.big_u0.need(caps.big + 1);
    a.tiles = z.tiles.need(n_tiles + 1);
    a.n_samples = n_samples;
    a.sorted = z.sorted.need(caps.pair + 1);
    a.helper = z.helper.need(caps.helper + 1);
    a.rare = z.rare.need(caps.rare + 1);
    a.owner = z.owner.need(n_samples + 1);
    a.tile_need = z.tile_need.need(n_tiles + 1);
    a.tile_done = z.tile_done.need(n_tiles + 1);
    a.ids = ids;
    a.rec_cap = caps.rec;
    a.pair_cap = caps.pair;
    a.unit_cap = caps.unit;
    a.big_cap = caps.big;
    a.helper_cap = caps.helper;
    a.rare_cap = caps.rare;
    a.width = r.width;
    a.height = r.height;
    a.samples = S;
    a.sb = p.f.subpixel_bits;
    a.tw = tw;
    a.th = th;
    a.ls = bits_for(S) - 1;
    a.ltw = bits_for(tw) - 1;
    a.lth = bits_for(th) - 1;
    a.tiles_x = tiles_x;
    a.tiles_y = tiles_y;
    a.segment = segment;
    const bool gpu = ex.where == Where::gpu;
    ex.zero(a.ctr, (kZCounterWords + (n_tiles + 1) / 2 + 1) * 8);
    ++ex.queued;
    if (gpu) {
      const uint64_t want = (std::max<uint64_t>(p.f.n_vertices, n_samples / 4) + 255) / 256;
      k_zb_vertex<<<uint32_t(std::max<uint64_t>(1, std::min<uint64_t>(want, uint64_t(ex.grid_blocks) * 8))), 256, 0,
                    ex.main_stream>>>(a, p.f.n_vertices);
      TV_CUDA(cudaGetLastError());
    } else {
      for (uint64_t i = 0; i < p.f.n_vertices; ++i) zb_vertex(a, ex.host_index(i, p.f.n_vertices));
      std::fill(ids, ids + n_samples, -1);
    }
    ++ex.queued;
    if (gpu) {
      const uint64_t want = (n_tri + kTriBlock - 1) / kTriBlock;
      if (want) k_zb_triangles<<<uint32_t(std::min<uint64_t>(want, uint64_t(ex.grid_blocks) * 8)), kTriBlock, 0,
                                 ex.main_stream>>>(a, n_tri);
      TV_CUDA(cudaGetLastError());
    } else {
      for (uint64_t t = 0; t < n_tri; ++t) zb_trace_triangle_host(a, ex.host_index(t, n_tri));
    }
    if (gpu) {
      k_zb_rare<<<ex.grid_blocks, 128, 0, ex.main_stream>>>(a);
      TV_CUDA(cudaGetLastError());
      k_zb_units<<<ex.grid_blocks * 4, 256, 0, ex.main_stream>>>(a);
      TV_CUDA(cudaGetLastError());
    } else if (!overflowed(a)) {
      const uint64_t n = a.ctr[kZBig] & kZUnitMask;
      for (uint64_t u = 0; u < n; ++u) zb_unit(a, ex.host_index(u, n), 0, 1);
    }
    marks.mark(1);
    ex.exclusive_scan(a.tile_count, a.tile_off, n_tiles);
    if (gpu) {
      k_zb_scatter<<<ex.grid_blocks * 4, 256, 0, ex.main_stream>>>(a);
      TV_CUDA(cudaGetLastError());
    } else if (!overflowed(a)) {
      const uint64_t n = a.ctr[kZPairs];
      for (uint64_t i = 0; i < n; ++i) zb_scatter(a, ex.host_index(i, n));
    }
    marks.mark(2);
    if (gpu) {
      const uint64_t want = (n_tiles + kWarpsPerBlock - 1) / kWarpsPerBlock;
      k_zb_tiles<<<uint32_t(std::min<uint64_t>(want, uint64_t(ex.grid_blocks) * 16)), kRasterBlock, 0,
                   ex.main_stream>>>(a);
      TV_CUDA(cudaGetLastError());
      k_zb_helpers<<<ex.grid_blocks * 2, kRasterBlock, 0, ex.main_stream>>>(a);
      TV_CUDA(cudaGetLastError());
    } else if (!overflowed(a)) {
      for (uint64_t t = 0; t < n_tiles; ++t) zb_tile_host(a, ex.host_index(t, n_tiles));
      const uint64_t n = overflowed(a) ? 0 : a.ctr[kZHelpers];
      for (uint64_t h = 0; h < n; ++h) zb_helper_host(a, ex.host_index(h, n));
    }
    marks.mark(3);
    // After the frame's last event: the counters, once (overflow check; not a size any stage waits for).
    const uint32_t during = ex.syncs;
    ex.download(got, a.ctr, sizeof(got));
    ex.syncs = during;
    const bool over = got[kZRecords] > caps.rec || got[kZPairs] > caps.pair || (got[kZBig] & kZUnitMask) > caps.unit ||
                      (got[kZBig] >> kZUnitBits) > caps.big ||
                      got[kZHelpers] > caps.helper || got[kZRare] > caps.rare;
    auto grow = [](uint64_t& cap, uint64_t need) { cap = std::max(cap, need + need / 4 + 16); };
    grow(caps.rec, got[kZRecords]);
    grow(caps.pair, got[kZPairs]);
    grow(caps.unit, got[kZBig] & kZUnitMask);
    grow(caps.big, got[kZBig] >> kZUnitBits);
    grow(caps.helper, got[kZHelpers]);
    grow(caps.rare, got[kZRare]);
    return !over;
  };
  const uint32_t runs = ex.where == Where::cpu ? 1 : std::max<uint32_t>(cfg.runs, 1);
  const uint32_t warm = ex.where == Where::cpu ? 0 : std::max<uint32_t>(cfg.warmup, 1);
  uint32_t retries = 0;
  for (uint32_t k = 0; k < warm + runs;) {
    if (!once()) {
      if (++retries > 32) throw std::runtime_error("cuda zbuffer: buffers still overflow after 32 retries");
      continue;
    }
    ex.sync();
    if (k++ < warm) continue;
    for (int s = 0; s + 1 < n_marks; ++s) stage[size_t(s)].push_back(marks.ms(s, s + 1));
    total.push_back(marks.ms(0, n_marks - 1));
  }
  r.runs = runs;
  r.host_syncs = ex.syncs;
  const char* const names_tiled[] = {"setup_bin", "lists", "raster"};
  const char* const names_naive[] = {"raster"};
  for (int s = 0; s + 1 < n_marks; ++s)
    r.stage_ms.push_back({naive ? names_naive[s] : names_tiled[s], median_of(stage[size_t(s)])});
  r.total_ms = median_of(total);
  r.ids.resize(n_samples);
  ex.download(r.ids.data(), ids, n_samples * 4);
  if (naive) {
    unsigned long long c[2] = {0, 0};
    ex.download(c, z.ncount.get(), sizeof(c));
    r.triangles_drawn = c[0];
    r.skipped = c[1];
  } else {
    r.triangles_drawn = 0;
    for (uint32_t k = 0; k < kZSpread; ++k) r.triangles_drawn += got[kZCounterCount + k];
    r.bin_entries = got[kZPairs];
    r.retries = retries;
  }
  return r;
}

}  // namespace tilevis::cuda
