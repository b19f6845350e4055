// Occlusion (SVGPU §3.3) per (tile, triangle) item, its pieces in turn (float: one warp per
// item, its lanes judging 32 occluders at a time; exact: one thread per item): the centroid of the piece's first three
// vertices against the tile's original opaque triangles, nearest first (stable by z_min),
// stopping at the first that hides it or at the first wholly behind it. Visible pieces get
// their exact area (doubled area terms rounded once each, summed in fan order).
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
};

// The bin whose half-open span holds v (the outer bins take whatever lies beyond the tile),
// with the same monotone arithmetic as golden's.
TV_HD inline uint32_t bin_at(double v, double origin, double step, uint32_t n) {
  const double k = floor((v - origin) / step);
  return k <= 0.0 ? 0u : k >= double(n - 1) ? n - 1 : uint32_t(k);
}

// The sequential scan of an occluder list, judged a team at a time: lane l judges occluder
// k0 + l; the lowest lane whose verdict ends the search decides, and the tests counted are
// those the sequential loop would have made up to it.
template <class P, class Team>
TV_HD bool occluded(const typename P::R& q, double qx, double qy, const TileTri<P>& tt, const TileTri<P>* tris,
                    const OccRec* occ, uint32_t n_occ, uint32_t& tests, Team team) {
  const uint32_t lane = team.lane();
  for (uint32_t k0 = 0; k0 < n_occ; k0 += Team::kSize) {
    const OccVerdict v =
        k0 + lane < n_occ ? occluder_verdict<P>(q, qx, qy, tt, tris, occ[k0 + lane]) : OccVerdict::skip;
    const uint32_t tested = team.ballot(v == OccVerdict::tested || v == OccVerdict::hides);
    const uint32_t ends = team.ballot(v == OccVerdict::hides || v == OccVerdict::ends);
    if (ends == 0) {
      tests += popc(tested);
      continue;
    }
    const uint32_t first = ends & (~ends + 1u);  // lowest set bit
    tests += popc(tested & (first | (first - 1u)));
    return (team.ballot(v == OccVerdict::hides) & first) != 0;
  }
  return false;
}

// One (tile, triangle) item, piece by piece: each piece's interior point against its
// tile's (or bin's) occluder list; per-tile counters added once per item, the frame's count of
// visible triangles into `vis_tris` (added once per warp).
template <class P, class Team>
TV_HD void occlude_item(const OccArgs<P>& a, uint64_t j, Team team, uint64_t& vis_tris) {
  PEdge<P> local[kTileCap];
  const ItemPieces<P> it = item_pieces<P>(a.src, j, local);
  if (it.count == 0) return;
  const TileTri<P>& tt = a.src.tris[it.tri];
  const bool lead = team.lane() == 0;
  uint32_t tests = 0, visible = 0, triangles = 0;
  for (uint64_t k = 0; k < it.count; ++k) {
    const uint64_t p = it.first + k;
    const PieceView<P> v = piece_of<P>(a.src, it, k, local);
    if (v.n < 3) {  // a float polygon that degenerated: covers nothing
      if (lead) a.visible[p] = 0;
      continue;
    }
    const typename P::R q = P::interior(v.e[0].start, v.e[1].start, v.e[2].start);
    const double qx = P::rx(q), qy = P::ry(q);
    const OccRec* occ = a.occ + a.item_begin[it.tile];
    uint32_t n_occ = a.occ_count[it.tile];
    if (a.bins_x * a.bins_y > 1) {
      const Rect r = a.src.grid.rect(it.tile);
      const uint64_t g = (uint64_t(it.tile) * a.bins_y + bin_at(qy, double(r.y0), a.step_y, a.bins_y)) * a.bins_x +
                         bin_at(qx, double(r.x0), a.step_x, a.bins_x);
      n_occ = a.bin_count[g];
      occ = a.bin_occ + a.bin_begin[g];
    }
    const bool hidden = occluded<P>(q, qx, qy, tt, a.src.tris, occ, n_occ, tests, team);
    if (!lead) continue;
    a.visible[p] = hidden ? 0 : 1;
    if (hidden) continue;
    ++visible;
    triangles += v.n - 2;
    a.area[p] = ddiv(doubled_area<P>(v.e, v.n), a.area_scale);
  }
  if (!lead) return;
  int64_t* row = a.rows + uint64_t(it.tile) * kTileColumns;
  count_add(&row[kColOcclusionTests], tests);
  count_add(&row[kColVisiblePieces], visible);
  vis_tris += triangles;
}

template <class P>
TV_HD void occlude_item_host(const OccArgs<P>& a, uint64_t j) {
  uint64_t vis_tris = 0;
  occlude_item<P>(a, j, HostTeam{}, vis_tris);
  a.counters[kVisibleTriangles] += vis_tris;
}

// Exact: one thread per item (its interior point and tests are too heavy to repeat in 32
// lanes); float: one warp per item.
template <class P>
__global__ void k_occlude(OccArgs<P> a, uint64_t n) {
  uint64_t vis_tris = 0;
  if constexpr (P::kExact) {
    TV_GRID_LOOP(i, n) occlude_item<P>(a, i, HostTeam{}, vis_tris);
  } else {
    TV_WARP_LOOP(w, n) occlude_item<P>(a, w, WarpTeam{}, vis_tris);
  }
  if (vis_tris >> 32) atomic_add(&a.counters[kVisibleTriangles], vis_tris);
  else count_add(&a.counters[kVisibleTriangles], uint32_t(vis_tris));
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
  a.bins_x = p.obins_x;
  a.bins_y = p.obins_y;
  if (p.obins_x * p.obins_y > 1) {
    a.step_x = double(p.obin_w) * s;
    a.step_y = double(p.obin_h) * s;
    a.bin_occ = p.obin_rec.get();
    a.bin_begin = p.obin_begin.get();
    a.bin_count = p.obin_count.get();
  }
  if constexpr (P::kExact) p.ex.launch(k_occlude<P>, occlude_item_host<P>, p.n_items, a);
  else p.ex.launch_warps(k_occlude<P>, occlude_item_host<P>, p.n_items, a);
}

template void stage_occlusion<ExactP>(Pipeline<ExactP>&);
template void stage_occlusion<FloatP>(Pipeline<FloatP>&);

}  // namespace tilevis::cuda
