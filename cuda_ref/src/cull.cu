// Per-tile culling (SVGPU §3.2.1), kCullLanes threads per (tile, triangle) item rather than
// one thread per tile (lane l takes the item's pairs l, l + kCullLanes, ...):
// the pairs of an item are the tile's edges not behind the triangle (test 6 on edges sorted
// by nearest depth: a binary search gives the count). The cheap tests (test 6, bounding
// boxes, test 4) run there; the survivors are appended to a list (device counter, grown and
// retried on overflow) for the exact tests 1-3 against the triangle's tile polygon, one
// thread per pair.
#include "pipeline.cuh"

namespace tilevis::cuda {

template <class P>
struct CullArgs {
  const TileTri<P>* tris;
  const SilEdge<P>* edges;
  const uint64_t* item_key;   // tile
  const uint32_t* item_tri;
  const uint64_t* tedge_key;  // tile << D | z_min
  const uint32_t* tedge_id;
  const Rect* tedge_box;
  const uint32_t* edge_begin;
  int64_t* rows;
  TileGrid grid;
  uint32_t depth_bits;
  uint32_t* piece_count;
  uint64_t* deep;
  uint64_t deep_cap;
  uint64_t* counters;
  uint32_t* cand_count;
  uint32_t* cand_cursor;  // zeroed here for clipping's scatter
  uint32_t* clip_items;   // items with candidates (listed at their first)
  uint64_t* cands;
  uint64_t cand_cap;
  uint64_t n_items;
  HybridBudget budget;
};

namespace {


// Element i: lane i % kCullLanes of item i / kCullLanes (tile, triangle). The items of a tile
// are neighbours, so the threads of a warp walk the same tile's edge list (edges by nearest
// depth) nearly in step: the loads of the streamed edge boxes are shared. Pairs past the
// cheap tests go to the exact tests.
template <class P>
TV_HD void cull_item(const CullArgs<P>& a, uint64_t i) {
  const uint64_t j = i / kCullLanes;
  const uint32_t lane = uint32_t(i % kCullLanes);
  const uint32_t tile = uint32_t(a.item_key[j]);
  const TileTri<P>& tt = a.tris[a.item_tri[j]];
  if (lane == 0) a.cand_count[j] = a.cand_cursor[j] = 0;
  // Hybrid: a tile over the budget goes per pixel, so its items make no piece (no candidate,
  // nothing to clip, occlude or raster); the per-pixel pass sets its row.
  if (a.budget.over(a.rows + uint64_t(tile) * kTileColumns)) {
    if (lane == 0) a.piece_count[j] = 0;
    return;
  }
  // Binning put the triangle here because its interior meets the tile's, so the exact tile
  // polygon is never empty (golden's empty check cannot fire). Float arithmetic can make it
  // empty, and then the item does nothing, as golden would with an empty polygon.
  uint32_t n = 3;
  if constexpr (!P::kExact) {
    PEdge<P> poly[kTileCap];
    bool overflow = false;
    n = tile_polygon<P>(tt, a.grid.rect(tile), poly, overflow);
    if (overflow && lane == 0) atomic_add(&a.counters[kFloatAnomalies], 1);
  }
  if (lane == 0) a.piece_count[j] = n == 0 ? 0 : 1;
  if (n == 0) return;
  // Test 6: edges whose nearest depth is behind the triangle's farthest are skipped, with
  // every later one: the pairs examined are the edges with z_min <= z_max (upper bound).
  const int64_t* row = a.rows + uint64_t(tile) * kTileColumns;
  const uint32_t begin = a.edge_begin[tile], count = uint32_t(row[kColEdges]);
  const uint64_t zmask = (uint64_t{1} << a.depth_bits) - 1;
  uint32_t lo = 0, hi = count;
  while (lo < hi) {
    const uint32_t mid = (lo + hi) / 2;
    if ((a.tedge_key[begin + mid] & zmask) <= tt.z_max) lo = mid + 1;
    else hi = mid;
  }
  if (lo == 0) return;
  if (lane == 0) count_add(&a.rows[uint64_t(tile) * kTileColumns + kColPairTests], lo);
  const Rect tb = tt.bbox;
  for (uint32_t k = begin + lane; k < begin + lo; k += kCullLanes) {
    // Bounding boxes that at most touch: the segment cannot meet the interior (test 2). The
    // boxes are streamed in the tile's order; the edge itself is read only past this test.
    const Rect eb = a.tedge_box[k];
    if (eb.x1 <= tb.x0 || eb.x0 >= tb.x1 || eb.y1 <= tb.y0 || eb.y0 >= tb.y1) continue;
    const uint32_t ei = a.tedge_id[k];
    const SilEdge<P>& e = a.edges[ei];
    // Test 4: the silhouette edge is an edge of the triangle.
    bool same = false;
    for (int q = 0; q < 3; ++q) {
      const Vtx &u = tt.v[q], &w = tt.v[(q + 1) % 3];
      same |= (u == e.a && w == e.b) || (u == e.b && w == e.a);
    }
    if (same) continue;
    const uint64_t at = bump_one(&a.counters[kDeepPairs], a.deep_cap);
    if (at != ~uint64_t{0}) a.deep[at] = (j << 32) | ei;
  }
}

template <class P>
TV_HD void cull_exact(const CullArgs<P>& a, uint64_t k) {
  const uint64_t d = a.deep[k];
  const uint32_t j = uint32_t(d >> 32), ei = uint32_t(d);
  const uint32_t tile = uint32_t(a.item_key[j]);
  const TileTri<P>& tt = a.tris[a.item_tri[j]];
  PEdge<P> poly[kTileCap];
  bool overflow = false;
  const uint32_t n = tile_polygon<P>(tt, a.grid.rect(tile), poly, overflow);
  if (!survives<P>(poly, n, tt, a.edges[ei])) return;
  count_add(&a.rows[uint64_t(tile) * kTileColumns + kColCandidates], 1);
  if (atomic_add(&a.cand_count[j], 1u) == 0) a.clip_items[bump_one(&a.counters[kClipItems], ~uint64_t{0})] = j;
  const uint64_t at = bump_one(&a.counters[kCandidates], a.cand_cap);
  if (at != ~uint64_t{0}) a.cands[at] = d;
}

template <class P>
__global__ void k_cull_item(CullArgs<P> a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) cull_item<P>(a, i);
}
template <class P>
__global__ void k_cull_exact(CullArgs<P> a, const uint64_t* count, uint64_t cap) {
  TV_KERNEL_WAIT();
  const uint64_t n = *count < cap ? *count : cap;
  TV_GRID_LOOP(i, n) cull_exact<P>(a, i);
}

}  // namespace

template <class P>
void stage_cull(Pipeline<P>& p) {
  Exec& ex = p.ex;
  const uint64_t ni = p.n_items;
  CullArgs<P> a{};
  a.tris = p.tris.get();
  a.edges = p.edges.get();
  a.item_key = p.item_key_sorted.get();
  a.item_tri = p.item_tri_sorted.get();
  a.tedge_key = p.tedge_key_sorted.get();
  a.tedge_id = p.tedge_id_sorted.get();
  a.tedge_box = p.tedge_box.get();
  a.edge_begin = p.tile_edge_begin.get();
  a.rows = p.tile_rows.get();
  a.grid = p.grid;
  a.depth_bits = p.f.depth_bits;
  a.piece_count = p.piece_count.need(ni + 1);
  a.deep = p.deep.need(p.caps.deep_pairs);
  a.deep_cap = p.caps.deep_pairs;
  a.counters = p.counters.get();
  a.cand_count = p.cand_count.need(ni + 1);
  a.cand_cursor = p.cand_cursor.need(ni + 1);
  a.clip_items = p.clip_items.need(ni + 1);
  a.cands = p.cands.need(p.caps.candidates);
  a.cand_cap = p.caps.candidates;
  a.n_items = ni;
  a.budget = hybrid_budget(p.cfg);
  ex.launch(k_cull_item<P>, cull_item<P>, p.N(kSzCullLanes, ni * kCullLanes), a);
  ex.launch_dyn(k_cull_exact<P>, cull_exact<P>, p.counters.get() + kDeepPairs, p.caps.deep_pairs, a);
}

template void stage_cull<ExactP>(Pipeline<ExactP>&);
template void stage_cull<FloatP>(Pipeline<FloatP>&);

}  // namespace tilevis::cuda
