// Raster and outputs: the samples of every piece, a tile at a time (a block takes up to
// kTilePieces of one tile's pieces, their edges in shared memory, and its threads take the
// tile's samples, each testing its samples against every piece in turn: no piece's size holds
// up a warp, one id write per sample and block); a piece with more than kTileEdges edges goes
// to a queue, one warp each, its lanes taking runs of its pixels. A sample is covered under
// the tie rule. Then the id buffer (per sample, the last visible piece in canonical order:
// within a tile, the highest triangle in setup order, kept by atomicMax), the per-tile
// sample counters, and the visible area per original triangle folded in canonical order
// (items sorted by id).
#include "pieces.cuh"

namespace tilevis::cuda {
namespace {

template <class P>
struct RasterArgs {
  PieceSource<P> src;
  const uint8_t* visible;
  const uint32_t* sample_xy;
  uint32_t n_samples, width, height;
  int64_t* rows;
  uint32_t* winner;
  uint64_t* heavy;            // queued pieces (more than kTileEdges edges)
  uint64_t* heavy_count;      // counters + kHeavyPieces
  uint64_t heavy_cap;
  const uint32_t* item_begin;  // per tile, its first item
  const uint64_t* unit_off;    // per tile, its first work unit (scan; the total at [n_tiles])
  uint32_t n_tiles;
};

inline constexpr uint32_t kTileEdges = 12, kTilePieces = 64, kRasterBlock = 256;

// The pixels [px0, px0 + w) x [py0, py0 + h) of a piece's bounding box inside the tile and
// the screen.
struct PixelBox {
  int64_t px0, py0;
  uint32_t w, h;
};

// Coverage of a piece over its pixel box; returns this lane's covered samples. The team's
// lanes take runs of up to kRun pixels of a row at one sample position, in turn. N > 0: N
// edges, held in registers; N = 0: any edge count, each sample tested as covers() does.
// Exact: the edge functions evaluated at the run's first pixel and stepped along it,
// e(x + 2^sb) = e(x) + a 2^sb: exact in int64 (|e| < 2^49, |a 2^sb| <= 2^32), the same
// integer test as covers() under the tie rule (e > 0, or e = 0 on an owned boundary: e > -1).
// Float: every sample evaluated as covers() does.
inline constexpr uint32_t kRun = 32;

template <int N, class P, class Team>
TV_HD uint64_t raster_box(const RasterArgs<P>& a, const PEdge<P>* poly, uint32_t n, const PixelBox& b, uint32_t tri,
                          bool vis, Team team) {
  [[maybe_unused]] typename P::Line l[N > 0 ? N : 1];
  [[maybe_unused]] int64_t step[N > 0 ? N : 1], floor[N > 0 ? N : 1];
  const uint32_t S = a.n_samples, sb = a.src.grid.sb;
  if constexpr (N > 0)
    for (int i = 0; i < N; ++i) {
      l[i] = poly[i].line;
      if constexpr (P::kExact) {
        step[i] = l[i].a << sb;
        floor[i] = l[i].owns_boundary() ? -1 : 0;
      }
    }
  const uint32_t runs = (b.w + kRun - 1) / kRun;
  const uint32_t units = runs * b.h * S;  // <= 4096 * 4096 * 16
  uint64_t covered = 0;
  for (uint32_t u = team.lane(); u < units; u += Team::kSize) {
    const uint32_t run = runs == 1 ? 0 : u % runs, rest = runs == 1 ? u : u / runs;
    const uint32_t k = S == 1 ? 0 : rest % S, row = S == 1 ? rest : rest / S;
    const int64_t px0 = b.px0 + int64_t(run) * kRun, py = b.py0 + row;
    const int64_t px_end = tmin<int64_t>(px0 + kRun, b.px0 + b.w);
    const uint32_t sxy = a.sample_xy[k];
    const int64_t x0 = (px0 << sb) + (sxy & 0xffffu), y = (py << sb) + (sxy >> 16);
    [[maybe_unused]] int64_t e[N > 0 ? N : 1];
    if constexpr (P::kExact && N > 0)
      for (int i = 0; i < N; ++i) e[i] = l[i].a * x0 + l[i].b * y + l[i].c;
    for (int64_t px = px0; px < px_end; ++px) {
      bool in = true;
      if constexpr (P::kExact && N > 0) {
        for (int i = 0; i < N; ++i) {
          in &= e[i] > floor[i];
          e[i] += step[i];
        }
      } else {
        const Pt s{int32_t(x0 + ((px - px0) << sb)), int32_t(y)};
        if constexpr (N > 0) {
          for (int i = 0; i < N; ++i) in &= P::in_half(l[i], s);
        } else {
          in = covers<P>(poly, n, s);
        }
      }
      if (!in) continue;
      ++covered;
      if (vis) atomic_max(&a.winner[(uint64_t(py) * a.width + uint64_t(px)) * S + k], tri + 1);
    }
  }
  return covered;
}

// A piece's pixel box (false: it covers no pixel of the tile and screen).
template <class P>
TV_HD bool pixel_box(const RasterArgs<P>& a, const PieceView<P>& v, PixelBox& b) {
  if (v.n < 3) return false;
  const TileGrid& g = a.src.grid;
  const uint32_t sb = g.sb, tx = v.tile % g.tiles_x, ty = v.tile / g.tiles_x;
  const Rect r = bounding_box<P>(v.e, v.n);
  // A pixel's samples lie in [px 2^sb, (px + 1) 2^sb).
  const int64_t px0 = tmax<int64_t>(int64_t(tx) * g.tile_w, int64_t(r.x0) >> sb);
  const int64_t px1 = tmin<int64_t>(tmin<int64_t>(int64_t(tx + 1) * g.tile_w, a.width) - 1, int64_t(r.x1) >> sb);
  const int64_t py0 = tmax<int64_t>(int64_t(ty) * g.tile_h, int64_t(r.y0) >> sb);
  const int64_t py1 = tmin<int64_t>(tmin<int64_t>(int64_t(ty + 1) * g.tile_h, a.height) - 1, int64_t(r.y1) >> sb);
  if (px1 < px0 || py1 < py0) return false;
  b = {px0, py0, uint32_t(px1 - px0 + 1), uint32_t(py1 - py0 + 1)};
  return true;
}

template <class P, class Team>
TV_HD uint64_t raster_piece(const RasterArgs<P>& a, const PieceView<P>& v, const PixelBox& b, bool vis, Team team) {
  switch (v.n) {
    case 3: return raster_box<3, P>(a, v.e, v.n, b, v.tri, vis, team);
    case 4: return raster_box<4, P>(a, v.e, v.n, b, v.tri, vis, team);
    case 5: return raster_box<5, P>(a, v.e, v.n, b, v.tri, vis, team);
    case 6: return raster_box<6, P>(a, v.e, v.n, b, v.tri, vis, team);
    case 7: return raster_box<7, P>(a, v.e, v.n, b, v.tri, vis, team);
    case 8: return raster_box<8, P>(a, v.e, v.n, b, v.tri, vis, team);
    default: return raster_box<0, P>(a, v.e, v.n, b, v.tri, vis, team);
  }
}

// A piece as a tile block holds it in shared memory.
template <class P>
struct TilePiece {
  typename P::Line l[kTileEdges];
  int32_t px0, py0, px1, py1;  // its pixel box, inclusive (px1 < px0: nothing to raster here)
  uint32_t n, tri;
  bool vis;
};

template <class P>
TV_HD void load_piece(const RasterArgs<P>& a, uint64_t p, TilePiece<P>& tp) {
  PEdge<P> local[kTileCap];
  const PieceView<P> v = piece_at<P>(a.src, p, local);
  tp.px0 = 0;
  tp.px1 = -1;
  PixelBox b;
  if (!pixel_box<P>(a, v, b)) return;
  if (v.n > kTileEdges) {
    const uint64_t at = bump_one(a.heavy_count, a.heavy_cap);
    if (at != ~uint64_t{0}) a.heavy[at] = p;
    return;
  }
  for (uint32_t i = 0; i < v.n; ++i) tp.l[i] = v.e[i].line;
  tp.n = v.n;
  tp.px0 = int32_t(b.px0);
  tp.py0 = int32_t(b.py0);
  tp.px1 = int32_t(b.px0 + b.w - 1);
  tp.py1 = int32_t(b.py0 + b.h - 1);
  tp.tri = v.tri;
  tp.vis = a.visible[p] != 0;
}

// A work unit: up to kTilePieces consecutive pieces of one tile, and the tile's pixels inside
// the screen.
struct TileUnit {
  uint32_t tile, count;
  uint64_t first;  // piece
  int32_t px0, py0;
  uint32_t w, h;
};

template <class P>
TV_HD TileUnit tile_unit(const RasterArgs<P>& a, uint64_t u) {
  uint32_t lo = 0, hi = a.n_tiles;  // the last tile whose first unit is <= u
  while (hi - lo > 1) {
    const uint32_t mid = (lo + hi) / 2;
    if (a.unit_off[mid] <= u) lo = mid;
    else hi = mid;
  }
  const TileGrid& g = a.src.grid;
  TileUnit t;
  t.tile = lo;
  const uint64_t chunk = u - a.unit_off[lo];
  const uint64_t pieces = uint64_t(a.rows[uint64_t(lo) * kTileColumns + kColPieces]);
  t.first = a.src.piece_offset[a.item_begin[lo]] + chunk * kTilePieces;
  t.count = uint32_t(tmin<uint64_t>(kTilePieces, pieces - chunk * kTilePieces));
  t.px0 = int32_t((lo % g.tiles_x) * g.tile_w);
  t.py0 = int32_t((lo / g.tiles_x) * g.tile_h);
  t.w = tmin(g.tile_w, a.width - uint32_t(t.px0));
  t.h = tmin(g.tile_h, a.height - uint32_t(t.py0));
  return t;
}

// Sample `idx` of the unit's tile (pixels row by row, samples innermost) against its pieces.
template <class P>
TV_HD void raster_sample(const RasterArgs<P>& a, const TileUnit& t, const TilePiece<P>* pcs, uint32_t idx,
                         uint32_t& frags, uint32_t& vis_frags) {
  const uint32_t S = a.n_samples, sb = a.src.grid.sb;
  const uint32_t k = S == 1 ? 0 : idx % S, pix = S == 1 ? idx : idx / S;
  const int32_t px = t.px0 + int32_t(pix % t.w), py = t.py0 + int32_t(pix / t.w);
  const uint32_t sxy = a.sample_xy[k];
  const Pt s{int32_t((int64_t(px) << sb) + (sxy & 0xffffu)), int32_t((int64_t(py) << sb) + (sxy >> 16))};
  uint32_t win = 0;
  for (uint32_t q = 0; q < t.count; ++q) {
    const TilePiece<P>& tp = pcs[q];
    if (px < tp.px0 || px > tp.px1 || py < tp.py0 || py > tp.py1) continue;
    bool in = true;
    for (uint32_t i = 0; i < tp.n && in; ++i) in = P::in_half(tp.l[i], s);
    if (!in) continue;
    ++frags;
    if (!tp.vis) continue;
    ++vis_frags;
    win = tmax(win, tp.tri + 1);
  }
  if (win) atomic_max(&a.winner[(uint64_t(py) * a.width + uint64_t(px)) * S + k], win);
}

template <class P>
__global__ void __launch_bounds__(kRasterBlock) k_raster_tiles(RasterArgs<P> a, const uint64_t* count, uint64_t) {
  __shared__ TilePiece<P> pcs[kTilePieces];
  const uint64_t n = *count;
  for (uint64_t u = blockIdx.x; u < n; u += gridDim.x) {
    const TileUnit t = tile_unit<P>(a, u);
    if (threadIdx.x < t.count) load_piece<P>(a, t.first + threadIdx.x, pcs[threadIdx.x]);
    __syncthreads();
    uint32_t frags = 0, vis_frags = 0;
    for (uint32_t idx = threadIdx.x; idx < t.w * t.h * a.n_samples; idx += blockDim.x)
      raster_sample<P>(a, t, pcs, idx, frags, vis_frags);
    int64_t* row = a.rows + uint64_t(t.tile) * kTileColumns;
    count_add(&row[kColFragments], frags);
    count_add(&row[kColSamplesCovered], vis_frags);
    __syncthreads();
  }
}

template <class P>
void raster_unit_host(const RasterArgs<P>& a, uint64_t u) {
  static thread_local std::vector<TilePiece<P>> pcs(kTilePieces);
  const TileUnit t = tile_unit<P>(a, u);
  for (uint32_t q = 0; q < t.count; ++q) load_piece<P>(a, t.first + q, pcs[q]);
  uint32_t frags = 0, vis_frags = 0;
  for (uint32_t idx = 0; idx < t.w * t.h * a.n_samples; ++idx) raster_sample<P>(a, t, pcs.data(), idx, frags, vis_frags);
  int64_t* row = a.rows + uint64_t(t.tile) * kTileColumns;
  count_add(&row[kColFragments], frags);
  count_add(&row[kColSamplesCovered], vis_frags);
}

// Work units per tile: its pieces in chunks of kTilePieces.
struct UnitArgs {
  const int64_t* rows;
  uint32_t* units;
};
TV_HD void tile_units(const UnitArgs& a, uint64_t t) {
  a.units[t] = uint32_t((uint64_t(a.rows[t * kTileColumns + kColPieces]) + kTilePieces - 1) / kTilePieces);
}
__global__ void k_tile_units(UnitArgs a, uint64_t n) {
  TV_GRID_LOOP(i, n) tile_units(a, i);
}

// Second pass, one team per queued piece: the lanes take its samples in turn.
template <class P, class Team>
TV_HD void raster_heavy(const RasterArgs<P>& a, uint64_t h, Team team) {
  const uint64_t p = a.heavy[h];
  PEdge<P> local[kTileCap];
  const PieceView<P> v = piece_at<P>(a.src, p, local);
  PixelBox b;
  pixel_box<P>(a, v, b);
  const bool vis = a.visible[p] != 0;
  const uint64_t c = team.sum(raster_piece<P>(a, v, b, vis, team));
  if (team.lane() != 0) return;
  int64_t* row = a.rows + uint64_t(v.tile) * kTileColumns;
  atomic_add(&row[kColFragments], int64_t(c));
  if (vis) atomic_add(&row[kColSamplesCovered], int64_t(c));
}

template <class P>
TV_HD void raster_heavy_host(const RasterArgs<P>& a, uint64_t h) {
  raster_heavy<P>(a, h, HostTeam{});
}

template <class P>
struct OutArgs {
  const uint32_t* winner;
  const TileTri<P>* tris;
  int32_t* ids;
  const uint64_t* area_key;   // original id, items sorted by it (stable: canonical order)
  const uint32_t* area_item;
  const uint64_t* piece_offset;
  const uint8_t* visible;
  const double* piece_area;
  double* area;
};

template <class P>
TV_HD void write_id(const OutArgs<P>& a, uint64_t s) {
  const uint32_t w = a.winner[s];
  a.ids[s] = w ? int32_t(a.tris[w - 1].id) : -1;
}

// One thread per original triangle's run of items: area += piece area, piece by piece, in
// canonical order (the left fold golden performs).
template <class P>
TV_HD void fold_area(const OutArgs<P>& a, uint64_t q) {
  const uint64_t id = a.area_key[q];
  if (q > 0 && a.area_key[q - 1] == id) return;
  double sum = 0;
  bool any = false;
  for (uint64_t r = q; a.area_key[r] == id; ++r) {
    const uint32_t j = a.area_item[r];
    for (uint64_t p = a.piece_offset[j]; p < a.piece_offset[j + 1]; ++p)
      if (a.visible[p]) {
        sum = dadd(sum, a.piece_area[p]);
        any = true;
      }
  }
  if (any) a.area[id] = sum;
}

template <class P>
__global__ void k_raster_heavy(RasterArgs<P> a, const uint64_t* count, uint64_t cap) {
  const uint64_t n = *count < cap ? *count : cap;
  TV_WARP_LOOP(w, n) raster_heavy<P>(a, w, WarpTeam{});
}
template <class P>
__global__ void k_write_id(OutArgs<P> a, uint64_t n) {
  TV_GRID_LOOP(i, n) write_id<P>(a, i);
}
template <class P>
__global__ void k_fold_area(OutArgs<P> a, uint64_t n) {
  TV_GRID_LOOP(i, n) fold_area<P>(a, i);
}

}  // namespace

template <class P>
void stage_raster(Pipeline<P>& p) {
  Exec& ex = p.ex;
  const uint64_t n_samples = uint64_t(p.f.width) * p.f.height * p.f.n_samples;
  RasterArgs<P> a{};
  a.src = piece_source(p);
  a.visible = p.piece_visible.get();
  a.sample_xy = p.sample_xy.get();
  a.n_samples = p.f.n_samples;
  a.width = p.f.width;
  a.height = p.f.height;
  a.rows = p.tile_rows.get();
  a.winner = p.winner.need(n_samples + 1);
  ex.zero(a.winner, n_samples * 4);
  a.heavy_count = p.counters.get() + kHeavyPieces;
  a.heavy_cap = p.n_pieces;
  a.heavy = p.heavy.need(p.n_pieces + 1);
  ex.zero(a.heavy_count, 8);
  a.item_begin = p.tile_item_begin.get();
  a.n_tiles = p.n_tiles;
  uint32_t* units = p.tile_units.need(p.n_tiles + 1);
  ex.launch(k_tile_units, tile_units, p.n_tiles, UnitArgs{a.rows, units});
  ex.exclusive_scan(units, p.unit_off.need(p.n_tiles + 1), p.n_tiles);
  a.unit_off = p.unit_off.get();
  ex.launch_dyn(k_raster_tiles<P>, raster_unit_host<P>, a.unit_off + p.n_tiles, ~uint64_t{0}, a, kRasterBlock);
  ex.launch_dyn(k_raster_heavy<P>, raster_heavy_host<P>, a.heavy_count, a.heavy_cap, a);

  OutArgs<P> o{};
  o.winner = a.winner;
  o.tris = p.tris.get();
  o.ids = p.ids.need(n_samples + 1);
  o.area_key = p.area_key_sorted.get();  // ends with a sentinel (binning)
  o.area_item = p.area_item_sorted.get();
  o.piece_offset = p.piece_offset.get();
  o.visible = p.piece_visible.get();
  o.piece_area = p.piece_area.get();
  o.area = p.area.need(p.f.n_triangles + 1);
  ex.zero(o.area, p.f.n_triangles * 8);
  ex.launch(k_write_id<P>, write_id<P>, n_samples, o);
  ex.merge(2);  // the visible-area order (binning)
  ex.launch(k_fold_area<P>, fold_area<P>, p.n_items, o);
}

template void stage_raster<ExactP>(Pipeline<ExactP>&);
template void stage_raster<FloatP>(Pipeline<FloatP>&);

}  // namespace tilevis::cuda
