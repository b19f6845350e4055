// Hybrid mode on the GPU (model/visibility/hybrid_resolver.cpp): every tile gets a verdict
// (stage_verdicts, on side streams 3 and 4 beside the analytic stages, from binning's lists),
// and the tiles whose analytic answer can be wrong are redone per pixel (the exact z-buffer over
// the tile's triangles; stage_per_pixel, beside the analytic stages too: from the start on side
// 5 for causes 2 and 3, which binning's counts decide, after the verdicts on side 3 for cause 1),
// their ids and rows written over the analytic stages' at the end (stage_per_pixel_out) as
// golden's per_pixel resolver sets them:
//   1 interpenetration: two opaque triangles of the tile (other trace triangles) whose planes
//     cross strictly inside their overlap within the tile;
//   2 non-opaque content in the tile;
//   3 budget: triangles x edges over pair_budget, or more triangles or edges than the lists.
// The detector is golden's, step for step, so its work counts (screens, tests) agree: the
// tile's opaque triangles nearest z_min first (the occluder list), detection bins of
// `detection_bin` pixels in row-major order, in each a sweep keeping the triangles whose depth
// range reaches the current one's nearest depth, a pair screened (may_cross, opposite mesh
// neighbours) and tested (planes_cross) in the first bin it shares; the first crossing ends
// the tile's search. A block per tile, its warps taking the bins (bins are independent
// sweeps: see sweep_bins), a warp's lanes the pairs of its bins 32 at a time; a heavy tile's
// block has a warp per bin (k_verdict).
//
// Per-pixel tiles: ids and the tile's samples_covered / fragments_generated from the tile's
// z-buffer (the other per-tile counters are 0, as golden's per_pixel resolver leaves them);
// their triangles' visible areas are the owned samples times a sample's share of a pixel,
// added one sample at a time in the fold (golden's order of additions).
#include "pieces.cuh"

namespace tilevis::cuda {
namespace {

using XTri = TileTri<ExactP>;

template <class P>
struct HybArgs {
  const TileTri<P>* tris;
  const OccRec* occ;
  const uint32_t* item_begin;
  const uint32_t* occ_count;
  const uint32_t* item_tri;
  int64_t* rows;
  TileGrid grid;
  HybridBudget budget;
  uint32_t detection_bin;
  uint32_t* cause;
  uint64_t* screens;
  uint64_t* tests;
  uint32_t* crossing;
  uint32_t* range;   // per occluder position: bins x0, y0, x1, y1 (8 bits each); ~0: empty in the tile
  DetRec* rec;       // per occluder position: its depths, id, triangle and box
  uint8_t* flag;     // per occluder position: in some crossing pair
  uint4* active;     // per warp and occluder position: a detection bin's active members (scratch)
  uint64_t active_stride;  // positions per warp's share of `active`
  uint64_t* batch;   // per tile and warp, kBatchWords x 32 words: the pairs waiting for the exact test
  uint64_t* bin_counts;    // per tile and detection bin, kBinWords: screens and tests (sweep_bins)
  uint32_t bins_per_tile;
  uint32_t* heavy;   // the heavy tiles (k_heavy_list): their count, then the tiles in any order
  // Per-pixel tiles.
  const uint32_t* sample_xy;
  uint32_t n_samples, width, height;
  int32_t* ids;
  uint32_t* owned;  // per item: samples it owns in a per-pixel tile
  uint64_t* shaded;  // per per-pixel tile at 1 sample: pixels shaded (owners, and non-opaque triangles in front)
  uint32_t pp_fw, pp_fh, pp_lfw, pp_ls;  // a fine tile's pixels (64 samples), log2 of its width and of n_samples
  bool pp_narrow;     // depth bits <= 26: depths compared in I128 (pp_order)
  uint64_t* pp_sums;  // per tile, kPPSums words: covered, generated, shaded (zeroed, added to by its regions)
  int32_t* pp_ids;    // per sample, as ids: the per-pixel tiles' owners (per_pixel_out copies them)
};

template <class P>
TV_HD inline XTri exact_of(const TileTri<P>& t) {
  if constexpr (P::kExact) return t;  // already exact
  else return make_tile_tri<ExactP>(t.v[0], t.v[1], t.v[2], t.id, t.opaque != 0);
}

// sign(z_p - z_q) at an implicit point (w > 0): M = alpha x + beta y + gamma w < 2^(100+D),
// M_p area_q - M_q area_p < 2^(150+D) (W256).
TV_HD inline int depth_at(const exact::Plane& p, const exact::Plane& q, const exact::IPoint& s) {
  const W256 mp = exact::plane_numerator<4>(p, s.x, s.y, I128{s.w});
  const W256 mq = exact::plane_numerator<4>(q, s.x, s.y, I128{s.w});
  return (mp * wide<4>(q.area) - mq * wide<4>(p.area)).sign();
}

template <class T, class U>  // TileTri or DetRec
TV_HD inline bool may_cross(const T& t, const U& u) {
  return u.z_min < t.z_max && u.z_max > t.z_min && u.bbox.x1 > t.bbox.x0 && u.bbox.x0 < t.bbox.x1 &&
         u.bbox.y1 > t.bbox.y0 && u.bbox.y0 < t.bbox.y1;
}

template <class P>
TV_HD inline bool opposite_neighbours(const TileTri<P>& t, const TileTri<P>& u) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (t.v[i] == u.v[(j + 1) % 3] && t.v[(i + 1) % 3] == u.v[j]) return true;
  return false;
}

// svgpu::planes_cross: region = t clipped to the tile; the overlap is region clipped by u's
// edges (geom::clip: keep the positive side; nothing strictly positive: empty).
TV_HD inline bool planes_cross(const PEdge<ExactP>* region, uint32_t n, const XTri& t, const XTri& u) {
  if (!may_cross(t, u) || n == 0) return false;
  PEdge<ExactP> a[kTileCap + 4], b[kTileCap + 4];
  for (uint32_t i = 0; i < n; ++i) a[i] = region[i];
  PEdge<ExactP>* cur = a;
  PEdge<ExactP>* next = b;
  for (int k = 0; k < 3; ++k) {
    bool pos, neg;
    line_sides<ExactP>(cur, n, u.edge[k], pos, neg);
    if (!neg) continue;
    if (!pos) return false;
    PolyOut<ExactP> in{next, 0, kTileCap + 4, false}, out{nullptr, 0, 0, false};
    split<ExactP>(cur, n, u.edge[k], in, out);
    n = in.n;
    PEdge<ExactP>* s = cur;
    cur = next;
    next = s;
    if (n == 0) return false;
  }
  bool nearer = false, farther = false;
  for (uint32_t i = 0; i < n; ++i) {
    const int o = depth_at(u.plane, t.plane, cur[i].start);
    nearer = nearer || o < 0;
    farther = farther || o > 0;
  }
  return nearer && farther;
}

// A filter before planes_cross, exact: z_u - z_t is affine, so where it takes no two strict
// signs at a triangle's vertices it takes none over the triangle, which holds the overlap (the
// overlap's vertices are judged by the same sign function, depth_at, at w > 0).
TV_HD inline bool signs_differ_at(const XTri& v, const XTri& t, const XTri& u) {
  bool nearer = false, farther = false;
  for (int i = 0; i < 3; ++i) {
    const int o = depth_at(u.plane, t.plane, exact::IPoint::of(v.v[i].xy()));
    nearer = nearer || o < 0;
    farther = farther || o > 0;
  }
  return nearer && farther;
}
TV_HD inline bool planes_may_cross(const XTri& t, const XTri& u) {
  return signs_differ_at(u, t, u) && signs_differ_at(t, t, u);
}

TV_HD inline uint32_t lowest_bit(uint32_t v) {
#if defined(__CUDA_ARCH__)
  return uint32_t(__ffs(int(v)) - 1);
#else
  return uint32_t(__builtin_ctz(v));
#endif
}

struct Bins {
  uint32_t x, y;
  int64_t step, x0, y0;
  TV_HD uint32_t of(int64_t v, int64_t origin, uint32_t bins) const {
    const int64_t b = v < origin ? 0 : (v - origin) / step;
    return uint32_t(b < 0 ? 0 : b > int64_t(bins) - 1 ? int64_t(bins) - 1 : b);
  }
};

// hybrid_resolver.cpp crossing_pairs, split by detection bin. Golden's sweep visits, in each bin
// (row-major), each member k in list order against the active members a < k, in list order,
// after dropping those whose z_max is not past k's z_min (they never come back: z_min does not
// decrease along the list); the first crossing ends the tile's search. A bin's sweep starts
// from an empty active list, so bins are independent: the tile's counts are the whole counts
// of the bins before the first that has a crossing, plus that bin's counts through it. On the
// GPU a block takes a tile and its warps take the bins (sweep_bins, below); the host sweeps
// them in order. Both test every pair of the tile: the crossing triangles are counted over
// every bin, and the exact tests wait for a full round whatever bin they come from. A round at
// the end of each bin, with a second pass for the crossing tiles, took slivers' k_verdict
// 198 us against 138 (H200, reports/cuda/detector_one_pass_h200.md).

// Warps of a tile's block on the GPU (the bins shared out). 8 and 16 against 4 (H200, hybrid, 15
// scenes, one build, new frame, the verdicts beside the analytic stages): bunny float 1.161 ms at
// 4, 0.875 at 8, 0.814 at 16, million float 4.33 / 4.07 / 3.98; but decals float 0.471 / 0.585
// / 0.608, hot_tile 2.03 / 2.28 / 2.34, slivers 2.63 / 2.80 / 2.89: kept at 4.
inline constexpr uint32_t kDetWarps = 4;

// A tile as the detector sees it: its occluder list (nearest z_min first) and its bins.
template <class P>
struct DetTile {
  uint32_t base, n;
  const OccRec* occ;
  Rect rect;
  Bins g;
};

// The detection bins over a tile's rectangle (the first tile's are the most any tile has).
template <class P>
TV_HD Bins bins_of(const HybArgs<P>& a, const Rect& rect) {
  Bins g;
  const uint32_t tw = a.grid.tile_w, th = a.grid.tile_h;
  g.step = int64_t(a.detection_bin ? a.detection_bin : (tw > th ? tw : th)) << a.grid.sb;
  g.x = uint32_t((int64_t(rect.x1) - rect.x0 + g.step - 1) / g.step);
  g.y = uint32_t((int64_t(rect.y1) - rect.y0 + g.step - 1) / g.step);
  return g;
}

template <class P>
TV_HD DetTile<P> det_tile(const HybArgs<P>& a, uint32_t tile) {
  DetTile<P> d;
  d.base = a.item_begin[tile];
  d.n = a.occ_count[tile];
  d.occ = a.occ + d.base;
  d.rect = a.grid.rect(tile);
  d.g = bins_of(a, d.rect);
  return d;
}

// Positions i0, i0 + stride, ...: their bins (~0: the triangle misses the tile), their records
// (DetRec: what the sweep reads of a member and of an active entry in one load), and the
// crossing flags cleared. Golden clips each triangle to the tile and skips an empty polygon;
// clipping keeps only what is strictly inside each line, so the polygon is empty exactly when
// the interiors of triangle and tile do not meet: binning's exact test (triangle_overlaps_rect),
// at a fraction of the cost of the exact clip.
template <class P>
TV_HD void det_positions(const HybArgs<P>& a, const DetTile<P>& d, uint32_t i0, uint32_t stride) {
  for (uint32_t k = i0; k < d.n; k += stride) {
    const TileTri<P>& t = a.tris[d.occ[k].tri];
    const Bins& g = d.g;
    const Rect& rect = d.rect;
    if (!triangle_overlaps_rect(t.v[0].xy(), t.v[1].xy(), t.v[2].xy(), rect)) {
      a.range[d.base + k] = ~0u;
    } else {
      a.range[d.base + k] = g.of(t.bbox.x0, rect.x0, g.x) | g.of(t.bbox.y0, rect.y0, g.y) << 8 |
                            g.of(t.bbox.x1, rect.x0, g.x) << 16 | g.of(t.bbox.y1, rect.y0, g.y) << 24;
    }
    a.flag[d.base + k] = 0;
    a.rec[d.base + k] = DetRec{t.z_min, t.z_max, t.id, d.occ[k].tri, t.bbox};
  }
}

// A team's sweeps of the bins b0, b0 + bstep, ... of a tile, each with the team's active list
// `act` (the tile's n entries) started empty. The team keeps golden's active list: the lanes
// take 32 of its entries at a time, drop and compact them as golden does (an entry carries
// position, z_max, id and bins in one 16-byte word). Pairs to test wait in the batch (kBatchWords
// x kSize words: the pair, the bin's screens through it, its bin and the bin's tests through it)
// across the team's bins, so that a round of the exact test takes up to kSize pairs in parallel,
// whatever bin they belong to. Every pair is tested and every crossing pair's triangles flagged
// (golden's second, count_all pass), and each bin's record in `counts` (kBinWords words) gets
// the bin's whole screens and tests and, at its first crossing pair, the screens and tests
// through it (tests through 0: no crossing): the tile's verdict and golden's counts, which stop
// at the tile's first crossing (tile_verdict), follow from them.
inline constexpr uint32_t kBatchWords = 3, kBinWords = 4;

// A pair's exact test (planes_cross over t clipped to the tile), out of line so that its wide
// arithmetic's registers do not weigh on the sweep's loop.
template <class P>
#if defined(__CUDACC__)
__noinline__
#endif
TV_HD bool pair_crosses(const TileTri<P>& t, const TileTri<P>& u, const Rect& rect) {
  const XTri xt = exact_of(t), xu = exact_of(u);
  if (!planes_may_cross(xt, xu)) return false;
  PEdge<ExactP> poly[kTileCap];
  bool overflow = false;
  const uint32_t np = tile_polygon<ExactP>(xt, rect, poly, overflow);
  return planes_cross(poly, np, xt, xu);
}

template <class P, class Team>
TV_HD void sweep_bins(const HybArgs<P>& a, const DetTile<P>& d, uint32_t b0, uint32_t bstep, uint4* act,
                      uint64_t* batch, uint64_t* counts, Team team) {
  const uint32_t n = d.n, nbins = d.g.x * d.g.y;
  const Rect rect = d.rect;
  const uint32_t* range = a.range + d.base;
  const DetRec* rec = a.rec + d.base;
  uint8_t* flag = a.flag + d.base;
  const uint32_t lane = team.lane();
  auto in_bin = [](uint32_t r, uint32_t bx, uint32_t by) {
    return r != ~0u && bx >= (r & 0xff) && by >= (r >> 8 & 0xff) && bx <= (r >> 16 & 0xff) && by <= (r >> 24);
  };
  const uint32_t below = (1u << lane) - 1u;  // the lanes before this one
  uint64_t* bpair = batch;                    // per batch entry: position k << 32 | position q
  uint64_t* bscreens = batch + Team::kSize;   // the bin's screens counted through it
  uint64_t* bbin = batch + 2 * Team::kSize;   // its bin << 32 | the bin's tests through it
  uint32_t nb = 0;
  // A round of exact tests over the batch.
  auto flush = [&]() {
    team.sync();  // the batch's entries, written by any lane
    bool cross = false;
    uint32_t k = 0, q = 0;
    if (lane < nb) {
      k = uint32_t(bpair[lane] >> 32);
      q = uint32_t(bpair[lane]);
      cross = pair_crosses(a.tris[rec[k].tri], a.tris[rec[q].tri], rect);
    }
    if (cross) flag[q] = flag[k] = 1;
    // Each bin's first crossing: the batch holds pairs in the bins' order.
    uint32_t cm = team.ballot(cross);
    if (lane == 0) {
      for (; cm != 0; cm &= cm - 1) {
        const uint32_t i = lowest_bit(cm), b = uint32_t(bbin[i] >> 32);
        if (counts[kBinWords * b + 3] == 0) {
          counts[kBinWords * b + 2] = bscreens[i];
          counts[kBinWords * b + 3] = uint32_t(bbin[i]);
        }
      }
    }
    nb = 0;
    team.sync();  // every entry read before the next ones are written
  };
  if (lane == 0)
    for (uint32_t b = b0; b < nbins; b += bstep) counts[kBinWords * b + 3] = 0;
  for (uint32_t b = b0; b < nbins; b += bstep) {
    const uint32_t bx = b % d.g.x, by = b / d.g.x;
    uint64_t s_cnt = 0, t_cnt = 0;
    uint32_t na = 0;
    for (uint32_t k0 = 0; k0 < n; k0 += Team::kSize) {
      // The bin's members among the next kSize positions, then each in list order.
      for (uint32_t mk = team.ballot(k0 + lane < n && in_bin(range[k0 + lane], bx, by)); mk != 0; mk &= mk - 1) {
        const uint32_t k = k0 + lowest_bit(mk), rk = range[k];
        const DetRec t = rec[k];
        uint32_t kept = 0;
        for (uint32_t j0 = 0; j0 < na; j0 += Team::kSize) {
          const uint32_t j = j0 + lane;
          uint4 e{0, 0, 0, 0};
          if (j < na) e = act[j];
          const uint32_t q = e.x;
          const bool keep = j < na && e.y > t.z_min;
          bool screen = false, test = false;
          if (keep && e.z != t.id) {
            screen = true;
            const uint32_t rq = e.w;
            const uint32_t x0 = tmax(rk & 0xff, rq & 0xff), y0 = tmax(rk >> 8 & 0xff, rq >> 8 & 0xff);
            // Decided in the first bin the two share, and only if they may cross.
            if (x0 == bx && y0 == by) {
              const DetRec u = rec[q];
              test = may_cross(t, u) && !opposite_neighbours(a.tris[t.tri], a.tris[u.tri]);
            }
          }
          const uint32_t km = team.ballot(keep), sm = team.ballot(screen), tm = team.ballot(test);
          // Golden's erase. Every lane has read its entry (the ballots order them), and no write
          // goes past the entries already read.
          if (keep) act[kept + popc(km & below)] = e;
          kept += popc(km);
          if (tm != 0) {
            if (nb + popc(tm) > Team::kSize) flush();
            if (test) {
              const uint32_t at = nb + popc(tm & below);
              bpair[at] = uint64_t(k) << 32 | q;
              bscreens[at] = s_cnt + popc(sm & (below << 1 | 1u));
              bbin[at] = uint64_t(b) << 32 | (t_cnt + popc(tm & below) + 1);
            }
            nb += popc(tm);
            t_cnt += popc(tm);
          }
          s_cnt += popc(sm);
        }
        team.sync();
        if (lane == 0) act[kept] = make_uint4(k, t.z_max, t.id, rk);
        na = kept + 1;
        team.sync();
      }
    }
    if (lane == 0) {
      counts[kBinWords * b] = s_cnt;
      counts[kBinWords * b + 1] = t_cnt;
    }
  }
  if (nb != 0) flush();
}

// The causes decided without the detector: 2 (non-opaque content), 3 (budget), else 0.
template <class P>
TV_HD uint32_t cause_of(const HybArgs<P>& a, uint64_t tile) {
  const int64_t* row = a.rows + tile * kTileColumns;
  if (uint64_t(row[kColTriangles]) > a.occ_count[tile]) return 2;  // a non-opaque triangle
  return a.budget.over(row) ? 3 : 0;
}

template <class P>
TV_HD void write_verdict(const HybArgs<P>& a, uint64_t tile, uint32_t cause, uint64_t screens, uint64_t tests,
                         uint32_t crossing) {
  a.cause[tile] = cause;
  a.screens[tile] = screens;
  a.tests[tile] = tests;
  a.crossing[tile] = crossing;
}

// The tile's verdict from its bins' records (sweep_bins) and `crossing`, its flagged triangles:
// golden stops at the first crossing pair in bin order, so its counts are the whole counts of
// the bins before the first bin with a crossing and that bin's counts through it.
template <class P>
TV_HD void tile_verdict(const HybArgs<P>& a, uint64_t tile, uint32_t nbins, const uint64_t* counts, uint32_t crossing) {
  uint64_t screens = 0, tests = 0;
  for (uint32_t b = 0; b < nbins; ++b) {
    const uint64_t* c = counts + kBinWords * b;
    if (c[3] != 0) {
      write_verdict(a, tile, 1, screens + c[2], tests + c[3], crossing);
      return;
    }
    screens += c[0];
    tests += c[1];
  }
  write_verdict(a, tile, 0, screens, tests, 0);
}

template <class P>
TV_HD void verdict_host(const HybArgs<P>& a, uint64_t tile) {
  const uint32_t cause = cause_of(a, tile);
  if (cause != 0) {
    write_verdict(a, tile, cause, 0, 0, 0);
    return;
  }
  const DetTile<P> d = det_tile(a, uint32_t(tile));
  det_positions(a, d, 0, 1);
  uint64_t* counts = a.bin_counts + tile * a.bins_per_tile * kBinWords;
  sweep_bins(a, d, 0, 1, a.active + d.base, a.batch + tile * kDetWarps * kBatchWords * WarpTeam::kSize, counts,
             HostTeam{});
  uint32_t crossing = 0;
  for (uint32_t k = 0; k < d.n; ++k) crossing += a.flag[d.base + k];
  tile_verdict(a, tile, d.g.x * d.g.y, counts, crossing);
}

// Heavy tiles: from kHeavyMin occluders a tile's sweeps are the verdict's longest chains (a warp
// sweeps its bins one member after another), so its bins go to a block of kHeavyWarps warps, a
// warp per bin at 16 bins, with their active lists and batches in shared memory (up to
// kHeavyCap occluders; a tile with more stays with the kDetWarps blocks and global lists). The
// heavy tiles are listed first (k_heavy_list), and their blocks, one an SM, run beside the
// others' (side stream 4). The outputs do not depend on which block takes a tile: each bin's
// sweep is the same.
inline constexpr uint32_t kHeavyWarps = 16, kHeavyMin = 32, kHeavyCap = 768;
inline constexpr size_t kHeavySmem = size_t(kHeavyWarps) * kHeavyCap * sizeof(uint4) +
                                     size_t(kHeavyWarps) * kBatchWords * WarpTeam::kSize * sizeof(uint64_t);

template <class P>
TV_HD bool heavy_tile(const HybArgs<P>& a, uint64_t tile) {
  const uint32_t n = a.occ_count[tile];
  return a.bins_per_tile > kDetWarps && n >= kHeavyMin && n <= kHeavyCap;
}

template <class P>
__global__ void k_heavy_list(HybArgs<P> a, uint64_t n_tiles) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(t, n_tiles) {
    if (cause_of(a, t) == 0 && heavy_tile(a, t)) a.heavy[1 + atomicAdd(a.heavy, 1u)] = uint32_t(t);
  }
}

// A block per tile (Heavy: the listed heavy tiles, kHeavyWarps warps; else the others, kDetWarps
// warps); its warps take the tile's bins w, w + W, ..., each with its own active list and batch;
// once every warp is done, the tile's verdict.
template <class P, bool Heavy>
__global__ void __launch_bounds__((Heavy ? kHeavyWarps : kDetWarps) * 32)
    k_verdict(HybArgs<P> a, uint64_t n_tiles) {
  TV_KERNEL_WAIT();
  constexpr uint32_t W = Heavy ? kHeavyWarps : kDetWarps;
  extern __shared__ uint4 heavy_smem[];  // Heavy: W x kHeavyCap list entries, then W batches
  __shared__ uint32_t found;
  const uint32_t w = threadIdx.x / 32;
  const uint64_t n = Heavy ? a.heavy[0] : n_tiles;
  for (uint64_t i = blockIdx.x; i < n; i += gridDim.x) {
    const uint64_t tile = Heavy ? a.heavy[1 + i] : i;
    if (!Heavy) {
      const uint32_t cause = cause_of(a, tile);
      if (cause != 0) {
        if (threadIdx.x == 0) write_verdict(a, tile, cause, 0, 0, 0);
        continue;  // uniform over the block
      }
      if (heavy_tile(a, tile)) continue;
    }
    const DetTile<P> d = det_tile(a, uint32_t(tile));
    if (threadIdx.x == 0) found = 0;
    det_positions(a, d, threadIdx.x, blockDim.x);
    __syncthreads();
    uint64_t* counts = a.bin_counts + tile * a.bins_per_tile * kBinWords;
    uint4* act;
    uint64_t* batch;
    if constexpr (Heavy) {
      act = heavy_smem + w * kHeavyCap;
      batch = reinterpret_cast<uint64_t*>(heavy_smem + W * kHeavyCap) + w * kBatchWords * WarpTeam::kSize;
    } else {
      act = a.active + uint64_t(w) * a.active_stride + d.base;
      batch = a.batch + (tile * kDetWarps + w) * kBatchWords * WarpTeam::kSize;
    }
    sweep_bins(a, d, w, W, act, batch, counts, WarpTeam{});
    __syncthreads();
    uint32_t mine = 0;
    for (uint32_t k = threadIdx.x; k < d.n; k += blockDim.x) mine += a.flag[d.base + k];
    atomicAdd(&found, mine);
    __syncthreads();
    if (threadIdx.x == 0) tile_verdict(a, tile, d.g.x * d.g.y, counts, found);
    __syncthreads();
  }
}

// ---- per-pixel tiles ------------------------------------------------------------------------

// A tile's item as the per-pixel pass tests it at a sample: its exact edges (positive_edges;
// the top-left rule's owned edges), exact::plane_of's integer part
// (all 0: degenerate) and the closed sub-pixel box. 128 bytes: the GPU stages a block's worth
// in shared memory.
struct alignas(16) PPRec {
  I128 gamma;
  int64_t alpha, beta, area;
  int64_t c[3];
  int32_t ea[3], eb[3];
  int32_t x0, y0, x1, y1;
  uint32_t item, id;  // id: the original (trace) triangle
  uint32_t flags;     // bit k < 3: edge k owns its boundary; kPPOpaque: opaque
};
constexpr uint32_t kPPOpaque = 8;

template <class P>
TV_HD inline PPRec pp_rec(const HybArgs<P>& a, uint32_t item) {
  const TileTri<P>& t = a.tris[a.item_tri[item]];
  const Vtx v0 = t.v[0], v1 = t.v[1], v2 = t.v[2];
  exact::Line e[3];
  positive_edges<ExactP>(v0, v1, v2, e);
  PPRec r;
  r.flags = t.opaque ? kPPOpaque : 0u;
  for (int k = 0; k < 3; ++k) {
    r.ea[k] = int32_t(e[k].a);  // |a|, |b| <= 2^24
    r.eb[k] = int32_t(e[k].b);
    r.c[k] = e[k].c;
    r.flags |= e[k].owns_boundary() ? 1u << k : 0u;
  }
  const exact::IntPlane q = exact::int_plane_of(v0, v1, v2);
  const bool live = q.area != 0;  // plane_of's degenerate plane is all 0
  r.alpha = live ? q.alpha : 0;
  r.beta = live ? q.beta : 0;
  r.gamma = live ? q.gamma : I128{0};
  r.area = q.area;
  r.x0 = t.bbox.x0;
  r.y0 = t.bbox.y0;
  r.x1 = t.bbox.x1;
  r.y1 = t.bbox.y1;
  r.item = item;
  r.id = t.id;
  return r;
}

// Coverage at sample (x, y): the box (a sample outside it is not covered: three edge functions
// spared), then the edge functions with the top-left rule.
TV_HD inline bool pp_covers(const PPRec& r, int64_t x, int64_t y) {
  if (x < r.x0 || x > r.x1 || y < r.y0 || y > r.y1) return false;
  for (int k = 0; k < 3; ++k) {
    const int64_t e = int64_t(r.ea[k]) * x + int64_t(r.eb[k]) * y + r.c[k];
    if (e < 0 || (e == 0 && !((r.flags >> k) & 1u))) return false;
  }
  return true;
}

// The depth numerator at (x, y): z = n / area.
TV_HD inline I128 pp_depth(const PPRec& r, int64_t x, int64_t y) { return I128{r.alpha} * x + I128{r.beta} * y + r.gamma; }

// A sample's owner so far: the first (smallest item) of the nearest opaque items that cover it.
struct alignas(16) PPOwner {
  I128 n;
  int64_t area;
  uint32_t item, id;
};

// sign(z - z_o) (zbuffer::passes): |n| < 2^(51+D), |n area| < 2^(100+D): I128 where `narrow`
// (depth bits D <= 26, as the tiled z-buffer's), else W192.
TV_HD inline int pp_order(const I128& n, int64_t area, const PPOwner& o, bool narrow) {
  if (narrow) {
    const I128 l = n * I128{o.area}, r = o.n * I128{area};
    return l < r ? -1 : l > r ? 1 : 0;
  }
  return (wide<3>(n) * wide<3>(o.area) - wide<3>(o.n) * wide<3>(area)).sign();
}

// Whether (n, area, item) takes the sample from o: nearer, or as near and earlier in the list.
// Golden's loop replaces only on strictly nearer, so it keeps the first of the nearest; the order
// is total, so the owners can be merged in any order.
TV_HD inline bool pp_takes(const I128& n, int64_t area, uint32_t item, const PPOwner& o, bool narrow) {
  if (o.item == kNone) return true;
  const int d = pp_order(n, area, o, narrow);
  return d < 0 || (d == 0 && item < o.item);
}

// The pixels of a tile (cut at the screen).
struct PixSpan {
  int64_t x0, y0, x1, y1;  // inclusive
};

template <class P>
TV_HD inline PixSpan tile_pixels(const HybArgs<P>& a, uint64_t tile) {
  const uint32_t tx = uint32_t(tile % a.grid.tiles_x), ty = uint32_t(tile / a.grid.tiles_x);
  const int64_t x0 = int64_t(tx) * a.grid.tile_w, y0 = int64_t(ty) * a.grid.tile_h;
  return {x0, y0, tmin<int64_t>(x0 + a.grid.tile_w, a.width) - 1, tmin<int64_t>(y0 + a.grid.tile_h, a.height) - 1};
}

template <class P>
TV_HD inline int64_t sample_x(const HybArgs<P>& a, int64_t px, uint32_t k) {
  return (px << a.grid.sb) + (a.sample_xy[k] & 0xffffu);
}
template <class P>
TV_HD inline int64_t sample_y(const HybArgs<P>& a, int64_t py, uint32_t k) {
  return (py << a.grid.sb) + (a.sample_xy[k] >> 16);
}

template <class P>
TV_HD inline uint64_t sample_at(const HybArgs<P>& a, int64_t px, int64_t py, uint32_t k) {
  return (uint64_t(py) * a.width + uint64_t(px)) * a.n_samples + k;
}

constexpr uint32_t kPPSums = 3;  // per tile: covered, generated, shaded (HybArgs::pp_sums)

// A per-pixel tile's row from its sums (pp_sums): the analytic stages ran beside the verdicts
// and counted in it too; golden's per_pixel resolver leaves these counters 0.
template <class P>
TV_HD void finish_tile_row(const HybArgs<P>& a, uint64_t tile) {
  const uint64_t* const sums = a.pp_sums + tile * kPPSums;
  const uint64_t covered = sums[0], generated = sums[1], shaded = sums[2];
  int64_t* r = a.rows + tile * kTileColumns;
  for (int c : {kColPairTests, kColCandidates, kColClips, kColPieces, kColVisiblePieces, kColOcclusionTests}) r[c] = 0;
  r[kColSamplesCovered] = int64_t(covered);
  r[kColFragments] = int64_t(generated);
  a.shaded[tile] = covered + shaded;
}

// A tile's cause in a per-pixel pass (0: not the pass's): the counted tiles' pass takes those
// that binning's counts send per pixel (cause_of), the found tiles' those the detector sent.
template <class P>
TV_HD uint32_t pp_pass_cause(const HybArgs<P>& a, uint64_t tile, PerPixelTiles which) {
  if (which == PerPixelTiles::counted) return cause_of(a, tile);
  return a.cause[tile] == 1 ? 1u : 0u;
}

// Host emulation of a per-pixel tile: golden's loop, sample by sample over the tile's list.
template <class P>
TV_HD void per_pixel_tile(const HybArgs<P>& a, uint64_t tile, PerPixelTiles which) {
  const uint32_t cause = pp_pass_cause(a, tile, which);
  if (cause == 0) return;
  const uint32_t begin = a.item_begin[tile], n = uint32_t(a.rows[tile * kTileColumns + kColTriangles]);
  uint64_t covered = 0, generated = 0, shaded = 0;
  const PixSpan tp = tile_pixels(a, tile);
  for (int64_t py = tp.y0; py <= tp.y1; ++py)
    for (int64_t px = tp.x0; px <= tp.x1; ++px)
      for (uint32_t k = 0; k < a.n_samples; ++k) {
        const int64_t x = sample_x(a, px, k), y = sample_y(a, py, k);
        PPOwner o{0, 0, kNone, 0};
        for (uint32_t i = 0; i < n; ++i) {
          const PPRec r = pp_rec(a, begin + i);
          if (!pp_covers(r, x, y)) continue;
          ++generated;
          const I128 d = pp_depth(r, x, y);
          if ((r.flags & kPPOpaque) && pp_takes(d, r.area, r.item, o, a.pp_narrow)) o = {d, r.area, r.item, r.id};
        }
        covered += o.item != kNone ? 1 : 0;
        // Non-opaque triangles are shaded where they cover the sample in front of its owner
        // (per_pixel_resolver.cpp; at 1 sample a pixel is a sample).
        for (uint32_t i = 0; i < n && cause == 2; ++i) {
          const PPRec r = pp_rec(a, begin + i);
          if (!(r.flags & kPPOpaque) && pp_covers(r, x, y) &&
              (o.item == kNone || pp_order(pp_depth(r, x, y), r.area, o, a.pp_narrow) < 0))
            ++shaded;
        }
        a.pp_ids[sample_at(a, px, py, k)] = o.item == kNone ? -1 : int32_t(o.id);
        if (o.item != kNone) atomic_add(&a.owned[o.item], 1u);
      }
  uint64_t* const sums = a.pp_sums + tile * kPPSums;
  sums[0] = covered;
  sums[1] = generated;
  sums[2] = shaded;
}

// Once the rasters are done: a per-pixel tile's ids over theirs, the samples [k0, k1) of its
// rows of pixels, each row's samples consecutive in the id buffer.
template <class P>
TV_HD void per_pixel_ids(const HybArgs<P>& a, const PixSpan& tp, uint32_t k0, uint32_t k1, uint32_t step) {
  const uint32_t row = uint32_t(tp.x1 - tp.x0 + 1) * a.n_samples;
  for (uint32_t k = k0; k < k1; k += step) {
    const uint64_t at = sample_at(a, tp.x0, tp.y0 + k / row, 0) + k % row;
    a.ids[at] = a.pp_ids[at];
  }
}
template <class P>
TV_HD uint32_t tile_samples(const HybArgs<P>& a, const PixSpan& tp) {
  return uint32_t(tp.x1 - tp.x0 + 1) * uint32_t(tp.y1 - tp.y0 + 1) * a.n_samples;
}

// Host emulation: a per-pixel tile's ids and its row.
template <class P>
void per_pixel_out(const HybArgs<P>& a, uint64_t tile) {
  if (a.cause[tile] == 0) return;
  const PixSpan tp = tile_pixels(a, tile);
  per_pixel_ids(a, tp, 0, tile_samples(a, tp), 1);
  finish_tile_row(a, tile);
}

// ---- per-pixel tiles on the GPU ------------------------------------------------------------
//
// In the manner of the tiled z-buffer's raster (zbuffer.cu): a warp per fine tile of 64 samples
// (8x8 pixels at 1 sample, 8x4 at 2, 4x4 at 4, 4x2 at 8, 2x2 at 16), two samples a lane, and a
// block of kPPWarps per region of 2x2 fine tiles (a 32x32 tile at 1 sample has 4 regions). The
// block runs through the tile's list kPPThreads items at a time: the items whose box meets the
// region are staged in shared memory (list order kept) and each warp takes those whose box meets
// its fine tile, a lane per record: a small one (at most kPPFragMax samples of its box in the
// fine tile) is drawn fragment-parallel, its coverage as bits, then rounds in which every lane
// takes its next covered sample and lanes meeting at one sample take turns; the large ones wait
// in a per-warp list and every lane tests its two samples against each. The owners live in
// shared memory. Fragments count every covering item, opaque or not; at cause 2 a second pass
// counts the non-opaque items in front of the final owners. A tile's counts are added up over
// its regions, and the last region's block writes its row. (Before: three kernels, small items
// drawn by a thread each into owner words by compare-and-swap, large ones by a thread per
// sample, each comparison deriving the owner's plane again, 2.5 to 4x slower than the tiled
// z-buffer; then a block of 16 warps per tile, whose warps waited at its barriers for the
// busiest fine tile: million 0.59 ms on the H200, Nsight Compute.)
constexpr uint32_t kPPWarps = 4, kPPThreads = kPPWarps * 32, kPPFragMax = 16;

// A tile's regions (2x2 fine tiles each), in rows of `x`.
struct PPRegions {
  uint32_t x, n;
};
template <class P>
TV_HD inline PPRegions pp_regions(const HybArgs<P>& a, const PixSpan& tp) {
  const uint32_t nfx = uint32_t(tp.x1 - tp.x0) / a.pp_fw + 1, nfy = uint32_t(tp.y1 - tp.y0) / a.pp_fh + 1;
  return {(nfx + 1) / 2, ((nfx + 1) / 2) * ((nfy + 1) / 2)};
}

#if defined(__CUDACC__)
// A fine tile: pixel origin, its last pixel inside the tile and the screen, log2 of its width.
struct Fine {
  int32_t x0, y0, x1, y1;
  uint32_t lw;
};

// The lane's sample u of the fine tile.
struct PPSample {
  int64_t x, y;
  uint64_t at;
  bool inside;
};

template <class P>
__device__ inline PPSample pp_sample(const HybArgs<P>& a, const Fine& f, uint32_t u) {
  const uint32_t k = u & (a.n_samples - 1), p = u >> a.pp_ls;
  const int32_t px = f.x0 + int32_t(p & ((1u << f.lw) - 1)), py = f.y0 + int32_t(p >> f.lw);
  PPSample s;
  s.inside = px <= f.x1 && py <= f.y1;
  s.x = sample_x(a, px, k);
  s.y = sample_y(a, py, k);
  s.at = s.inside ? sample_at(a, px, py, k) : 0;
  return s;
}

// The record's box in the fine tile's pixels (empty: nx or ny <= 0).
struct PPSpan {
  int32_t px0, py0, nx, ny;
};
template <class P>
__device__ inline PPSpan pp_span(const HybArgs<P>& a, const PPRec& d, const Fine& f) {
  const int sb = int(a.grid.sb);
  const int32_t px0 = tmax(d.x0 >> sb, f.x0), py0 = tmax(d.y0 >> sb, f.y0);
  return {px0, py0, tmin(d.x1 >> sb, f.x1) - px0 + 1, tmin(d.y1 >> sb, f.y1) - py0 + 1};
}

// Whether the fine tile's pixels (on the screen) lie strictly inside all three edges: every
// sample of them is covered.
template <class P>
__device__ inline bool pp_inside(const HybArgs<P>& a, const PPRec& d, const Fine& f) {
  const int sb = int(a.grid.sb);
  const int64_t rx0 = int64_t(f.x0) << sb, ry0 = int64_t(f.y0) << sb;
  const int64_t rx1 = int64_t(f.x1 + 1) << sb, ry1 = int64_t(f.y1 + 1) << sb;
  return rect_inside_edges(d.ea, d.eb, d.c, rx0, ry0, rx1, ry1);
}

// A small record's covered samples of the fine tile, as bits u.
template <class P>
__device__ inline uint64_t pp_coverage(const HybArgs<P>& a, const PPRec& d, const Fine& f, const PPSpan& sp) {
  uint64_t m = 0;
  for (int32_t py = sp.py0; py < sp.py0 + sp.ny; ++py)
    for (int32_t px = sp.px0; px < sp.px0 + sp.nx; ++px)
      for (uint32_t k = 0; k < a.n_samples; ++k)
        if (pp_covers(d, sample_x(a, px, k), sample_y(a, py, k)))
          m |= uint64_t{1} << ((((uint32_t(py - f.y0) << f.lw) + uint32_t(px - f.x0)) << a.pp_ls) + k);
  return m;
}

// The warp's share of a staged chunk of m records: the fragments counted, the owners merged.
template <class P>
__device__ inline uint32_t pp_chunk(const HybArgs<P>& a, const PPRec* rec, uint32_t m, PPOwner* own, uint16_t* large,
                                    const Fine& f, const PPSample& s0, const PPSample& s1) {
  const uint32_t lane = threadIdx.x & 31u;
  uint32_t generated = 0;
  for (uint32_t j0 = 0; j0 < m; j0 += 32) {
    const uint32_t j = j0 + lane;
    uint64_t cov = 0;
    bool big = false, full = false;
    if (j < m) {
      const PPRec& d = rec[j];
      const PPSpan sp = pp_span(a, d, f);
      if (sp.nx > 0 && sp.ny > 0) {
        if ((uint32_t(sp.nx * sp.ny) << a.pp_ls) <= kPPFragMax) {
          cov = pp_coverage(a, d, f, sp);
          generated += uint32_t(__popcll(cov));
          if (!(d.flags & kPPOpaque)) cov = 0;
        } else {
          big = true;
          full = pp_inside(a, d, f);
        }
      }
    }
    const unsigned lm = __ballot_sync(0xffffffffu, big);
    if (big) large[__popc(lm & ((1u << lane) - 1u))] = uint16_t(j | (full ? 0x8000u : 0u));
    warp_fragment_rounds<I128>(
        cov,
        [&](uint32_t u) {
          const PPSample s = pp_sample(a, f, u);
          return pp_depth(rec[j], s.x, s.y);
        },
        [&](uint32_t u, const I128& n) {
          const PPRec& d = rec[j];
          if (pp_takes(n, d.area, d.item, own[u], a.pp_narrow)) own[u] = {n, d.area, d.item, d.id};
        });
    __syncwarp();  // the large list before it is read
    if (lm) {
      PPOwner o0 = own[lane], o1 = own[lane + 32];
      for (uint32_t i = 0, nl = uint32_t(__popc(lm)); i < nl; ++i) {
        const uint32_t e = large[i];
        const PPRec& d = rec[e & 0x7fffu];
        const bool whole = e & 0x8000u;
        auto test = [&](const PPSample& s, PPOwner& o) {
          if (!s.inside || !(whole || pp_covers(d, s.x, s.y))) return;
          ++generated;
          if (!(d.flags & kPPOpaque)) return;
          const I128 n = pp_depth(d, s.x, s.y);
          if (pp_takes(n, d.area, d.item, o, a.pp_narrow)) o = {n, d.area, d.item, d.id};
        };
        test(s0, o0);
        test(s1, o1);
      }
      own[lane] = o0;
      own[lane + 32] = o1;
      __syncwarp();
    }
  }
  return generated;
}

// The warp's share of a staged chunk at cause 2: its samples' non-opaque fragments in front of
// their final owners.
template <class P>
__device__ inline uint32_t pp_shade_chunk(const HybArgs<P>& a, const PPRec* rec, uint32_t m, const PPOwner* own,
                                          const Fine& f, const PPSample& s0, const PPSample& s1) {
  const uint32_t lane = threadIdx.x & 31u;
  uint32_t shaded = 0;
  for (uint32_t j0 = 0; j0 < m; j0 += 32) {
    bool cand = false;
    if (j0 + lane < m) {
      const PPRec& d = rec[j0 + lane];
      const PPSpan sp = pp_span(a, d, f);
      cand = !(d.flags & kPPOpaque) && sp.nx > 0 && sp.ny > 0;
    }
    for (unsigned cm = __ballot_sync(0xffffffffu, cand); cm; cm &= cm - 1) {
      const PPRec& d = rec[j0 + uint32_t(__ffs(cm) - 1)];
      auto shade = [&](const PPSample& s, const PPOwner& o) {
        if (s.inside && pp_covers(d, s.x, s.y) && (o.item == kNone || pp_order(pp_depth(d, s.x, s.y), d.area, o, a.pp_narrow) < 0))
          ++shaded;
      };
      shade(s0, own[lane]);
      shade(s1, own[lane + 32]);
    }
  }
  return shaded;
}

// Window by window over the tile's list: the block finds the items of the next kPPWindow whose
// closed box meets the region's sub-pixel rectangle r (each thread kPPScan positions, their
// loads in flight together; the kept positions appended in any order: the owners' order is
// total and the counts are sums), then stages them kPPThreads at a time and calls `each` (the
// warps' share) with the count staged. Every thread of the block calls it.
constexpr uint32_t kPPScan = 8, kPPWindow = kPPThreads * kPPScan;
template <class P, class Each>
__device__ inline void pp_chunks(const HybArgs<P>& a, uint32_t begin, uint32_t n, const Rect& r, PPRec* rec,
                                 uint32_t* kept, uint32_t* n_kept, Each each) {
  const uint32_t lane = threadIdx.x & 31u;
  for (uint32_t c = 0; c < n; c += kPPWindow) {
    __syncthreads();  // the previous window's records read
    if (threadIdx.x == 0) *n_kept = 0;
    __syncthreads();
    Rect b[kPPScan]{};
#pragma unroll
    for (uint32_t k = 0; k < kPPScan; ++k) {
      const uint32_t i = c + k * kPPThreads + threadIdx.x;
      if (i < n) b[k] = a.tris[a.item_tri[begin + i]].bbox;
    }
#pragma unroll
    for (uint32_t k = 0; k < kPPScan; ++k) {
      const bool keep = c + k * kPPThreads + threadIdx.x < n && b[k].x1 >= r.x0 && b[k].x0 <= r.x1 &&
                        b[k].y1 >= r.y0 && b[k].y0 <= r.y1;
      const unsigned km = __ballot_sync(0xffffffffu, keep);
      uint32_t at = 0;
      if (lane == 0 && km) at = atomicAdd(n_kept, uint32_t(__popc(km)));
      at = __shfl_sync(0xffffffffu, at, 0);
      if (keep) kept[at + uint32_t(__popc(km & ((1u << lane) - 1u)))] = c + k * kPPThreads + threadIdx.x;
    }
    __syncthreads();
    const uint32_t total = *n_kept;
    for (uint32_t s = 0; s < total; s += kPPThreads) {
      const uint32_t m = tmin(kPPThreads, total - s);
      if (s) __syncthreads();  // the previous chunk read
      if (threadIdx.x < m) rec[threadIdx.x] = pp_rec(a, begin + kept[s + threadIdx.x]);
      __syncthreads();
      each(m);
    }
  }
}

// Each of the lane's two samples: its id, and its owner's count (one atomic per owner and warp).
template <class P>
__device__ inline uint32_t pp_finish(const HybArgs<P>& a, const PPSample& s, const PPOwner& o) {
  if (s.inside) a.pp_ids[s.at] = o.item == kNone ? -1 : int32_t(o.id);
  const bool counts = s.inside && o.item != kNone;
  const unsigned cm = __ballot_sync(0xffffffffu, counts);
  if (counts) {
    const unsigned peers = __match_any_sync(cm, o.item);
    if (int(threadIdx.x & 31u) == __ffs(peers) - 1) atomicAdd(&a.owned[o.item], uint32_t(__popc(peers)));
  }
  return counts ? 1u : 0u;
}

// A block per (tile, region); the tile's counts added into a.pp_sums (zeroed before), its ids
// into a.pp_ids. It runs beside the analytic stages, which write every tile's ids and row:
// k_per_pixel_out writes the per-pixel tiles' after them.
template <class P>
__global__ void __launch_bounds__(kPPThreads, 4)
    k_per_pixel(HybArgs<P> a, uint64_t n_tiles, uint32_t regions, PerPixelTiles which) {
  TV_KERNEL_WAIT();
  __shared__ PPRec rec[kPPThreads];
  __shared__ PPOwner owners[kPPWarps][64];
  __shared__ uint16_t large[kPPWarps][32];
  __shared__ uint32_t kept[kPPWindow], n_kept;
  __shared__ unsigned long long sums[3];
  const uint32_t lane = threadIdx.x & 31u, w = threadIdx.x / 32;
  PPOwner* const own = owners[w];
  const uint32_t fw = a.pp_fw, fh = a.pp_fh;
  const int sb = int(a.grid.sb);
  for (uint64_t job = blockIdx.x; job < n_tiles * regions; job += gridDim.x) {
    const uint64_t tile = job / regions;
    const uint32_t region = uint32_t(job % regions);
    const uint32_t cause = pp_pass_cause(a, tile, which);
    if (cause == 0) continue;  // uniform over the block
    const PixSpan tp = tile_pixels(a, tile);
    const PPRegions rg = pp_regions(a, tp);
    if (region >= rg.n) continue;  // an edge tile's
    const uint32_t begin = a.item_begin[tile], n = uint32_t(a.rows[tile * kTileColumns + kColTriangles]);
    // Fine tile (2 rx + (w & 1), 2 ry + (w >> 1)) of the region; the region's pixels.
    const uint32_t rx = region % rg.x, ry = region / rg.x;
    Fine f;
    f.x0 = int32_t(tp.x0) + int32_t((2 * rx + (w & 1)) * fw);
    f.y0 = int32_t(tp.y0) + int32_t((2 * ry + (w >> 1)) * fh);
    f.x1 = tmin(f.x0 + int32_t(fw) - 1, int32_t(tp.x1));
    f.y1 = tmin(f.y0 + int32_t(fh) - 1, int32_t(tp.y1));
    f.lw = a.pp_lfw;
    const bool mine = f.x0 <= f.x1 && f.y0 <= f.y1;  // uniform over the warp
    const int64_t rpx0 = tp.x0 + int64_t(2 * rx * fw), rpy0 = tp.y0 + int64_t(2 * ry * fh);
    const Rect r{int32_t(rpx0 << sb), int32_t(rpy0 << sb),
                 int32_t(((tmin<int64_t>(rpx0 + 2 * fw - 1, tp.x1) + 1) << sb) - 1),
                 int32_t(((tmin<int64_t>(rpy0 + 2 * fh - 1, tp.y1) + 1) << sb) - 1)};
    PPSample s0 = pp_sample(a, f, lane), s1 = pp_sample(a, f, lane + 32);
    s0.inside &= mine;
    s1.inside &= mine;
    own[lane].item = own[lane + 32].item = kNone;
    if (threadIdx.x < 3) sums[threadIdx.x] = 0;
    __syncwarp();
    uint32_t generated = 0, covered = 0, shaded = 0;
    pp_chunks(a, begin, n, r, rec, kept, &n_kept, [&](uint32_t m) {
      if (mine) generated += pp_chunk(a, rec, m, own, large[w], f, s0, s1);
    });
    if (cause == 2)
      pp_chunks(a, begin, n, r, rec, kept, &n_kept, [&](uint32_t m) {
        if (mine) shaded += pp_shade_chunk(a, rec, m, own, f, s0, s1);
      });
    covered += pp_finish(a, s0, own[lane]);
    covered += pp_finish(a, s1, own[lane + 32]);
    for (int off = 16; off > 0; off >>= 1) {
      generated += __shfl_down_sync(0xffffffffu, generated, off);
      covered += __shfl_down_sync(0xffffffffu, covered, off);
      shaded += __shfl_down_sync(0xffffffffu, shaded, off);
    }
    if (lane == 0) {
      atomicAdd(&sums[0], static_cast<unsigned long long>(covered));
      atomicAdd(&sums[1], static_cast<unsigned long long>(generated));
      atomicAdd(&sums[2], static_cast<unsigned long long>(shaded));
    }
    __syncthreads();
    if (threadIdx.x < kPPSums)
      atomicAdd(reinterpret_cast<unsigned long long*>(a.pp_sums + tile * kPPSums) + threadIdx.x, sums[threadIdx.x]);
    __syncthreads();  // the shared words are reused by the next job
  }
}
#endif

// The visible areas again, per original id over its items in canonical order: an analytic
// tile's item adds its visible pieces (fold_area), a per-pixel tile's item its owned samples,
// one sample's share at a time. The totals visible_triangles and max_tile_pieces are counted
// again here over the analytic tiles' items only: golden's per-pixel resolver adds nothing to
// them (FrameOutput: "per-pixel tiles: none"), while the analytic stages ran on every tile.
template <class P>
struct HFoldArgs {
  uint64_t* counters;
  const uint64_t* area_key;
  const uint32_t* area_item;
  const uint64_t* item_key;
  const uint32_t* cause;
  const uint32_t* owned;
  const uint32_t* cand_count;
  const uint32_t* piece_count;
  const uint32_t* item_slot;
  uint64_t n_items;
  const uint8_t* visible;
  const uint16_t* edges;  // per piece: its edge count (occlusion wrote it)
  const double* piece_area;
  double sample_area;
  double* area;
  uint32_t* long_runs;    // GPU: first entries of runs longer than kFoldLong items
  uint64_t* long_count;
};

template <class P>
TV_HD void hybrid_fold(const HFoldArgs<P>& a, uint64_t q) {
  const uint64_t id = a.area_key[q];
  if (q > 0 && a.area_key[q - 1] == id) return;
  double sum = 0;
  uint32_t vis_tris = 0, most_pieces = 0;
  for (uint64_t r = q; a.area_key[r] == id; ++r) {
    const uint32_t j = a.area_item[r];
    if (a.cause[a.item_key[j]] != 0) {
      sum = add_repeated(sum, a.sample_area, a.owned[j]);  // a sample's share at a time
      continue;
    }
    const uint32_t n = a.piece_count[j];
    const bool clipped = a.cand_count[j] != 0;
    // As clip.cu (clipped items) and count_unclipped (an unclipped item's one piece) count it.
    most_pieces = tmax(most_pieces, clipped ? n : n != 0 ? 1u : 0u);
    for (uint32_t k = 0; k < n; ++k) {
      const uint64_t p = clipped ? a.n_items + a.item_slot[j] + k : j;
      if (!a.visible[p]) continue;
      sum = dadd(sum, a.piece_area[p]);
      vis_tris += a.edges[p] - 2u;  // as occ_finish counts a visible piece
    }
  }
  a.area[id] = sum;
  count_add(&a.counters[kVisibleTriangles], vis_tris);
  count_max(&a.counters[kMaxTilePieces], most_pieces);
}

// As raster.cu's fold: on the GPU a run of more than kFoldLong items (a big triangle, one
// item per tile) goes to a block (block_fold_run): its threads gather the run's terms (a
// per-pixel item's one term repeated once per owned sample), one thread adds them in canonical
// order, and the counts are sums and maxima, in any order.

template <class P>
__global__ void k_hybrid_fold(HFoldArgs<P> a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(q, n) {
    if (fold_run_start(a.area_key, q, a.n_items, kFoldLong, a.long_runs, a.long_count) == 1) hybrid_fold<P>(a, q);
  }
}

// An entry's terms for block_fold_run, as hybrid_fold's loop adds them, and the counts of the
// terms this thread loads.
template <class P>
struct HybridFoldTerms {
  static constexpr bool kRepeats = true;
  struct Entry {
    uint64_t base;   // an analytic item's first piece
    uint32_t owned;  // a per-pixel item's samples
    uint8_t per_pixel, clipped;
  };
  const HFoldArgs<P>& a;
  uint32_t vis_tris = 0, most_pieces = 0;
  __device__ Entry entry(uint64_t r, uint32_t& n) {
    const uint32_t j = a.area_item[r];
    if (a.cause[a.item_key[j]] != 0) {
      n = 1;
      return {0, a.owned[j], 1, 0};
    }
    n = a.piece_count[j];
    const bool clipped = a.cand_count[j] != 0;
    most_pieces = tmax(most_pieces, clipped ? n : n != 0 ? 1u : 0u);
    return {clipped ? a.n_items + a.item_slot[j] : j, 0, 0, uint8_t(clipped)};
  }
  __device__ double term(const Entry& e, uint32_t k, uint32_t& repeat) {
    if (e.per_pixel) {
      repeat = e.owned;  // a sample's share at a time
      return a.sample_area;
    }
    const uint64_t p = e.clipped ? e.base + k : e.base;
    const bool v = a.visible[p] != 0;
    const double x = a.piece_area[p];
    if (!v) return -0.0;
    vis_tris += a.edges[p] - 2u;
    return x;
  }
};

template <class P>
__global__ void __launch_bounds__(kFoldBlock) k_hybrid_fold_long(HFoldArgs<P> a, const uint64_t* count, uint64_t cap) {
  TV_KERNEL_WAIT();
  const uint64_t n = *count < cap ? *count : cap;
  for (uint64_t w = blockIdx.x; w < n; w += gridDim.x) {
    const uint64_t q0 = a.long_runs[w];
    HybridFoldTerms<P> src{a};
    const double sum = block_fold_run(a.area_key, q0, a.n_items, src);
    if (threadIdx.x == 0) a.area[a.area_key[q0]] = sum;
    count_add(&a.counters[kVisibleTriangles], src.vis_tris);
    count_max(&a.counters[kMaxTilePieces], src.most_pieces);
  }
}
template <class P>
void hybrid_fold_long_host(const HFoldArgs<P>&, uint64_t) {}  // the host's hybrid_fold folds every run

// A block per per-pixel tile: its ids and row (per_pixel_out).
template <class P>
__global__ void k_per_pixel_out(HybArgs<P> a, uint64_t n_tiles) {
  TV_KERNEL_WAIT();
  for (uint64_t tile = blockIdx.x; tile < n_tiles; tile += gridDim.x) {
    if (a.cause[tile] == 0) continue;  // uniform over the block
    const PixSpan tp = tile_pixels(a, tile);
    per_pixel_ids(a, tp, threadIdx.x, tile_samples(a, tp), blockDim.x);
    if (threadIdx.x == 0) finish_tile_row(a, tile);
  }
}

template <class P>
HybArgs<P> hybrid_args(Pipeline<P>& p) {
  const uint64_t ni = p.n_items, nt = p.n_tiles;
  HybArgs<P> a{};
  a.tris = p.tris.get();
  a.occ = p.occ_rec.get();
  a.item_begin = p.tile_item_begin.get();
  a.occ_count = p.tile_occ_count.get();
  a.item_tri = p.item_tri_sorted.get();
  a.rows = p.tile_rows.get();
  a.grid = p.grid;
  a.budget = hybrid_budget(p.cfg);
  a.detection_bin = p.cfg.detection_bin;
  a.cause = p.hyb_cause.need(nt + 1);
  a.screens = p.hyb_screens.need(nt + 1);
  a.tests = p.hyb_tests.need(nt + 1);
  a.crossing = p.hyb_crossing.need(nt + 1);
  a.range = p.hyb_range.need(ni + 1);
  a.rec = p.hyb_rec.need(ni + 1);
  a.flag = p.hyb_flag.need(ni + 1);
  a.active_stride = ni + 1;
  a.active = p.hyb_active.need(kDetWarps * a.active_stride);
  a.batch = p.hyb_batch.need(nt * kDetWarps * kBatchWords * WarpTeam::kSize + 1);
  {
    const Bins g = bins_of(a, a.grid.rect(0));
    a.bins_per_tile = g.x * g.y;
  }
  a.bin_counts = p.hyb_bin_counts.need(nt * a.bins_per_tile * kBinWords + 1);
  a.heavy = p.hyb_heavy.need(nt + 1);
  a.sample_xy = p.sample_xy.get();
  a.n_samples = p.f.n_samples;
  a.width = p.f.width;
  a.height = p.f.height;
  a.ids = p.ids.get();
  a.owned = p.hyb_owned.need(ni + 1);
  a.shaded = p.hyb_shaded.need(nt + 1);
  // Fine tiles of 64 samples, as the tiled z-buffer's: 8x8 pixels at 1 sample, 8x4 at 2, 4x4 at 4, ...
  a.pp_fw = 8;
  a.pp_fh = 8;
  for (uint32_t s = a.n_samples; s > 1; s >>= 1) (a.pp_fw > a.pp_fh ? a.pp_fw : a.pp_fh) >>= 1;
  a.pp_lfw = bits_for(a.pp_fw) - 1;
  a.pp_ls = bits_for(a.n_samples) - 1;
  a.pp_sums = p.hyb_pp_sums.need(nt * kPPSums + 1);
  a.pp_ids = p.hyb_pp_ids.need(uint64_t(p.f.width) * p.f.height * p.f.n_samples + 1);
  a.pp_narrow = p.f.depth_bits <= 26;
  return a;
}

}  // namespace

template <class P>
void stage_verdicts(Pipeline<P>& p) {
  Exec& ex = p.ex;
  const uint64_t nt = p.n_tiles;
  const HybArgs<P> a = hybrid_args(p);
  if (ex.where == Where::cpu) {  // the host takes every tile as the light blocks do
    for (uint64_t t = 0; t < nt; ++t) verdict_host<P>(a, ex.host_index(t, nt));
    return;
  }
  k_verdict<P, false><<<uint32_t(tmin<uint64_t>(nt, uint64_t(ex.grid_blocks) * 8)), kDetWarps * 32, 0, ex.stream>>>(a, nt);
  TV_CUDA(cudaGetLastError());
  ++ex.queued;
  if (a.bins_per_tile > kDetWarps) {  // else no tile is heavy
    ex.branch(4);  // forked where side 3 was, beside it
    static const bool smem_set = [] {
      TV_CUDA(cudaFuncSetAttribute(k_verdict<P, true>, cudaFuncAttributeMaxDynamicSharedMemorySize, int(kHeavySmem)));
      return true;
    }();
    (void)smem_set;
    ex.zero(a.heavy, 4);
    k_heavy_list<P><<<uint32_t(tmin<uint64_t>((nt + 255) / 256, ex.grid_blocks)), 256, 0, ex.stream>>>(a, nt);
    TV_CUDA(cudaGetLastError());
    k_verdict<P, true><<<ex.grid_blocks / 2, kHeavyWarps * 32, kHeavySmem, ex.stream>>>(a, nt);
    TV_CUDA(cudaGetLastError());
    ex.queued += 2;
    ex.resume(3);
    ex.wait_for(4);  // side 3 goes on with every verdict
  }
}

template <class P>
void stage_per_pixel(Pipeline<P>& p, PerPixelTiles which) {
  Exec& ex = p.ex;
  const uint64_t ni = p.n_items, nt = p.n_tiles;
  const HybArgs<P> a = hybrid_args(p);
  if (which == PerPixelTiles::counted) {  // the first pass zeroes the counts of both
    ex.zero(a.owned, (ni + 1) * 4);
    ex.zero(a.pp_sums, nt * kPPSums * 8);
    p.hyb_pp_zeroed = ex.record();
  } else {
    ex.wait(p.hyb_pp_zeroed);
  }
  if (ex.where == Where::cpu) {
    for (uint64_t t = 0; t < nt; ++t) per_pixel_tile<P>(a, ex.host_index(t, nt), which);
    return;
  }
  const uint32_t S = p.f.n_samples;
  if (S == 0 || S > 16 || (S & (S - 1)) != 0) throw std::runtime_error("cuda hybrid: samples must be 1, 2, 4, 8 or 16");
  // Regions of 2x2 fine tiles: a whole tile's.
  const PPRegions rg = pp_regions(a, PixSpan{0, 0, int64_t(p.grid.tile_w) - 1, int64_t(p.grid.tile_h) - 1});
  k_per_pixel<P><<<uint32_t(tmin<uint64_t>(nt * rg.n, uint64_t(ex.grid_blocks) * 16)), kPPThreads, 0, ex.stream>>>(
      a, nt, rg.n, which);
  TV_CUDA(cudaGetLastError());
  ++ex.queued;
}

template <class P>
void stage_hybrid(Pipeline<P>& p) {
  Exec& ex = p.ex;
  const uint64_t ni = p.n_items;
  const HybArgs<P> a = hybrid_args(p);
  HFoldArgs<P> f{};
  f.counters = p.counters.get();
  // The two totals are counted again by the fold over the analytic tiles only.
  static_assert(kMaxTilePieces == kVisibleTriangles + 1, "adjacent counters");
  ex.zero(p.counters.get() + kVisibleTriangles, 2 * sizeof(uint64_t));
  f.area_key = p.area_key_sorted.get();
  f.area_item = p.area_item_sorted.get();
  f.item_key = p.item_key_sorted.get();
  f.cause = a.cause;
  f.owned = a.owned;
  f.cand_count = p.cand_count.get();
  f.piece_count = p.piece_count.get();
  f.item_slot = p.item_slot.get();
  f.n_items = ni;
  f.visible = p.piece_visible.get();
  f.edges = p.piece_edges.get();
  f.piece_area = p.piece_area.get();
  f.sample_area = 1.0 / double(p.f.n_samples);
  f.area = p.area.get();
  f.long_runs = p.hyb_long_folds.need(ni + 1);
  f.long_count = p.counters.get() + kHybridLongFolds;
  ex.zero(f.long_count, 8);
  ex.launch(k_hybrid_fold<P>, hybrid_fold<P>, p.N(kSzItems, ni), f);
  ex.launch_dyn(k_hybrid_fold_long<P>, hybrid_fold_long_host<P>, f.long_count, ni, f, kFoldBlock, ex.grid_blocks);
}

// Over the rasters' ids and counts (after every other stage): the per-pixel tiles' ids and rows.
template <class P>
void stage_per_pixel_out(Pipeline<P>& p) {
  Exec& ex = p.ex;
  const uint64_t nt = p.n_tiles;
  const HybArgs<P> a = hybrid_args(p);
  if (ex.where == Where::cpu) {
    for (uint64_t t = 0; t < nt; ++t) per_pixel_out<P>(a, ex.host_index(t, nt));
    return;
  }
  k_per_pixel_out<P><<<uint32_t(tmin<uint64_t>(nt, uint64_t(ex.grid_blocks) * 8)), 256, 0, ex.stream>>>(a, nt);
  TV_CUDA(cudaGetLastError());
  ++ex.queued;
}

template void stage_verdicts<ExactP>(Pipeline<ExactP>&);
template void stage_verdicts<FloatP>(Pipeline<FloatP>&);
template void stage_per_pixel<ExactP>(Pipeline<ExactP>&, PerPixelTiles);
template void stage_per_pixel<FloatP>(Pipeline<FloatP>&, PerPixelTiles);
template void stage_per_pixel_out<ExactP>(Pipeline<ExactP>&);
template void stage_per_pixel_out<FloatP>(Pipeline<FloatP>&);
template void stage_hybrid<ExactP>(Pipeline<ExactP>&);
template void stage_hybrid<FloatP>(Pipeline<FloatP>&);

}  // namespace tilevis::cuda
