// Occlusion (SVGPU §3.3): the centroid of the piece's first three vertices against the
// tile's original opaque triangles, nearest first (stable by z_min), up to the first that
// hides it or the first wholly behind it. kOccLanes threads per piece share the occluder list
// (lane l takes occluders l, l + kOccLanes, ...), in two passes so that the counts stay those
// of the sequential scan: the first finds each lane's first hiding occluder and keeps the
// least (atomic min), the second counts each lane's tests up to that one and, in lane 0,
// marks the piece visible or not. Visible pieces get their exact area (doubled area terms
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
  uint32_t* first_hit;  // per piece: the least hiding occluder index, ~0u for none
  double area_scale;    // 2 * 2^sb * 2^sb
};

inline constexpr uint32_t kOccLanes = 8;

template <class P>
TV_HD void occlude_first(const OccArgs<P>& a, uint64_t i) {
  const uint64_t p = i / kOccLanes;
  const uint32_t lane = uint32_t(i % kOccLanes);
  PEdge<P> local[kTileCap];
  const PieceView<P> v = piece_at<P>(a.src, p, local);
  if (v.n < 3) return;  // a float polygon that degenerated: covers nothing
  uint32_t tests = 0;
  const uint32_t h = first_hiding<P>(v.e, a.src.tris[v.tri], a.src.tris, a.occ + a.item_begin[v.tile],
                                     a.occ_count[v.tile], lane, kOccLanes, ~0u, tests);
  if (h != ~0u) atomic_min(&a.first_hit[p], h);
}

template <class P>
TV_HD void occlude_count(const OccArgs<P>& a, uint64_t i) {
  const uint64_t p = i / kOccLanes;
  const uint32_t lane = uint32_t(i % kOccLanes);
  PEdge<P> local[kTileCap];
  const PieceView<P> v = piece_at<P>(a.src, p, local);
  if (v.n < 3) {
    if (lane == 0) a.visible[p] = 0;
    return;
  }
  const uint32_t h = a.first_hit[p];
  uint32_t tests = 0;
  first_hiding<P>(v.e, a.src.tris[v.tri], a.src.tris, a.occ + a.item_begin[v.tile], a.occ_count[v.tile], lane,
                  kOccLanes, h == ~0u ? ~0u : h + 1, tests);
  int64_t* row = a.rows + uint64_t(v.tile) * kTileColumns;
  if (tests) atomic_add(&row[kColOcclusionTests], int64_t(tests));
  if (lane != 0) return;
  a.visible[p] = h == ~0u;
  if (h != ~0u) return;
  atomic_add(&row[kColVisiblePieces], 1);
  atomic_add(&a.counters[kVisibleTriangles], uint64_t(v.n - 2));
  a.area[p] = ddiv(doubled_area<P>(v.e, v.n), a.area_scale);
}

template <class P>
__global__ void k_occlude_first(OccArgs<P> a, uint64_t n) {
  TV_GRID_LOOP(i, n) occlude_first<P>(a, i);
}
template <class P>
__global__ void k_occlude_count(OccArgs<P> a, uint64_t n) {
  TV_GRID_LOOP(i, n) occlude_count<P>(a, i);
}

}  // namespace

template <class P>
void stage_occlusion(Pipeline<P>& p) {
  OccArgs<P> a{};
  a.src = piece_source(p);
  a.occ = p.occ_rec.get();
  a.item_begin = p.tile_item_begin.get();
  a.occ_count = p.tile_occ_count.get();
  a.rows = p.tile_rows.get();
  a.visible = p.piece_visible.need(p.n_pieces + 1);
  a.area = p.piece_area.need(p.n_pieces + 1);
  a.counters = p.counters.get();
  const double s = double(1u << p.f.subpixel_bits);
  a.area_scale = 2.0 * s * s;
  a.first_hit = p.piece_first_hit.need(p.n_pieces + 1);
  p.ex.fill_ones(a.first_hit, p.n_pieces * 4);
  p.ex.launch(k_occlude_first<P>, occlude_first<P>, p.n_pieces * kOccLanes, a);
  p.ex.launch(k_occlude_count<P>, occlude_count<P>, p.n_pieces * kOccLanes, a);
}

template void stage_occlusion<ExactP>(Pipeline<ExactP>&);
template void stage_occlusion<FloatP>(Pipeline<FloatP>&);

}  // namespace tilevis::cuda
