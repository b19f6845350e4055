// Occlusion (SVGPU §3.3), in two passes over pieces (pieces.cuh: the unclipped items' beside
// the clipping, then the clipped ones'): the centroid of the piece's first three vertices
// against the tile's original opaque triangles, nearest first (stable by z_min), stopping at
// the first that hides it or at the first wholly behind it. A thread per piece, visiting only
// the list entries whose bounding boxes can hold its point (the tile's cell masks, below),
// except float's clipped pieces when they are few (a warp per piece, 32 entries at a time);
// with finer occlusion bins, a thread per piece for the first kSoloOccluders entries of its
// bin's list, then one warp per piece still undecided, its lanes judging 32 entries at a time.
// Visible pieces get their exact area (doubled area terms rounded once each, summed in fan
// order).
#include "pieces.cuh"

namespace tilevis::cuda {
namespace {

// Cell masks (finer bins off): a tile's occluder list, as bits. A tile is cut into kCells
// columns and kCells rows of cells (cell_w x cell_h sub-pixel units from the tile's corner, the
// outer ones open towards the outside); for every 32 positions of the sorted record list,
// word kCells * 2 * w + c has bit k set where record 32 w + k may hold a point of column c,
// word ... + kCells + r likewise for row r. A record's columns are those of its bounding box
// widened by occluder_verdict's margin: cell_of() is monotone and floor(qx) lies in
// [x0 - 1, x1 + 1] whenever qx does, so a piece whose interior point is in column c and row r
// skips only records whose bounding box test would have skipped it: its search visits the
// set bits of (column & row) in list order, with the same verdicts, the same first hider and
// the same tests counted, and ends where the sequential scan ends (the first record whose
// z_min is past the piece's z_max: the list is sorted by z_min).
inline constexpr uint32_t kCells = 16, kCellWords = 2 * kCells;

TV_HD inline uint32_t cell_of(int64_t v, int64_t origin, int64_t width) {
  const int64_t d = v - origin;
  return d < 0 ? 0u : d / width >= int64_t(kCells) ? kCells - 1 : uint32_t(d / width);
}

struct CellGeometry {
  TileGrid grid;
  int64_t cell_w, cell_h;  // sub-pixel units
};
TV_HD inline CellGeometry cell_geometry(const TileGrid& g) {
  const int64_t w = (int64_t(g.tile_w) << g.sb), h = (int64_t(g.tile_h) << g.sb);
  return {g, tmax<int64_t>(1, (w + kCells - 1) / kCells), tmax<int64_t>(1, (h + kCells - 1) / kCells)};
}

template <class P>
struct OccArgs {
  PieceSource<P> src;
  const OccRec* occ;           // by (tile, not opaque, z_min)
  const uint32_t* item_begin;  // per tile, first entry in occ_tri
  const uint32_t* occ_count;   // per tile, opaque entries
  int64_t* rows;
  uint8_t* visible;
  uint16_t* edges;             // per piece: its polygon's edge count
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
  CellGeometry cells;         // finer bins off: the tiles' cell masks (above)
  const uint32_t* cell_mask;
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
  a.edges[p] = uint16_t(v.n);
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
// A piece's search begins: an unclipped piece is counted and its query made; false (the piece
// marked not visible) when there is nothing to search.
template <class P>
TV_HD bool begin_piece(const OccArgs<P>& a, uint64_t p, PEdge<P>* local, OccQuery<P>& o) {
  if (p < a.src.n_items) count_unclipped<P>(a, p);
  if (occ_query<P>(a, p, local, o)) return true;
  a.visible[p] = 0;
  return false;
}

template <class P>
TV_HD void occlude_first(const OccArgs<P>& a, uint64_t p, uint32_t solo) {
  PEdge<P> local[kTileCap];
  OccQuery<P> o;
  if (!begin_piece<P>(a, p, local, o)) return;
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

// The columns (bits 0-15) and rows (bits 16-31) a record may hold a point of.
TV_HD inline uint32_t record_cells(const CellGeometry& cg, uint32_t tile, const Rect& b) {
  const Rect r = cg.grid.rect(tile);
  const uint32_t c0 = cell_of(int64_t(b.x0) - 1, r.x0, cg.cell_w), c1 = cell_of(int64_t(b.x1) + 1, r.x0, cg.cell_w);
  const uint32_t r0 = cell_of(int64_t(b.y0) - 1, r.y0, cg.cell_h), r1 = cell_of(int64_t(b.y1) + 1, r.y0, cg.cell_h);
  const uint32_t cols = ((2u << c1) - 1u) & ~((1u << c0) - 1u), rows = ((2u << r1) - 1u) & ~((1u << r0) - 1u);
  return cols | rows << 16;
}

struct CellArgs {
  const OccRec* rec;
  const uint64_t* occ_key;  // sorted: tile << (depth_bits + 1) | not opaque << depth_bits | z_min
  uint32_t key_shift;       // depth_bits + 1
  uint32_t n_tiles;
  CellGeometry cg;
  const uint64_t* count;    // records (device memory)
  uint32_t* mask;
};

TV_HD inline uint32_t position_cells(const CellArgs& a, uint64_t k, uint64_t n) {
  if (k >= n) return 0;
  const uint64_t tile = a.occ_key[k] >> a.key_shift;
  return tile < a.n_tiles ? record_cells(a.cg, uint32_t(tile), a.rec[k].bbox) : 0u;
}

// Host: word group w, its 32 positions one after the other (element 32 w + l of the launch:
// l = 0 writes the group).
TV_HD void cell_words_host(const CellArgs& a, uint64_t i) {
  if (i % 32 != 0) return;
  const uint64_t w = i / 32, n = *a.count;
  uint32_t words[kCellWords] = {};
  for (uint32_t k = 0; k < 32; ++k) {
    const uint32_t cells = position_cells(a, w * 32 + k, n);
    for (uint32_t c = 0; c < kCellWords; ++c) words[c] |= ((cells >> c) & 1u) << k;
  }
  for (uint32_t c = 0; c < kCellWords; ++c) a.mask[w * kCellWords + c] = words[c];
}

// Device: a lane per position, a warp per word group (the launch is a multiple of 32 elements,
// so a warp's lanes stay together); lane c writes word c.
__global__ void k_cell_words(CellArgs a, uint64_t n_lanes) {
  TV_KERNEL_WAIT();
  const uint64_t n = *a.count;
  TV_GRID_LOOP(i, n_lanes) {
    const uint32_t lane = uint32_t(i & 31u);
    const uint32_t cells = position_cells(a, i, n);
    uint32_t mine = 0;
    for (uint32_t c = 0; c < kCellWords; ++c) {
      const uint32_t word = __ballot_sync(0xffffffffu, (cells >> c) & 1u);
      if (lane == c) mine = word;
    }
    a.mask[(i / 32) * kCellWords + lane] = mine;
  }
}

// A piece's search through the set bits of its cell's words. Returns 1: hidden, 0: visible.
template <class P>
TV_HD int scan_cells(const OccArgs<P>& a, const OccQuery<P>& o, const TileTri<P>& tt, uint32_t& tests) {
  if (o.n_occ == 0) return 0;
  const uint64_t b = a.item_begin[o.v.tile], e = b + o.n_occ;
  // The interior point's cell; a point the bounding box test cannot place (not a number, or
  // too far out for int64) visits every record, as the sequential scan tests every one.
  const bool placed = fabs(o.qx) < 0x1p52 && fabs(o.qy) < 0x1p52;
  uint32_t cx = 0, cy = 0;
  if (placed) {
    const Rect r = a.cells.grid.rect(o.v.tile);
    cx = cell_of(int64_t(floor(o.qx)), r.x0, a.cells.cell_w);
    cy = kCells + cell_of(int64_t(floor(o.qy)), r.y0, a.cells.cell_h);
  }
  for (uint64_t w = b / 32; w * 32 < e; ++w) {
    const uint32_t lo = uint32_t(tmax<uint64_t>(b, w * 32) - w * 32), hi = uint32_t(tmin<uint64_t>(e, w * 32 + 32) - w * 32);
    uint32_t m = placed ? a.cell_mask[w * kCellWords + cx] & a.cell_mask[w * kCellWords + cy] : ~0u;
    m &= (hi == 32 ? ~0u : (1u << hi) - 1u) & ~((1u << lo) - 1u);
    const bool last = a.occ[w * 32 + hi - 1].z_min > tt.z_max;  // the search ends in this word
    while (m != 0) {
      const uint32_t k = uint32_t(ctz32(m));
      m &= m - 1u;
      const OccVerdict v = occluder_verdict<P>(o.q, o.qx, o.qy, tt, a.src.tris, a.occ[w * 32 + k]);
      if (v == OccVerdict::ends) return 0;
      if (v == OccVerdict::skip) continue;
      ++tests;
      if (v == OccVerdict::hides) return 1;
    }
    if (last) return 0;
  }
  return 0;
}

// A piece's occlusion (finer bins off): a thread per piece, unclipped or clipped.
template <class P>
TV_HD void occlude_cells(const OccArgs<P>& a, uint64_t i) {
  const uint64_t p = a.base + i;
  PEdge<P> local[kTileCap];
  OccQuery<P> o;
  if (!begin_piece<P>(a, p, local, o)) return;
  uint32_t tests = 0;
  const int r = scan_cells<P>(a, o, a.src.tris[o.v.tri], tests);
  occ_finish<P>(a, p, o.v, r > 0, tests);
}

template <class P>
__global__ void k_occlude_cells(OccArgs<P> a, const uint64_t* count, uint64_t cap) {
  TV_KERNEL_WAIT();
  const uint64_t n = *count < cap ? *count : cap;
  TV_GRID_LOOP(i, n) occlude_cells<P>(a, i);
}

// The clipped pass in float: with fewer than kWarpSlots piece slots (every scene but million
// at 1080p), a warp per piece over its whole list, 32 entries at a time (its list is long for
// one thread's walk, and there are too few pieces to keep the threads busy: measured, the
// thread walk took the bunny's clipped pass from 0.021 to 0.069 ms); with more, a thread per
// piece through the cell masks (million: 0.82 -> about 0.36 ms). The same verdicts either way.
inline constexpr uint64_t kWarpSlots = 65536;

template <class P>
__global__ void k_occlude_clipped_float(OccArgs<P> a, const uint64_t* count, uint64_t cap) {
  TV_KERNEL_WAIT();
  const uint64_t n = *count < cap ? *count : cap;
  if (n < kWarpSlots) {
    TV_WARP_LOOP(w, n) occlude_team<P>(a, a.base + w, 0, WarpTeam{});
  } else {
    TV_GRID_LOOP(i, n) occlude_cells<P>(a, i);
  }
}

template <class P>
__global__ void k_occlude(OccArgs<P> a, const uint64_t* count, uint64_t cap) {
  TV_KERNEL_WAIT();
  const uint64_t n = *count < cap ? *count : cap;
  TV_GRID_LOOP(i, n) occlude_piece<P>(a, i);
}
template <class P>
__global__ void k_occlude_heavy(OccArgs<P> a, const uint64_t* count, uint64_t cap) {
  TV_KERNEL_WAIT();
  const uint64_t n = *count < cap ? *count : cap;
  TV_WARP_LOOP(w, n) occlude_team<P>(a, a.heavy[w], kSoloOccluders<P>, WarpTeam{});
}
template <class P>
__global__ void k_occlude_clipped(OccArgs<P> a, const uint64_t* count, uint64_t cap) {
  TV_KERNEL_WAIT();
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
  a.edges = p.piece_edges.need(p.n_items + p.caps.clip_slots + 1);
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
  if (p.obins_x * p.obins_y == 1) {  // both passes: a thread per piece through its cell's bits
    a.cells = cell_geometry(p.grid);
    a.cell_mask = p.occ_cells.get();
    if (!P::kExact && pass == Pass::clipped) ex.launch_dyn(k_occlude_clipped_float<P>, occlude_cells<P>, r.count, r.cap, a);
    else ex.launch_dyn(k_occlude_cells<P>, occlude_cells<P>, r.count, r.cap, a);
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

template <class P>
void occlusion_cells(Pipeline<P>& p) {
  const uint64_t ni = p.n_items, groups = (ni + 31) / 32;
  CellArgs a{p.occ_rec.get(), p.occ_key_sorted.get(), p.f.depth_bits + 1, p.n_tiles, cell_geometry(p.grid),
             p.dev ? p.sizes.get() + kSzItems : p.tri_tiles_off.get() + p.n_tris,
             p.occ_cells.need(groups * kCellWords + 1)};
  p.ex.launch(k_cell_words, cell_words_host, groups * 32, a);
}

template void stage_occlusion<ExactP>(Pipeline<ExactP>&, Pass);
template void stage_occlusion<FloatP>(Pipeline<FloatP>&, Pass);
template void occlusion_cells<ExactP>(Pipeline<ExactP>&);
template void occlusion_cells<FloatP>(Pipeline<FloatP>&);

}  // namespace tilevis::cuda
