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
};

TV_HD inline int64_t floor_div64(int64_t a, int64_t d) { return a >= 0 ? a / d : -((-a + d - 1) / d); }

// Calls fn(tile) for every tile whose closed rectangle the box touches (clamped to the screen)
// and that the primitive overlaps.
template <class P, class Test, class Fn>
TV_HD inline void for_tiles(const BinArgs<P>& a, const Rect& b, Test&& test, Fn&& fn) {
  const int64_t tw = int64_t(a.tile_w) << a.sb, th = int64_t(a.tile_h) << a.sb;
  const int64_t tx0 = tmax<int64_t>(0, floor_div64(b.x0, tw)), tx1 = tmin<int64_t>(a.tiles_x - 1, floor_div64(b.x1, tw));
  const int64_t ty0 = tmax<int64_t>(0, floor_div64(b.y0, th)), ty1 = tmin<int64_t>(a.tiles_y - 1, floor_div64(b.y1, th));
  for (int64_t ty = ty0; ty <= ty1; ++ty)
    for (int64_t tx = tx0; tx <= tx1; ++tx)
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
        atomic_add(&a.rows[uint64_t(tile) * kTileColumns + kColTriangles], 1);
        if (t.opaque) atomic_add(&a.occ_count[tile], 1u);
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
        atomic_add(&a.rows[uint64_t(tile) * kTileColumns + kColEdges], 1);
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

template <class P>
__global__ void k_bin_tri_count(BinArgs<P> a, uint64_t n) {
  TV_GRID_LOOP(i, n) bin_tri_count<P>(a, i);
}
template <class P>
__global__ void k_bin_tri_emit(BinArgs<P> a, uint64_t n) {
  TV_GRID_LOOP(i, n) bin_tri_emit<P>(a, i);
}
template <class P>
__global__ void k_bin_edge_count(BinArgs<P> a, uint64_t n) {
  TV_GRID_LOOP(i, n) bin_edge_count<P>(a, i);
}
template <class P>
__global__ void k_bin_edge_emit(BinArgs<P> a, uint64_t n) {
  TV_GRID_LOOP(i, n) bin_edge_emit<P>(a, i);
}
__global__ void k_tile_begin(RangeArgs a, uint64_t n) {
  TV_GRID_LOOP(i, n) tile_begin(a, i);
}
template <class P>
__global__ void k_gather_box(BoxArgs<P> a, uint64_t n) {
  TV_GRID_LOOP(i, n) gather_box<P>(a, i);
}
template <class P>
__global__ void k_gather_occ(OccGatherArgs<P> a, uint64_t n) {
  TV_GRID_LOOP(i, n) gather_occ<P>(a, i);
}
template <class P>
__global__ void k_area_key(AreaKeyArgs<P> a, uint64_t n) {
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
  ex.launch(k_bin_tri_count<P>, bin_tri_count<P>, p.n_tris, a);
  ex.launch(k_bin_edge_count<P>, bin_edge_count<P>, p.n_edges, a);
  ex.exclusive_scan(a.tri_tiles, p.tri_tiles_off.get(), p.n_tris);
  ex.exclusive_scan(a.edge_tiles, p.edge_tiles_off.get(), p.n_edges);
  // sync: the numbers of (tile, triangle) and (tile, edge) pairs.
  ex.read_many({{&p.n_items, p.tri_tiles_off.get() + p.n_tris}, {&p.n_tile_edges, p.edge_tiles_off.get() + p.n_edges}});
  if (p.n_items >= 0xffffffffull) throw std::runtime_error("cuda: more than 2^32 - 2 (tile, triangle) pairs");

  const uint64_t ni = p.n_items, ne = p.n_tile_edges;
  a.item_key = p.item_key.need(ni + 1);
  a.item_tri = p.item_tri.need(ni + 1);
  a.occ_key = p.occ_key.need(ni + 1);
  a.occ_tri = p.occ_tri.need(ni + 1);
  a.tedge_key = p.tedge_key.need(ne + 1);
  a.tedge_id = p.tedge_id.need(ne + 1);
  ex.launch(k_bin_tri_emit<P>, bin_tri_emit<P>, p.n_tris, a);
  ex.launch(k_bin_edge_emit<P>, bin_edge_emit<P>, p.n_edges, a);

  const int tile_bits = int(bits_for(tiles));
  const int d = int(p.f.depth_bits);
  ex.sort_pairs(a.item_key, p.item_key_sorted.need(ni + 1), a.item_tri, p.item_tri_sorted.need(ni + 1), ni, tile_bits);
  ex.sort_pairs(a.occ_key, p.occ_key_sorted.need(ni + 1), a.occ_tri, p.occ_tri_sorted.need(ni + 1), ni,
                tile_bits + d + 1);
  ex.sort_pairs(a.tedge_key, p.tedge_key_sorted.need(ne + 1), a.tedge_id, p.tedge_id_sorted.need(ne + 1), ne,
                tile_bits + d);

  uint32_t* item_begin = p.tile_item_begin.need(tiles);
  uint32_t* edge_begin = p.tile_edge_begin.need(tiles);
  ex.zero(item_begin, tiles * 4ull);
  ex.zero(edge_begin, tiles * 4ull);
  ex.launch(k_tile_begin, tile_begin, ni, RangeArgs{p.item_key_sorted.get(), 0, ni, item_begin});
  ex.launch(k_tile_begin, tile_begin, ne, RangeArgs{p.tedge_key_sorted.get(), uint32_t(d), ne, edge_begin});
  ex.launch(k_gather_occ<P>, gather_occ<P>, ni, OccGatherArgs<P>{p.tris.get(), p.occ_tri_sorted.get(), p.occ_rec.need(ni + 1)});
  ex.launch(k_gather_box<P>, gather_box<P>, ne, BoxArgs<P>{p.edges.get(), p.tedge_id_sorted.get(), p.tedge_box.need(ne + 1)});

  AreaKeyArgs<P> ak{p.tris.get(), p.item_tri_sorted.get(), p.area_key.need(ni + 1), p.area_item.need(ni + 1)};
  ex.launch(k_area_key<P>, area_key<P>, ni, ak);
  ex.sort_pairs(ak.key, p.area_key_sorted.need(ni + 1), ak.item, p.area_item_sorted.need(ni + 1), ni,
                int(bits_for(p.f.n_triangles)));
}

template void stage_binning<ExactP>(Pipeline<ExactP>&);
template void stage_binning<FloatP>(Pipeline<FloatP>&);

}  // namespace tilevis::cuda
