// Raster and outputs: the samples of every piece (one thread per piece, over the pixels of
// its bounding box inside the tile; a sample is covered under the tie rule), the id buffer
// (per sample, the last visible piece in canonical order: within a tile, the highest
// triangle in setup order, kept by atomicMax), the per-tile sample counters, and the
// visible area per original triangle folded in canonical order (items sorted by id).
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
};

// Coverage of an N-edge piece, row by row, N a template parameter so that the edge data
// lives in registers. Exact: edge functions stepped along a row, e(x + 2^sb) = e(x) + a 2^sb,
// exact in int64 (|e| < 2^49, |a 2^sb| <= 2^32), so this is the same integer test as covers().
// Float: each sample evaluated as covers() does.
template <int N, class P>
TV_HD int64_t raster_rows(const RasterArgs<P>& a, const PieceView<P>& v, int64_t px0, int64_t px_end, int64_t py0,
                          int64_t py1, bool vis) {
  const uint32_t sb = a.src.grid.sb;
  typename P::Line l[N];
  for (int i = 0; i < N; ++i) l[i] = v.e[i].line;
  int64_t covered = 0;
  for (int64_t py = py0; py <= py1 && py < a.height; ++py)
    for (uint32_t k = 0; k < a.n_samples; ++k) {
      const uint32_t sxy = a.sample_xy[k];
      const int64_t x0 = (px0 << sb) + (sxy & 0xffffu), y = (py << sb) + (sxy >> 16);
      [[maybe_unused]] int64_t e[N];
      if constexpr (P::kExact)
        for (int i = 0; i < N; ++i) e[i] = l[i].a * x0 + l[i].b * y + l[i].c;
      for (int64_t px = px0; px <= px_end; ++px) {
        bool in = true;
        if constexpr (P::kExact) {
          for (int i = 0; i < N; ++i) {
            in &= e[i] > 0 || (e[i] == 0 && l[i].owns_boundary());
            e[i] += l[i].a << sb;
          }
        } else {
          const Pt s{int32_t(x0 + ((px - px0) << sb)), int32_t(y)};
          for (int i = 0; i < N; ++i) in &= P::in_half(l[i], s);
        }
        if (!in) continue;
        ++covered;
        if (vis) atomic_max(&a.winner[(uint64_t(py) * a.width + uint64_t(px)) * a.n_samples + k], v.tri + 1);
      }
    }
  return covered;
}

template <class P>
TV_HD void raster_piece(const RasterArgs<P>& a, uint64_t p) {
  PEdge<P> local[kTileCap];
  const PieceView<P> v = piece_at<P>(a.src, p, local);
  if (v.n < 3) return;
  const bool vis = a.visible[p] != 0;
  const TileGrid& g = a.src.grid;
  const uint32_t sb = g.sb;
  const uint32_t tx = v.tile % g.tiles_x, ty = v.tile / g.tiles_x;
  const Rect b = bounding_box<P>(v.e, v.n);
  // A pixel's samples lie in [px 2^sb, (px + 1) 2^sb).
  const int64_t px0 = tmax<int64_t>(int64_t(tx) * g.tile_w, int64_t(b.x0) >> sb);
  const int64_t px1 = tmin<int64_t>(int64_t(tx + 1) * g.tile_w - 1, int64_t(b.x1) >> sb);
  const int64_t py0 = tmax<int64_t>(int64_t(ty) * g.tile_h, int64_t(b.y0) >> sb);
  const int64_t py1 = tmin<int64_t>(int64_t(ty + 1) * g.tile_h - 1, int64_t(b.y1) >> sb);
  int64_t covered = 0;
  const int64_t px_end = tmin<int64_t>(px1, int64_t(a.width) - 1);
  bool done = false;
  {
    switch (v.n) {
      case 3: covered = raster_rows<3>(a, v, px0, px_end, py0, py1, vis), done = true; break;
      case 4: covered = raster_rows<4>(a, v, px0, px_end, py0, py1, vis), done = true; break;
      case 5: covered = raster_rows<5>(a, v, px0, px_end, py0, py1, vis), done = true; break;
      case 6: covered = raster_rows<6>(a, v, px0, px_end, py0, py1, vis), done = true; break;
      case 7: covered = raster_rows<7>(a, v, px0, px_end, py0, py1, vis), done = true; break;
      case 8: covered = raster_rows<8>(a, v, px0, px_end, py0, py1, vis), done = true; break;
      default: break;
    }
  }
  for (int64_t py = py0; !done && py <= py1 && py < a.height; ++py)
    for (int64_t px = px0; px <= px1 && px < a.width; ++px)
      for (uint32_t k = 0; k < a.n_samples; ++k) {
        const uint32_t sxy = a.sample_xy[k];
        const Pt s{int32_t((px << sb) + (sxy & 0xffffu)), int32_t((py << sb) + (sxy >> 16))};
        if (!covers<P>(v.e, v.n, s)) continue;
        ++covered;
        if (vis) atomic_max(&a.winner[(uint64_t(py) * a.width + uint64_t(px)) * a.n_samples + k], v.tri + 1);
      }
  if (!covered) return;
  int64_t* row = a.rows + uint64_t(v.tile) * kTileColumns;
  atomic_add(&row[kColFragments], covered);
  if (vis) atomic_add(&row[kColSamplesCovered], covered);
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
__global__ void k_raster(RasterArgs<P> a, uint64_t n) {
  TV_GRID_LOOP(i, n) raster_piece<P>(a, i);
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
  ex.launch(k_raster<P>, raster_piece<P>, p.n_pieces, a);

  OutArgs<P> o{};
  o.winner = a.winner;
  o.tris = p.tris.get();
  o.ids = p.ids.need(n_samples + 1);
  // The key list ends with a sentinel no id equals, so a run's walk stops without a bound check.
  o.area_key = p.area_key_sorted.get();
  ex.fill_ones(p.area_key_sorted.get() + p.n_items, 8);
  o.area_item = p.area_item_sorted.get();
  o.piece_offset = p.piece_offset.get();
  o.visible = p.piece_visible.get();
  o.piece_area = p.piece_area.get();
  o.area = p.area.need(p.f.n_triangles + 1);
  ex.zero(o.area, p.f.n_triangles * 8);
  ex.launch(k_write_id<P>, write_id<P>, n_samples, o);
  ex.launch(k_fold_area<P>, fold_area<P>, p.n_items, o);
}

template void stage_raster<ExactP>(Pipeline<ExactP>&);
template void stage_raster<FloatP>(Pipeline<FloatP>&);

}  // namespace tilevis::cuda
