// Raster and outputs, in the two passes of pieces.cuh: the samples of every piece (a warp
// takes 32 pieces, each lane finding one and staging its lines in shared memory, then the
// warp rasters them one at a time, its lanes over each piece's pixel box inside the tile; a
// sample is covered under the tie rule), the id buffer (per sample, the last visible opaque
// piece in canonical order: within a tile, the highest triangle in setup order, which has the
// largest original id since front triangles are in setup order, kept by atomicMax on the id
// buffer itself, -1 before; non-opaque pieces never own a sample, as in golden and the truth),
// the per-tile sample counters, and the visible area per original triangle folded in
// canonical order (items sorted by id).
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
  int32_t* ids;  // per sample, -1 before any visible piece covers it
  uint64_t base;              // the pass's first piece id (pieces.cuh)
};

// The pixels [px0, px0 + w) x [py0, py0 + h) of a piece's bounding box inside the tile and
// the screen.
struct PixelBox {
  int64_t px0, py0;
  uint32_t w, h;
};

// Coverage of a piece over its pixel box; returns this lane's covered samples. N > 0: the N
// lines `lines`, held in registers; N = 0: the polygon `poly` of n edges, each sample tested
// as covers() does. Exact: the team's lanes take runs of up to kRun pixels of a row at one
// sample position, the edge functions evaluated at the run's first pixel and stepped along
// it, e(x + 2^sb) = e(x) + a 2^sb: exact in int64 (|e| < 2^49, |a 2^sb| <= 2^32), the same
// integer test as covers() under the tie rule (e > 0, or e = 0 on an owned boundary: e > -1).
// Float: the lanes take samples, each evaluated as covers() does.
inline constexpr uint32_t kRun = 8;

// Unit u of a box's runs of up to kRun pixels (run, then sample position, then row): its
// sample k, its row py and its pixels [px0, px_end).
struct Run {
  uint32_t k;
  int64_t px0, px_end, py;
};
TV_HD inline Run run_of(uint32_t u, uint32_t runs, uint32_t S, const PixelBox& b) {
  const uint32_t run = runs == 1 ? 0 : u % runs, rest = runs == 1 ? u : u / runs;
  Run r;
  r.k = S == 1 ? 0 : rest % S;
  r.py = b.py0 + (S == 1 ? rest : rest / S);
  r.px0 = b.px0 + int64_t(run) * kRun;
  r.px_end = tmin<int64_t>(r.px0 + kRun, b.px0 + b.w);
  return r;
}

template <int N, class P, class Team>
TV_HD uint64_t raster_box(const RasterArgs<P>& a, const typename P::Line* lines, const PEdge<P>* poly, uint32_t n,
                          const PixelBox& b, uint32_t tri, bool owns, Team team) {
  [[maybe_unused]] typename P::Line l[N > 0 ? N : 1];
  [[maybe_unused]] int64_t step[N > 0 ? N : 1], floor[N > 0 ? N : 1];
  const uint32_t S = a.n_samples, sb = a.src.grid.sb;
  if constexpr (N > 0)
    for (int i = 0; i < N; ++i) {
      l[i] = lines[i];
      if constexpr (P::kExact) {
        step[i] = l[i].a << sb;
        floor[i] = l[i].owns_boundary() ? -1 : 0;
      }
    }
  uint64_t covered = 0;
  auto hit = [&](int64_t px, int64_t py, uint32_t k) {
    ++covered;
    if (owns) atomic_max(&a.ids[(uint64_t(py) * a.width + uint64_t(px)) * S + k], int32_t(tri));
  };
  if constexpr (P::kExact && N > 0) {
    const uint32_t runs = (b.w + kRun - 1) / kRun;
    const uint32_t units = runs * b.h * S;  // <= 4096 * 4096 * 16
    for (uint32_t u = team.lane(); u < units; u += Team::kSize) {
      const Run ru = run_of(u, runs, S, b);
      const uint32_t k = ru.k;
      const int64_t px0 = ru.px0, px_end = ru.px_end, py = ru.py;
      const uint32_t sxy = a.sample_xy[k];
      const int64_t x0 = (px0 << sb) + (sxy & 0xffffu), y = (py << sb) + (sxy >> 16);
      int64_t e[N];
      for (int i = 0; i < N; ++i) e[i] = l[i].a * x0 + l[i].b * y + l[i].c;
      for (int64_t px = px0; px < px_end; ++px) {
        bool in = true;
        for (int i = 0; i < N; ++i) {
          in &= e[i] > floor[i];
          e[i] += step[i];
        }
        if (in) hit(px, py, k);
      }
    }
    return covered;
  }
  if constexpr (!P::kExact && N > 0) {
    // Float, a box at least a run wide: the same runs, each sample evaluated as covers() does
    // (in_half: eval's rounded products, never fused, so a row's b (y - oy) term is computed
    // once per run, bit for bit). Narrower boxes take a sample per lane (below): runs there
    // leave lanes idle (bunny float raster 0.032 -> 0.049 ms with runs everywhere).
    if (b.w >= kRun) {
      bool owns_b[N];
      for (int i = 0; i < N; ++i) owns_b[i] = l[i].owns_boundary();
      const uint32_t runs = (b.w + kRun - 1) / kRun;
      const uint32_t units = runs * b.h * S;  // <= 4096 * 4096 * 16
      for (uint32_t u = team.lane(); u < units; u += Team::kSize) {
        const Run ru = run_of(u, runs, S, b);
        const uint32_t k = ru.k;
        const int64_t px0 = ru.px0, px_end = ru.px_end, py = ru.py;
        const uint32_t sxy = a.sample_xy[k];
        const int32_t sx = int32_t(sxy & 0xffffu);
        const float fy = float(int32_t((py << sb) + (sxy >> 16)));
        float r[N];
        for (int i = 0; i < N; ++i) r[i] = l[i].row(fy);
        for (int64_t px = px0; px < px_end; ++px) {
          const float fx = float(int32_t((px << sb) + sx));
          bool in = true;
          for (int i = 0; i < N; ++i) {
            const float v = l[i].eval_row(fx, r[i]);
            in &= v > 0 || (v == 0 && owns_b[i]);
          }
          if (in) hit(px, py, k);
        }
      }
      return covered;
    }
  }
  const uint32_t cells = b.w * b.h * S;  // <= 4096 * 4096 * 16
  for (uint32_t c = team.lane(); c < cells; c += Team::kSize) {
    const uint32_t k = S == 1 ? 0 : c % S, pix = S == 1 ? c : c / S;
    const int64_t px = b.px0 + int64_t(pix % b.w), py = b.py0 + int64_t(pix / b.w);
    const uint32_t sxy = a.sample_xy[k];
    const Pt s{int32_t((px << sb) + (sxy & 0xffffu)), int32_t((py << sb) + (sxy >> 16))};
    bool in = true;
    if constexpr (N > 0) {
      for (int i = 0; i < N; ++i) in &= P::in_half(l[i], s);
    } else {
      in = covers<P>(poly, n, s);
    }
    if (in) hit(px, py, k);
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

// A piece as its group's team sees it: pixel box, and its lines in the team's stage (at most
// kStageEdges of them) or, for a clipped piece with more, its polygon in the clip pool.
inline constexpr uint32_t kStageEdges = 8, kRasterBlock = 128;

template <class P>
struct RasterMeta {
  const PEdge<P>* poly;
  PixelBox box;
  uint32_t n, tri, tile;  // n = 0: nothing to raster; tri: the original triangle
  bool vis;   // visible piece: its samples are covered (shaded)
  bool owns;  // visible and opaque: it writes the id buffer
};

// A team's group of `size` (<= kSize) consecutive pieces of the pass, [first, first + size)
// cut at `count`: each of the first `size` lanes finds its piece and stages it; then the team
// rasters the pieces one at a time, its lanes over each piece's samples, so no piece's size
// holds up another's lane. The tile counters are added once per run of pieces of one tile.
template <class P, class Team>
TV_HD void raster_group(const RasterArgs<P>& a, uint64_t first, uint64_t count, uint32_t size,
                        typename P::Line (*lines)[kStageEdges], RasterMeta<P>* meta, Team team) {
  const uint32_t lane = team.lane();
  RasterMeta<P>& mine = meta[lane];
  mine.n = 0;
  if (lane < size && first + lane < count) {
    const uint64_t p = a.base + first + lane;
    PEdge<P> local[kTileCap];
    const PieceView<P> v = piece_at<P>(a.src, p, local);
    if (pixel_box<P>(a, v, mine.box)) {
      mine.poly = v.e;
      mine.n = v.n;
      mine.tri = a.src.tris[v.tri].id;
      mine.tile = v.tile;
      mine.vis = a.visible[p] != 0;
      mine.owns = mine.vis && a.src.tris[v.tri].opaque != 0;
      if (v.n <= kStageEdges)
        for (uint32_t i = 0; i < v.n; ++i) lines[lane][i] = v.e[i].line;
    }
  }
  team.sync();
  uint32_t tile = kNone;
  uint64_t frags = 0, vis_frags = 0;
  auto flush = [&] {
    const uint64_t f = team.sum(frags), vf = team.sum(vis_frags);
    if (lane == 0 && tile != kNone) {
      int64_t* row = a.rows + uint64_t(tile) * kTileColumns;
      atomic_add(&row[kColFragments], int64_t(f));
      atomic_add(&row[kColSamplesCovered], int64_t(vf));
    }
    frags = vis_frags = 0;
  };
  for (uint32_t q = 0; q < size; ++q) {
    const RasterMeta<P> m = meta[q];
    if (m.n == 0) continue;
    if (m.tile != tile) {
      flush();
      tile = m.tile;
    }
    uint64_t c = 0;
    switch (m.n) {
      case 3: c = raster_box<3, P>(a, lines[q], m.poly, m.n, m.box, m.tri, m.owns, team); break;
      case 4: c = raster_box<4, P>(a, lines[q], m.poly, m.n, m.box, m.tri, m.owns, team); break;
      case 5: c = raster_box<5, P>(a, lines[q], m.poly, m.n, m.box, m.tri, m.owns, team); break;
      case 6: c = raster_box<6, P>(a, lines[q], m.poly, m.n, m.box, m.tri, m.owns, team); break;
      case 7: c = raster_box<7, P>(a, lines[q], m.poly, m.n, m.box, m.tri, m.owns, team); break;
      case 8: c = raster_box<8, P>(a, lines[q], m.poly, m.n, m.box, m.tri, m.owns, team); break;
      default: c = raster_box<0, P>(a, nullptr, m.poly, m.n, m.box, m.tri, m.owns, team); break;
    }
    frags += c;
    if (m.vis) vis_frags += c;
  }
  flush();
  team.sync();  // the stage is refilled by the next group
}

// A warp's group holds as many pieces as spread the pass over every warp of the grid, 32 at
// most: with 32 always, a pass of few pieces (broken_mesh's unclipped ones, mostly whole
// tiles) kept under 100 of the grid's 4,224 warps busy, each rastering its 32 pieces one after
// the other (Nsight Compute: k_raster 159 us at 6 % achieved occupancy), and that pass was the
// end of float's frame (its `raster` stage is the wait for it: 0.199 ms against exact's 0.072).
template <class P>
__global__ void __launch_bounds__(kRasterBlock) k_raster(RasterArgs<P> a, const uint64_t* count, uint64_t cap) {
  TV_KERNEL_WAIT();
  __shared__ typename P::Line lines[kRasterBlock / 32][32][kStageEdges];
  __shared__ RasterMeta<P> meta[kRasterBlock / 32][32];
  const uint64_t n = *count < cap ? *count : cap;
  const uint64_t warps = uint64_t(gridDim.x) * (kRasterBlock / 32);
  const uint32_t size = uint32_t(tmin<uint64_t>(32, tmax<uint64_t>(1, (n + warps - 1) / warps)));
  const uint32_t w = threadIdx.x / 32;
  for (uint64_t g = (uint64_t(blockIdx.x) * (kRasterBlock / 32) + w) * size; g < n; g += warps * size)
    raster_group<P>(a, g, n, size, lines[w], meta[w], WarpTeam{});
}

template <class P>
void raster_piece_host(const RasterArgs<P>& a, uint64_t i) {
  typename P::Line lines[1][kStageEdges];
  RasterMeta<P> meta[1];
  raster_group<P>(a, i, i + 1, 1, lines, meta, HostTeam{});
}

template <class P>
struct OutArgs {
  const uint64_t* area_key;   // original id, items sorted by it (stable: canonical order)
  const uint32_t* area_item;
  const uint32_t* cand_count;
  const uint32_t* piece_count;
  const uint32_t* item_slot;
  uint64_t n_items;
  const uint8_t* visible;
  const double* piece_area;
  double* area;
  uint32_t* long_runs;    // GPU: first entries of runs longer than kFoldLong items
  uint64_t* long_count;
};

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
    const uint32_t n = a.piece_count[j];
    const bool clipped = a.cand_count[j] != 0;
    for (uint32_t k = 0; k < n; ++k) {
      const uint64_t p = clipped ? a.n_items + a.item_slot[j] + k : j;
      if (a.visible[p]) {
        sum = dadd(sum, a.piece_area[p]);
        any = true;
      }
    }
  }
  if (any) a.area[id] = sum;
}

// On the GPU a run of more than kFoldLong items (a big triangle: hot_tile's ground has 8,160,
// one per tile) is queued for a block rather than folded by its thread, whose chain of dependent
// loads was the end of those frames (hot_tile float: k_fold_area 1.95 ms beside a 0.16 ms
// raster; at 64, broken_mesh's runs of up to 64 items still took k_fold_area 28 us). The
// block's threads gather the run's terms in parallel and one thread adds them in canonical order
// (block_fold_run, pieces.cuh), so the area is the same double. A warp per run, its lanes
// loading 32 items' values and then adding a clipped item's pieces 32 at a time, took 745 us on
// hot_tile float's ground (the raster stage's whole length). (kFoldLong: pieces.cuh.)

template <class P>
__global__ void k_fold_area(OutArgs<P> a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(q, n) {
    if (fold_run_start(a.area_key, q, a.n_items, kFoldLong, a.long_runs, a.long_count) == 1) fold_area<P>(a, q);
  }
}

// An entry's terms for block_fold_run: its pieces' areas, -0.0 where not visible (fold_area's loop).
template <class P>
struct FoldTerms {
  static constexpr bool kRepeats = false;
  struct Entry {
    uint64_t base;  // its first piece
    bool clipped;
  };
  const OutArgs<P>& a;
  bool any = false;
  __device__ Entry entry(uint64_t r, uint32_t& n) const {
    const uint32_t j = a.area_item[r];
    const bool clipped = a.cand_count[j] != 0;
    n = a.piece_count[j];
    return {clipped ? a.n_items + a.item_slot[j] : j, clipped};
  }
  __device__ double term(const Entry& e, uint32_t k, uint32_t&) {
    const uint64_t p = e.clipped ? e.base + k : e.base;
    const bool v = a.visible[p] != 0;
    const double x = a.piece_area[p];  // loaded beside the flag, not after it
    any = any || v;
    return v ? x : -0.0;
  }
};

template <class P>
__global__ void __launch_bounds__(kFoldBlock) k_fold_long(OutArgs<P> a, const uint64_t* count, uint64_t cap) {
  TV_KERNEL_WAIT();
  const uint64_t n = *count < cap ? *count : cap;
  for (uint64_t w = blockIdx.x; w < n; w += gridDim.x) {
    const uint64_t q0 = a.long_runs[w];
    FoldTerms<P> src{a};
    const double sum = block_fold_run(a.area_key, q0, a.n_items, src);
    if (__syncthreads_or(src.any) && threadIdx.x == 0) a.area[a.area_key[q0]] = sum;
  }
}
template <class P>
void fold_long_host(const OutArgs<P>&, uint64_t) {}  // the host's fold_area folds every run

}  // namespace

template <class P>
void raster_begin(Pipeline<P>& p) {
  const uint64_t n_samples = uint64_t(p.f.width) * p.f.height * p.f.n_samples;
  p.ex.fill_ones(p.ids.need(n_samples + 1), n_samples * 4);  // -1: background
  p.ex.zero(p.area.need(p.f.n_triangles + 1), p.f.n_triangles * 8);
}

template <class P>
void stage_raster(Pipeline<P>& p, Pass pass) {
  RasterArgs<P> a{};
  a.src = piece_source(p);
  a.visible = p.piece_visible.get();
  a.sample_xy = p.sample_xy.get();
  a.n_samples = p.f.n_samples;
  a.width = p.f.width;
  a.height = p.f.height;
  a.rows = p.tile_rows.get();
  a.ids = p.ids.get();
  const PassRange r = pass_range(p, pass);
  a.base = r.base;
  // The unclipped pieces' pass runs beside the clipping; in exact, whose clipping is the longer
  // branch, it takes half the grid (2 blocks of 4 warps per SM), leaving the clipping kernels
  // room (new frame, H200: dragon exact 0.782 -> 0.692 ms, bunny 1.070 -> 0.995; float
  // glass, whose unclipped pass is its critical one, 0.552 -> 0.648 with half the grid).
  const uint32_t blocks = P::kExact && pass == Pass::unclipped ? p.ex.grid_blocks : 0;
  p.ex.launch_dyn(k_raster<P>, raster_piece_host<P>, r.count, r.cap, a, kRasterBlock, blocks);
}

template <class P>
OutArgs<P> out_args(Pipeline<P>& p) {
  OutArgs<P> o{};
  o.area_key = p.area_key_sorted.get();  // ends with a sentinel (binning)
  o.area_item = p.area_item_sorted.get();
  o.cand_count = p.cand_count.get();
  o.piece_count = p.piece_count.get();
  o.item_slot = p.item_slot.get();
  o.n_items = p.n_items;
  o.visible = p.piece_visible.get();
  o.piece_area = p.piece_area.get();
  o.area = p.area.get();  // cleared by raster_begin (side 2, before the area order)
  return o;
}

// Float: the visible pieces whose float area's sign was not proven (marked 2 by occlusion) get
// the exact area of the region their lines bound (poly.cuh), in a kernel of their own so that the
// exact code stays out of the occlusion kernels.
template <class P>
struct ExactAreaArgs {
  PieceSource<P> src;
  const uint8_t* visible;
  double* piece_area;
  uint64_t* counters;
  double area_scale;
};

template <class P>
TV_HD void exact_area(const ExactAreaArgs<P>& a, uint64_t p) {
  if constexpr (!P::kExact) {
    // Slots past those this run used keep an earlier run's flags.
    if (p >= a.src.n_items && p - a.src.n_items >= a.counters[kSlotsUsed]) return;
    if (p < a.src.n_items && p >= *a.src.item_count) return;  // device-sized: past the items there are
    if (a.visible[p] != 2) return;
    PEdge<P> local[kTileCap];
    const PieceView<P> v = piece_at<P>(a.src, p, local);
    bool overflow = false;
    const double x = exact_region_doubled_area<P>(v.e, v.n, a.src.tris[v.tri], a.src.grid.rect(v.tile), overflow);
    if (!overflow) a.piece_area[p] = ddiv(x, a.area_scale);
    count_add(&a.counters[kFloatAnomalies], overflow ? 1u : 0u);
    count_add(&a.counters[kFloatNegativeAreas], a.piece_area[p] < 0 ? 1u : 0u);
  }
}

template <class P>
__global__ void k_exact_area(ExactAreaArgs<P> a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) exact_area<P>(a, i);
}

template <class P>
void stage_fold(Pipeline<P>& p) {
  if constexpr (!P::kExact) {
    ExactAreaArgs<P> e{};
    e.src = piece_source(p);
    e.visible = p.piece_visible.get();
    e.piece_area = p.piece_area.get();
    e.counters = p.counters.get();
    e.area_scale = 2.0 * double(1u << p.f.subpixel_bits) * double(1u << p.f.subpixel_bits);
    p.ex.launch(k_exact_area<P>, exact_area<P>, p.n_items + p.caps.clip_slots, e);
  }
  OutArgs<P> o = out_args(p);
  o.long_runs = p.long_folds.need(p.n_items + 1);
  o.long_count = p.counters.get() + kLongFolds;
  p.ex.launch(k_fold_area<P>, fold_area<P>, p.N(kSzItems, p.n_items), o);
  p.ex.launch_dyn(k_fold_long<P>, fold_long_host<P>, o.long_count, p.n_items, o, kFoldBlock, p.ex.grid_blocks);
}

template void raster_begin<ExactP>(Pipeline<ExactP>&);
template void raster_begin<FloatP>(Pipeline<FloatP>&);
template void stage_raster<ExactP>(Pipeline<ExactP>&, Pass);
template void stage_raster<FloatP>(Pipeline<FloatP>&, Pass);
template void stage_fold<ExactP>(Pipeline<ExactP>&);
template void stage_fold<FloatP>(Pipeline<FloatP>&);

}  // namespace tilevis::cuda
