// Occlusion (SVGPU §3.3), in two passes over pieces (pieces.cuh: the unclipped items' beside
// the clipping, then the clipped ones'): the centroid of the piece's first three vertices
// against the tile's original opaque triangles, nearest first (stable by z_min), stopping at
// the first that hides it or at the first wholly behind it; one thread per piece for the first
// kSoloOccluders entries of its list, then one warp per piece still undecided, its lanes
// judging 32 entries at a time. Visible pieces get their exact area (doubled area terms
// rounded once each, summed in fan order).
#include "pieces.cuh"

namespace tilevis::cuda {
namespace {

template <class P>
struct OccArgs {
  PieceSource<P> src;
  const OccRec* occ;           // by (tile, not opaque, z_min)
  const uint32_t* item_begin;  // per tile, first entry in occ_tri
  const uint32_t* occ_count;   // per tile, opaque entries
  int64_t* rows;
  uint8_t* visible;
  double* area;
  uint64_t* counters;
  double area_scale;  // 2 * 2^sb * 2^sb
  // Finer occlusion bins (bins_x * bins_y > 1): the piece scans only the list of the bin of
  // its interior point (binning.cu says which occluders a bin lists).
  uint32_t bins_x, bins_y;
  double step_x, step_y;  // bin size, sub-pixel units
  const OccRec* bin_occ;
  const uint32_t* bin_begin;
  const uint32_t* bin_count;
  uint64_t base;              // the pass's first piece id (pieces.cuh)
  uint64_t* heavy;            // queued pieces
  uint64_t* heavy_count;
  uint64_t heavy_cap;
  const uint64_t* unit_off;   // unclipped pass by tiles: per tile, its first work unit (scan)
  uint32_t n_tiles;
};

// Occluders a piece's own thread judges; a longer search goes on in a warp. Exact: all of
// them (its interior point is too costly to repeat in 32 lanes: measured, the warps lost more
// than they won).
template <class P>
inline constexpr uint32_t kSoloOccluders = P::kExact ? 0xffffffffu : 32;

// The bin whose half-open span holds v (the outer bins take whatever lies beyond the tile),
// with the same monotone arithmetic as golden's.
TV_HD inline uint32_t bin_at(double v, double origin, double step, uint32_t n) {
  const double k = floor((v - origin) / step);
  return k <= 0.0 ? 0u : k >= double(n - 1) ? n - 1 : uint32_t(k);
}

// The sequential scan of entries [begin, end) of an occluder list, judged a team at a time:
// lane l judges entry k0 + l; the lowest lane whose verdict ends the search decides, and the
// tests counted are those the sequential loop would have made up to it. Returns 1: hidden,
// 0: the search ended with the piece visible, -1: no verdict before `end`.
template <class P, class Team>
TV_HD int scan_occluders(const typename P::R& q, double qx, double qy, const TileTri<P>& tt, const TileTri<P>* tris,
                         const OccRec* occ, uint32_t begin, uint32_t end, uint32_t& tests, Team team) {
  const uint32_t lane = team.lane();
  for (uint32_t k0 = begin; k0 < end; k0 += Team::kSize) {
    const OccVerdict v =
        k0 + lane < end ? occluder_verdict<P>(q, qx, qy, tt, tris, occ[k0 + lane]) : OccVerdict::skip;
    const uint32_t tested = team.ballot(v == OccVerdict::tested || v == OccVerdict::hides);
    const uint32_t ends = team.ballot(v == OccVerdict::hides || v == OccVerdict::ends);
    if (ends == 0) {
      tests += popc(tested);
      continue;
    }
    const uint32_t first = ends & (~ends + 1u);  // lowest set bit
    tests += popc(tested & (first | (first - 1u)));
    return (team.ballot(v == OccVerdict::hides) & first) != 0 ? 1 : 0;
  }
  return -1;
}

// A piece's occlusion query: its interior point and the occluder list of its tile (or bin).
template <class P>
struct OccQuery {
  PieceView<P> v;
  typename P::R q;
  double qx, qy;
  const OccRec* occ;
  uint32_t n_occ;
};

template <class P>
TV_HD bool occ_query(const OccArgs<P>& a, uint64_t p, PEdge<P>* local, OccQuery<P>& o) {
  o.v = piece_at<P>(a.src, p, local);
  if (o.v.n < 3) return false;  // a float polygon that degenerated: covers nothing
  o.q = P::interior(o.v.e[0].start, o.v.e[1].start, o.v.e[2].start);
  o.qx = P::rx(o.q);
  o.qy = P::ry(o.q);
  const uint32_t tile = o.v.tile;
  o.occ = a.occ + a.item_begin[tile];
  o.n_occ = a.occ_count[tile];
  if (a.bins_x * a.bins_y > 1) {
    const Rect r = a.src.grid.rect(tile);
    const uint64_t g = (uint64_t(tile) * a.bins_y + bin_at(o.qy, double(r.y0), a.step_y, a.bins_y)) * a.bins_x +
                       bin_at(o.qx, double(r.x0), a.step_x, a.bins_x);
    o.n_occ = a.bin_count[g];
    o.occ = a.bin_occ + a.bin_begin[g];
  }
  return true;
}

template <class P>
TV_HD void occ_finish(const OccArgs<P>& a, uint64_t p, const PieceView<P>& v, bool hidden, uint32_t tests) {
  int64_t* row = a.rows + uint64_t(v.tile) * kTileColumns;
  count_add(&row[kColOcclusionTests], tests);
  // Float: the vertices' area where its sign is proven (poly.cuh certified_convex); else the
  // piece is marked 2 and exact_areas (raster.cu, before the fold) gives it the exact area of
  // the region its lines bound.
  bool unproven = false;
  if constexpr (!P::kExact) unproven = !hidden && !certified_convex(v.e, v.n);
  a.visible[p] = hidden ? 0 : unproven ? 2 : 1;
  count_add(&row[kColVisiblePieces], hidden ? 0 : 1);
  count_add(&a.counters[kVisibleTriangles], hidden ? 0 : v.n - 2);
  if (!hidden) {
    const double area = ddiv(doubled_area<P>(v.e, v.n), a.area_scale);
    if constexpr (!P::kExact) {
      count_add(&a.counters[kFloatExactAreas], unproven ? 1u : 0u);
      count_add(&a.counters[kFloatNegativeAreas], !unproven && area < 0 ? 1u : 0u);  // cannot occur
    }
    a.area[p] = area;
  }
}

// An unclipped item's piece (if its tile polygon is not empty) in the per-tile piece count and
// the largest piece count (clipping counts the clipped items' pieces).
template <class P>
TV_HD void count_unclipped(const OccArgs<P>& a, uint64_t j) {
  const bool one = a.src.cand_count[j] == 0 && a.src.piece_count[j] != 0;
  count_add(&a.rows[a.src.item_key[j] * kTileColumns + kColPieces], one ? 1 : 0);
  count_max(&a.counters[kMaxTilePieces], one ? 1 : 0);
}

// First pass, one thread per piece over the first `solo` entries of its list; a piece still
// undecided is queued for the second pass.
template <class P>
TV_HD void occlude_first(const OccArgs<P>& a, uint64_t p, uint32_t solo) {
  if (p < a.src.n_items) count_unclipped<P>(a, p);
  PEdge<P> local[kTileCap];
  OccQuery<P> o;
  if (!occ_query<P>(a, p, local, o)) {
    a.visible[p] = 0;
    return;
  }
  const TileTri<P>& tt = a.src.tris[o.v.tri];
  uint32_t tests = 0;
  solo = tmin(o.n_occ, solo);
  const int r = scan_occluders<P>(o.q, o.qx, o.qy, tt, a.src.tris, o.occ, 0, solo, tests, HostTeam{});
  if (r < 0 && solo < o.n_occ) {
    count_add(&a.rows[uint64_t(o.v.tile) * kTileColumns + kColOcclusionTests], tests);
    const uint64_t at = bump_one(a.heavy_count, a.heavy_cap);
    if (at != ~uint64_t{0}) a.heavy[at] = p;
    return;
  }
  occ_finish<P>(a, p, o.v, r > 0, tests);
}

// A team's search for piece p from entry `begin` of its list on, kSize entries at a time.
template <class P, class Team>
TV_HD void occlude_team(const OccArgs<P>& a, uint64_t p, uint32_t begin, Team team) {
  PEdge<P> local[kTileCap];
  OccQuery<P> o;
  if (!occ_query<P>(a, p, local, o)) {
    if (team.lane() == 0) a.visible[p] = 0;
    return;
  }
  const TileTri<P>& tt = a.src.tris[o.v.tri];
  uint32_t tests = 0;
  const int r = scan_occluders<P>(o.q, o.qx, o.qy, tt, a.src.tris, o.occ, tmin(begin, o.n_occ), o.n_occ, tests, team);
  if (team.lane() == 0) occ_finish<P>(a, p, o.v, r > 0, tests);
}

// Second pass: the queued pieces, the rest of their lists.
template <class P>
TV_HD void occlude_heavy_host(const OccArgs<P>& a, uint64_t h) {
  occlude_team<P>(a, a.heavy[h], kSoloOccluders<P>, HostTeam{});
}

// The clipped pass: float, one warp per piece over its whole list; exact, one thread.
template <class P>
TV_HD void occlude_clipped_host(const OccArgs<P>& a, uint64_t i) {
  occlude_team<P>(a, a.base + i, 0, HostTeam{});
}

template <class P>
TV_HD void occlude_piece(const OccArgs<P>& a, uint64_t i) {
  occlude_first<P>(a, a.base + i, kSoloOccluders<P>);
}

// The unclipped pass a tile at a time (finer bins off): a block takes up to kOccBlock
// consecutive items of one tile, a thread each, and streams the tile's occluder list through
// shared memory kOccStage records at a time, every thread going on with the sequential search
// of its piece over the staged records until its verdict.
inline constexpr uint32_t kOccBlock = 128, kOccStage = 256;

struct TileChunk {
  uint32_t tile, count;
  uint64_t first;  // item
};

template <class P>
TV_HD TileChunk tile_chunk(const OccArgs<P>& a, uint64_t u) {
  uint32_t lo = 0, hi = a.n_tiles;  // the last tile whose first unit is <= u
  while (hi - lo > 1) {
    const uint32_t mid = (lo + hi) / 2;
    if (a.unit_off[mid] <= u) lo = mid;
    else hi = mid;
  }
  const uint64_t chunk = u - a.unit_off[lo], items = uint64_t(a.rows[uint64_t(lo) * kTileColumns + kColTriangles]);
  return {lo, uint32_t(tmin<uint64_t>(kOccBlock, items - chunk * kOccBlock)), a.item_begin[lo] + chunk * kOccBlock};
}

template <class P>
__global__ void __launch_bounds__(kOccBlock) k_occlude_tiles(OccArgs<P> a, const uint64_t* count, uint64_t) {
  __shared__ OccRec staged[kOccStage];
  const uint64_t n = *count;
  for (uint64_t u = blockIdx.x; u < n; u += gridDim.x) {
    const TileChunk c = tile_chunk<P>(a, u);
    const uint64_t j = c.first + threadIdx.x;
    PEdge<P> local[kTileCap];
    OccQuery<P> o;
    bool open = false;
    if (threadIdx.x < c.count) {
      count_unclipped<P>(a, j);
      open = occ_query<P>(a, j, local, o);
      if (!open) a.visible[j] = 0;
    }
    const bool mine = open;
    uint32_t tests = 0;
    int r = -1;
    const OccRec* list = a.occ + a.item_begin[c.tile];
    const uint32_t n_occ = a.occ_count[c.tile];
    for (uint32_t s0 = 0; s0 < n_occ; s0 += kOccStage) {
      if (!__syncthreads_or(open)) break;
      const uint32_t m = tmin(kOccStage, n_occ - s0);
      for (uint32_t k = threadIdx.x; k < m; k += blockDim.x) staged[k] = list[s0 + k];
      __syncthreads();
      if (open) {
        r = scan_occluders<P>(o.q, o.qx, o.qy, a.src.tris[o.v.tri], a.src.tris, staged, 0, m, tests, HostTeam{});
        open = r < 0;
      }
    }
    __syncthreads();  // the stage is refilled by the next unit
    if (mine) occ_finish<P>(a, j, o.v, r > 0, tests);
  }
}

template <class P>
void occlude_unit_host(const OccArgs<P>& a, uint64_t u) {
  const TileChunk c = tile_chunk<P>(a, u);
  for (uint32_t k = 0; k < c.count; ++k) occlude_first<P>(a, c.first + k, 0xffffffffu);
}

// Work units per tile: its items in chunks of kOccBlock.
struct OccUnitArgs {
  const int64_t* rows;
  uint32_t* units;
};
TV_HD void occ_units(const OccUnitArgs& a, uint64_t t) {
  a.units[t] = uint32_t((uint64_t(a.rows[t * kTileColumns + kColTriangles]) + kOccBlock - 1) / kOccBlock);
}
__global__ void k_occ_units(OccUnitArgs a, uint64_t n) {
  TV_GRID_LOOP(i, n) occ_units(a, i);
}

template <class P>
__global__ void k_occlude(OccArgs<P> a, const uint64_t* count, uint64_t cap) {
  const uint64_t n = *count < cap ? *count : cap;
  TV_GRID_LOOP(i, n) occlude_piece<P>(a, i);
}
template <class P>
__global__ void k_occlude_heavy(OccArgs<P> a, const uint64_t* count, uint64_t cap) {
  const uint64_t n = *count < cap ? *count : cap;
  TV_WARP_LOOP(w, n) occlude_team<P>(a, a.heavy[w], kSoloOccluders<P>, WarpTeam{});
}
template <class P>
__global__ void k_occlude_clipped(OccArgs<P> a, const uint64_t* count, uint64_t cap) {
  const uint64_t n = *count < cap ? *count : cap;
  if constexpr (P::kExact) {
    TV_GRID_LOOP(i, n) occlude_team<P>(a, a.base + i, 0, HostTeam{});
  } else {
    TV_WARP_LOOP(w, n) occlude_team<P>(a, a.base + w, 0, WarpTeam{});
  }
}

}  // namespace

template <class P>
void stage_occlusion(Pipeline<P>& p, Pass pass) {
  OccArgs<P> a{};
  a.src = piece_source(p);
  a.occ = p.occ_rec.get();
  a.item_begin = p.tile_item_begin.get();
  a.occ_count = p.tile_occ_count.get();
  a.rows = p.tile_rows.get();
  a.visible = p.piece_visible.need(p.n_items + p.caps.clip_slots + 1);
  a.area = p.piece_area.need(p.n_items + p.caps.clip_slots + 1);
  a.counters = p.counters.get();
  const double s = double(1u << p.f.subpixel_bits);
  a.area_scale = 2.0 * s * s;
  a.bins_x = p.obins_x;
  a.bins_y = p.obins_y;
  if (p.obins_x * p.obins_y > 1) {
    a.step_x = double(p.obin_w) * s;
    a.step_y = double(p.obin_h) * s;
    a.bin_occ = p.obin_rec.get();
    a.bin_begin = p.obin_begin.get();
    a.bin_count = p.obin_count.get();
  }
  const PassRange r = pass_range(p, pass);
  a.base = r.base;
  Exec& ex = p.ex;
  if (pass == Pass::unclipped && p.obins_x * p.obins_y == 1) {
    uint32_t* units = p.occ_units.need(p.n_tiles + 1);
    ex.launch(k_occ_units, occ_units, p.n_tiles, OccUnitArgs{a.rows, units});
    ex.exclusive_scan(units, p.occ_unit_off.need(p.n_tiles + 1), p.n_tiles);
    a.unit_off = p.occ_unit_off.get();
    a.n_tiles = p.n_tiles;
    ex.launch_dyn(k_occlude_tiles<P>, occlude_unit_host<P>, a.unit_off + p.n_tiles, ~uint64_t{0}, a, kOccBlock);
    return;
  }
  if (pass == Pass::clipped) {
    ex.launch_dyn(k_occlude_clipped<P>, occlude_clipped_host<P>, r.count, r.cap, a);
    return;
  }
  // The unclipped pass with finer bins: a thread per piece, then a warp per piece still open.
  a.heavy = p.heavy.need(r.cap + 1);
  a.heavy_count = p.counters.get() + kHeavyPieces;
  a.heavy_cap = r.cap;
  ex.zero(a.heavy_count, 8);
  ex.launch_dyn(k_occlude<P>, occlude_piece<P>, r.count, r.cap, a);
  ex.launch_dyn(k_occlude_heavy<P>, occlude_heavy_host<P>, a.heavy_count, a.heavy_cap, a);
}

template void stage_occlusion<ExactP>(Pipeline<ExactP>&, Pass);
template void stage_occlusion<FloatP>(Pipeline<FloatP>&, Pass);

}  // namespace tilevis::cuda
