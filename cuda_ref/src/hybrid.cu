// Hybrid mode on the GPU (model/visibility/hybrid_resolver.cpp): every tile gets a verdict
// (stage_verdicts, on side stream 3 beside the analytic stages, from binning's lists), and after
// the analytic stages the tiles whose analytic answer can be wrong are redone per pixel (the
// exact z-buffer over the tile's triangles), their rows set as golden's per_pixel resolver sets
// them:
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
// sweeps: see bin_sweep), a warp's lanes the pairs of a bin 32 at a time.
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
  uint8_t* flag;     // per occluder position: in some crossing pair (count_all)
  uint4* active;     // per warp and occluder position: a detection bin's active members (scratch)
  uint64_t active_stride;  // positions per warp's share of `active`
  uint64_t* batch;   // per tile and warp, 64 words: the pairs waiting for the exact test (scratch)
  uint64_t* bin_counts;    // per tile and detection bin: screens and tests (GPU scratch)
  uint32_t bins_per_tile;
  // Per-pixel tiles.
  const uint32_t* sample_xy;
  uint32_t n_samples, width, height;
  int32_t* ids;
  uint32_t* owned;  // per item: samples it owns in a per-pixel tile
  uint64_t* shaded;  // per per-pixel tile at 1 sample: pixels shaded (owners, and non-opaque triangles in front)
  uint32_t* big;        // GPU: per per-pixel tile, in its range of item positions, its big items (k_pp_small)
  uint32_t* big_count;  // GPU: per tile, how many
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

template <class P>
TV_HD inline bool may_cross(const TileTri<P>& t, const TileTri<P>& u) {
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
// GPU a block takes a tile and its warps take the bins (bin_sweep, below); the host sweeps
// them in order.

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

// Positions i0, i0 + stride, ...: their bins (~0: the triangle misses the tile), and the
// crossing flags cleared.
template <class P>
TV_HD void det_positions(const HybArgs<P>& a, const DetTile<P>& d, uint32_t i0, uint32_t stride) {
  for (uint32_t k = i0; k < d.n; k += stride) {
    const TileTri<P>& t = a.tris[d.occ[k].tri];
    PEdge<ExactP> poly[kTileCap];
    bool overflow = false;
    const Bins& g = d.g;
    const Rect& rect = d.rect;
    if (tile_polygon<ExactP>(exact_of(t), rect, poly, overflow) == 0) {
      a.range[d.base + k] = ~0u;
    } else {
      a.range[d.base + k] = g.of(t.bbox.x0, rect.x0, g.x) | g.of(t.bbox.y0, rect.y0, g.y) << 8 |
                            g.of(t.bbox.x1, rect.x0, g.x) << 16 | g.of(t.bbox.y1, rect.y0, g.y) << 24;
    }
    a.flag[d.base + k] = 0;
  }
}

// Bin (bx, by)'s sweep by a team, with its own active list `act` (the tile's n entries) and
// batch `bpair` (2 kSize words). The team keeps golden's active list: the lanes take 32 of its
// entries at a time, drop and compact them as golden does (an entry carries position, z_max, id
// and bins in one 16-byte word). Pairs to test wait in the batch, so that a round of the exact
// test takes up to kSize pairs in parallel, whatever member they belong to. Returns true at the
// first crossing (not with count_all: then it marks the crossing triangles' flags), with
// `screens` and `tests` counted through it; else the bin's whole counts.
template <class P, class Team>
TV_HD bool bin_sweep(const HybArgs<P>& a, const DetTile<P>& d, uint32_t bx, uint32_t by, bool count_all, uint4* act,
                     uint64_t* bpair, uint64_t& screens, uint64_t& tests, Team team) {
  const uint32_t n = d.n;
  const OccRec* occ = d.occ;
  const Rect rect = d.rect;
  const uint32_t* range = a.range + d.base;
  uint8_t* flag = a.flag + d.base;
  const uint32_t lane = team.lane();
  auto in_bin = [](uint32_t r, uint32_t bx, uint32_t by) {
    return r != ~0u && bx >= (r & 0xff) && by >= (r >> 8 & 0xff) && bx <= (r >> 16 & 0xff) && by <= (r >> 24);
  };
  const uint32_t below = (1u << lane) - 1u;  // the lanes before this one
  uint64_t* bscreens = bpair + Team::kSize;  // per batch entry: the screens counted through it
  uint32_t nb = 0;
  uint64_t s_cnt = 0, t_cnt = 0;
  // The batch's tests; true at a crossing that ends the search (not with count_all).
  auto flush = [&]() -> bool {
    team.sync();  // the batch's entries, written by any lane
    bool cross = false;
    uint32_t k = 0, q = 0;
    if (lane < nb) {
      k = uint32_t(bpair[lane] >> 32);
      q = uint32_t(bpair[lane]);
      const XTri xt = exact_of(a.tris[occ[k].tri]), xu = exact_of(a.tris[occ[q].tri]);
      if (planes_may_cross(xt, xu)) {
        PEdge<ExactP> poly[kTileCap];
        bool overflow = false;
        const uint32_t np = tile_polygon<ExactP>(xt, rect, poly, overflow);
        cross = planes_cross(poly, np, xt, xu);
      }
    }
    const uint32_t cm = team.ballot(cross);
    if (count_all) {
      if (cross) flag[q] = flag[k] = 1;
    } else if (cm != 0) {
      const uint32_t first = lowest_bit(cm);
      s_cnt = bscreens[first];
      t_cnt += first + 1;
      return true;
    }
    t_cnt += nb;
    nb = 0;
    team.sync();  // every entry read before the next ones are written
    return false;
  };
  uint32_t na = 0;
  for (uint32_t k0 = 0; k0 < n; k0 += Team::kSize) {
    // The bin's members among the next kSize positions, then each in list order.
    for (uint32_t mk = team.ballot(k0 + lane < n && in_bin(range[k0 + lane], bx, by)); mk != 0; mk &= mk - 1) {
      const uint32_t k = k0 + lowest_bit(mk), rk = range[k];
      const TileTri<P>& t = a.tris[occ[k].tri];
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
          test = x0 == bx && y0 == by && may_cross(t, a.tris[occ[q].tri]) && !opposite_neighbours(t, a.tris[occ[q].tri]);
        }
        const uint32_t km = team.ballot(keep), sm = team.ballot(screen), tm = team.ballot(test);
        // Golden's erase. Every lane has read its entry (the ballots order them), and no write
        // goes past the entries already read.
        if (keep) act[kept + popc(km & below)] = e;
        kept += popc(km);
        if (tm != 0) {
          if (nb + popc(tm) > Team::kSize && flush()) {
            screens = s_cnt;
            tests = t_cnt;
            return true;
          }
          if (test) {
            const uint32_t at = nb + popc(tm & below);
            bpair[at] = uint64_t(k) << 32 | q;
            bscreens[at] = s_cnt + popc(sm & (below << 1 | 1u));
          }
          nb += popc(tm);
        }
        s_cnt += popc(sm);
      }
      team.sync();
      if (lane == 0) act[kept] = make_uint4(k, t.z_max, t.id, rk);
      na = kept + 1;
      team.sync();
    }
  }
  const bool crossed = nb != 0 && flush();
  screens = s_cnt;
  tests = t_cnt;
  return crossed;
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

template <class P>
TV_HD void verdict_host(const HybArgs<P>& a, uint64_t tile) {
  uint32_t cause = cause_of(a, tile), crossing = 0;
  uint64_t screens = 0, tests = 0;
  if (cause == 0) {
    const DetTile<P> d = det_tile(a, uint32_t(tile));
    det_positions(a, d, 0, 1);
    uint4* act = a.active + d.base;
    uint64_t* bpair = a.batch + tile * kDetWarps * 2 * WarpTeam::kSize;
    for (uint32_t b = 0; b < d.g.x * d.g.y && cause == 0; ++b) {
      uint64_t s = 0, t = 0;
      if (bin_sweep(a, d, b % d.g.x, b / d.g.x, false, act, bpair, s, t, HostTeam{})) cause = 1;
      screens += s;
      tests += t;
    }
    if (cause == 1) {
      for (uint32_t b = 0; b < d.g.x * d.g.y; ++b) {
        uint64_t s = 0, t = 0;
        bin_sweep(a, d, b % d.g.x, b / d.g.x, true, act, bpair, s, t, HostTeam{});
      }
      for (uint32_t k = 0; k < d.n; ++k) crossing += a.flag[d.base + k];
    }
  }
  write_verdict(a, tile, cause, screens, tests, crossing);
}

// A block per tile; its warps take the tile's bins w, w + kDetWarps, ..., each with its own
// active list and batch. A warp stops at its first crossing bin, or when another warp has
// found one in an earlier bin (the bins after the first crossing one are not counted); the
// bins' counts are summed up to the first crossing bin once every warp is done.
template <class P>
__global__ void __launch_bounds__(kDetWarps * 32) k_verdict(HybArgs<P> a, uint64_t n_tiles) {
  TV_KERNEL_WAIT();
  __shared__ uint32_t first;  // the first bin (row-major) with a crossing; ~0: none
  __shared__ uint32_t found;
  const uint32_t w = threadIdx.x / 32, lane = threadIdx.x & 31u;
  for (uint64_t tile = blockIdx.x; tile < n_tiles; tile += gridDim.x) {
    const uint32_t cause = cause_of(a, tile);
    if (cause != 0) {
      if (threadIdx.x == 0) write_verdict(a, tile, cause, 0, 0, 0);
      continue;  // uniform over the block
    }
    const DetTile<P> d = det_tile(a, uint32_t(tile));
    const uint32_t nbins = d.g.x * d.g.y;
    if (threadIdx.x == 0) {
      first = ~0u;
      found = 0;
    }
    det_positions(a, d, threadIdx.x, blockDim.x);
    __syncthreads();
    uint4* act = a.active + uint64_t(w) * a.active_stride + d.base;
    uint64_t* bpair = a.batch + (tile * kDetWarps + w) * 2 * WarpTeam::kSize;
    uint64_t* counts = a.bin_counts + tile * a.bins_per_tile * 2;
    for (uint32_t b = w; b < nbins; b += kDetWarps) {
      const uint32_t seen = __shfl_sync(0xffffffffu, lane == 0 ? atomicAdd(&first, 0u) : 0u, 0);
      if (b > seen) break;  // an earlier bin has a crossing (one value for the whole warp)
      uint64_t s = 0, t = 0;
      const bool crossed = bin_sweep(a, d, b % d.g.x, b / d.g.x, false, act, bpair, s, t, WarpTeam{});
      if (lane == 0) {
        counts[2 * b] = s;
        counts[2 * b + 1] = t;
        if (crossed) atomicMin(&first, b);
      }
      if (crossed) break;
    }
    __syncthreads();
    const uint32_t f = first;
    if (f != ~0u) {  // the crossing triangles, over every bin
      for (uint32_t b = w; b < nbins; b += kDetWarps) {
        uint64_t s = 0, t = 0;
        bin_sweep(a, d, b % d.g.x, b / d.g.x, true, act, bpair, s, t, WarpTeam{});
      }
      __syncthreads();
      uint32_t mine = 0;
      for (uint32_t k = threadIdx.x; k < d.n; k += blockDim.x) mine += a.flag[d.base + k];
      atomicAdd(&found, mine);
    }
    __syncthreads();
    if (threadIdx.x == 0) {
      uint64_t screens = 0, tests = 0;
      for (uint32_t b = 0; b < nbins && b <= f; ++b) {
        screens += counts[2 * b];
        tests += counts[2 * b + 1];
      }
      write_verdict(a, tile, f != ~0u ? 1u : 0u, screens, tests, f != ~0u ? found : 0u);
    }
    __syncthreads();
  }
}

// ---- per-pixel tiles ------------------------------------------------------------------------

// One binned triangle at one sample: coverage (top-left), the depth test of zbuffer.h.
struct PTri {
  exact::Line e[3];
  exact::Plane plane;
  Rect bbox;  // closed: a sample outside it is not covered (three edge functions spared)
  uint32_t opaque, item;
};

struct POwner {
  const exact::Plane* plane = nullptr;
  int64_t item = -1;
};

TV_HD inline bool covers(const PTri& t, Pt s) {
  if (s.x < t.bbox.x0 || s.x > t.bbox.x1 || s.y < t.bbox.y0 || s.y > t.bbox.y1) return false;
  for (int k = 0; k < 3; ++k) {
    const int64_t e = t.e[k].eval(s);
    if (e < 0 || (e == 0 && !t.e[k].owns_boundary())) return false;
  }
  return true;
}

template <class P>
TV_HD inline PTri ptri_of(const HybArgs<P>& a, uint32_t item) {
  const XTri x = exact_of(a.tris[a.item_tri[item]]);
  PTri t;
  for (int k = 0; k < 3; ++k) t.e[k] = x.edge[k];
  t.plane = x.plane;
  t.bbox = x.bbox;
  t.opaque = x.opaque;
  t.item = item;
  return t;
}

// The pixels of the tile whose samples may lie in a closed sub-pixel box: a sample of pixel p
// lies in [p << sb, (p + 1) << sb).
struct PixSpan {
  int64_t x0, y0, x1, y1;  // inclusive; empty where x0 > x1 or y0 > y1
  TV_HD uint64_t samples(uint32_t n_samples) const {
    return x0 > x1 || y0 > y1 ? 0 : uint64_t(x1 - x0 + 1) * uint64_t(y1 - y0 + 1) * n_samples;
  }
};

template <class P>
TV_HD inline PixSpan pix_span(const HybArgs<P>& a, const Rect& box, const PixSpan& tile) {
  const int sb = int(a.grid.sb);
  return {tmax<int64_t>(tile.x0, int64_t(box.x0) >> sb), tmax<int64_t>(tile.y0, int64_t(box.y0) >> sb),
          tmin<int64_t>(tile.x1, int64_t(box.x1) >> sb), tmin<int64_t>(tile.y1, int64_t(box.y1) >> sb)};
}

template <class P>
TV_HD inline PixSpan tile_pixels(const HybArgs<P>& a, uint64_t tile) {
  const uint32_t tx = uint32_t(tile % a.grid.tiles_x), ty = uint32_t(tile / a.grid.tiles_x);
  const int64_t x0 = int64_t(tx) * a.grid.tile_w, y0 = int64_t(ty) * a.grid.tile_h;
  return {x0, y0, tmin<int64_t>(x0 + a.grid.tile_w, a.width) - 1, tmin<int64_t>(y0 + a.grid.tile_h, a.height) - 1};
}

// Sample u of a span, row-major pixels, samples within a pixel.
TV_HD inline void span_sample(const PixSpan& sp, uint32_t n_samples, uint64_t u, int64_t& px, int64_t& py,
                              uint32_t& k) {
  const uint64_t w = uint64_t(sp.x1 - sp.x0 + 1);
  k = uint32_t(u % n_samples);
  px = sp.x0 + int64_t((u / n_samples) % w);
  py = sp.y0 + int64_t((u / n_samples) / w);
}

template <class P>
TV_HD inline Pt sample_pt(const HybArgs<P>& a, int64_t px, int64_t py, uint32_t k) {
  const uint32_t sxy = a.sample_xy[k];
  return {int32_t((px << a.grid.sb) + (sxy & 0xffffu)), int32_t((py << a.grid.sb) + (sxy >> 16))};
}

template <class P>
TV_HD inline uint64_t sample_at(const HybArgs<P>& a, int64_t px, int64_t py, uint32_t k) {
  return (uint64_t(py) * a.width + uint64_t(px)) * a.n_samples + k;
}

// sign(z_p(s) - z_q(s)) at a sample (zbuffer::passes): |N| < 2^(51+D), |N area| < 2^(100+D) (W192).
TV_HD inline int sample_depth_order(const exact::Plane& p, const exact::Plane& q, Pt s) {
  const I128 np = I128{p.alpha} * s.x + I128{p.beta} * s.y + p.gamma;
  const I128 nq = I128{q.alpha} * s.x + I128{q.beta} * s.y + q.gamma;
  return (wide<3>(np) * wide<3>(q.area) - wide<3>(nq) * wide<3>(p.area)).sign();
}

TV_HD inline void test(const PTri& t, Pt s, POwner& o, uint32_t& generated) {
  if (!covers(t, s)) return;
  ++generated;
  if (!t.opaque) return;
  if (o.item < 0 || sample_depth_order(t.plane, *o.plane, s) < 0) {
    o.item = t.item;
    o.plane = &t.plane;
  }
}

// A per-pixel tile's row: the analytic stages ran beside the verdicts and counted in it too;
// golden's per_pixel resolver leaves these counters 0.
template <class P>
TV_HD void finish_tile_row(const HybArgs<P>& a, uint64_t tile, uint64_t covered, uint64_t generated, uint64_t shaded) {
  int64_t* r = a.rows + tile * kTileColumns;
  for (int c : {kColPairTests, kColCandidates, kColClips, kColPieces, kColVisiblePieces, kColOcclusionTests}) r[c] = 0;
  r[kColSamplesCovered] = int64_t(covered);
  r[kColFragments] = int64_t(generated);
  a.shaded[tile] = covered + shaded;
}

// Host emulation of a per-pixel tile.
template <class P>
TV_HD void per_pixel_tile(const HybArgs<P>& a, uint64_t tile) {
  if (a.cause[tile] == 0) return;
  int64_t* row = a.rows + tile * kTileColumns;
  const uint32_t begin = a.item_begin[tile], n = uint32_t(row[kColTriangles]);
  uint64_t covered = 0, generated = 0, shaded = 0;
  const PixSpan tp = tile_pixels(a, tile);
  for (uint64_t u = 0; u < tp.samples(a.n_samples); ++u) {
    int64_t px, py;
    uint32_t k;
    span_sample(tp, a.n_samples, u, px, py, k);
    const Pt s = sample_pt(a, px, py, k);
    POwner o;
    PTri held;  // the owner's record (o.plane points into it)
    uint32_t g = 0;
    for (uint32_t i = 0; i < n; ++i) {
      const PTri t = ptri_of(a, begin + i);
      const int64_t before = o.item;
      test(t, s, o, g);
      if (o.item != before) {
        held = t;
        o.plane = &held.plane;
      }
    }
    generated += g;
    covered += o.item >= 0 ? 1 : 0;
    // Non-opaque triangles are shaded where they cover the sample in front of its owner
    // (per_pixel_resolver.cpp; at 1 sample a pixel is a sample).
    for (uint32_t i = 0; i < n && a.cause[tile] == 2; ++i) {
      const PTri t = ptri_of(a, begin + i);
      if (!t.opaque && covers(t, s) && (o.item < 0 || sample_depth_order(t.plane, *o.plane, s) < 0)) ++shaded;
    }
    const uint64_t at = sample_at(a, px, py, k);
    a.ids[at] = o.item < 0 ? -1 : int32_t(a.tris[a.item_tri[o.item]].id);
    if (o.item >= 0) atomic_add(&a.owned[o.item], 1u);
  }
  finish_tile_row(a, tile, covered, generated, shaded);
}

// ---- per-pixel tiles on the GPU ------------------------------------------------------------
//
// While a tile is drawn, its samples' entries of the id buffer hold the owning item (-1: none).
// The owner of a sample is the first of the nearest opaque items that cover it in the tile's list
// (golden's loop replaces only on strictly nearer): the order (depth, list position) is total, so
// owners can be merged in any order, by compare-and-swap. Three kernels:
//  1 a block per tile: the owner words cleared; each small item (a box of at most kPixBig
//    samples: the sub-pixel triangles of an overloaded tile) drawn by a thread over its box; the
//    big ones listed;
//  2 a block per kPixBlock samples of a tile: a thread per sample runs through the tile's big
//    items (staged kPixChunk at a time), keeps the nearest, and merges it into the owner word;
//  3 a block per kPixBlock samples: non-opaque items' shaded samples (cause 2), each owner
//    replaced by its id, the samples owned and covered counted.
// (One kernel with a thread per sample that ran through the whole list: slivers float 0.90 ms
// on the H200, Nsight Compute, for tiles of thousands of dust triangles; one block per tile
// drawing every item by compare-and-swap: stack 5x slower, its tiles' thousands of big quads.)
constexpr uint32_t kPixThreads = 256, kPixBig = 64, kPixBlock = 256, kPixChunk = 32;

template <class P>
TV_HD inline exact::Plane exact_plane(const TileTri<P>& t) {
  if constexpr (P::kExact) return t.plane;
  else return exact::plane_of(t.v[0], t.v[1], t.v[2]);
}

// Owner word at `at` for opaque item `item` (plane `pl`) at sample s: taken where the item is
// nearer, or as near and earlier in the list.
template <class P>
__device__ inline void merge_owner(const HybArgs<P>& a, uint64_t at, uint32_t item, const exact::Plane& pl, Pt s) {
  int* const w = reinterpret_cast<int*>(a.ids) + at;
  int cur = atomicAdd(w, 0);
  for (;;) {
    if (cur >= 0) {
      if (uint32_t(cur) == item) return;
      const int d = sample_depth_order(pl, exact_plane(a.tris[a.item_tri[cur]]), s);
      if (d > 0 || (d == 0 && uint32_t(cur) < item)) return;  // the owner stays
    }
    const int seen = atomicCAS(w, cur, int(item));
    if (seen == cur) return;
    cur = seen;
  }
}

// 1: a block per tile. Row: the analytic columns 0, the small items' fragments; big items go
// to the tile's list (a.big, in the tile's range of item positions; a.big_count per tile).
template <class P>
__global__ void __launch_bounds__(kPixThreads) k_pp_small(HybArgs<P> a, uint64_t n_tiles) {
  TV_KERNEL_WAIT();
  __shared__ uint32_t n_big;
  __shared__ unsigned long long generated_sum;
  const uint32_t S = a.n_samples;
  for (uint64_t tile = blockIdx.x; tile < n_tiles; tile += gridDim.x) {
    if (a.cause[tile] == 0) continue;  // uniform over the block
    const uint32_t begin = a.item_begin[tile], n = uint32_t(a.rows[tile * kTileColumns + kColTriangles]);
    const PixSpan tp = tile_pixels(a, tile);
    if (threadIdx.x == 0) {
      n_big = 0;
      generated_sum = 0;
    }
    for (uint64_t u = threadIdx.x; u < tp.samples(S); u += blockDim.x) {
      int64_t px, py;
      uint32_t k;
      span_sample(tp, S, u, px, py, k);
      a.ids[sample_at(a, px, py, k)] = -1;
    }
    __syncthreads();
    uint32_t generated = 0;
    for (uint32_t i = threadIdx.x; i < n; i += blockDim.x) {
      const PixSpan sp = pix_span(a, a.tris[a.item_tri[begin + i]].bbox, tp);
      const uint64_t m = sp.samples(S);
      if (m > kPixBig) {
        a.big[begin + atomicAdd(&n_big, 1u)] = begin + i;
        continue;
      }
      if (m == 0) continue;
      const PTri t = ptri_of(a, begin + i);
      for (uint64_t u = 0; u < m; ++u) {
        int64_t px, py;
        uint32_t k;
        span_sample(sp, S, u, px, py, k);
        const Pt s = sample_pt(a, px, py, k);
        if (!covers(t, s)) continue;
        ++generated;
        if (t.opaque) merge_owner(a, sample_at(a, px, py, k), t.item, t.plane, s);
      }
    }
    atomicAdd(&generated_sum, static_cast<unsigned long long>(generated));
    __syncthreads();
    if (threadIdx.x == 0) {
      finish_tile_row(a, tile, 0, generated_sum, 0);  // kernel 3 adds the covered and shaded samples
      a.big_count[tile] = n_big;
    }
    __syncthreads();  // the shared words are reused by the next tile
  }
}

// Sample (tile, part, thread) of a per-pixel tile; false past the tile's samples.
template <class P>
__device__ inline bool pp_sample(const HybArgs<P>& a, uint64_t tile, uint32_t part, int64_t& px, int64_t& py,
                                 uint32_t& k) {
  const PixSpan tp = tile_pixels(a, tile);
  const uint64_t u = uint64_t(part) * kPixBlock + threadIdx.x;
  if (u >= tp.samples(a.n_samples)) return false;
  span_sample(tp, a.n_samples, u, px, py, k);
  return true;
}

// Items item_at(0 .. n - 1), staged kPixChunk at a time in shared memory, each given to `each`
// by every thread of the block.
template <class P, class At, class Each>
__device__ inline void staged_items(const HybArgs<P>& a, uint32_t n, PTri* staged, At item_at, Each each) {
  for (uint32_t c = 0; c < n; c += kPixChunk) {
    const uint32_t m = tmin(kPixChunk, n - c);
    __syncthreads();
    if (threadIdx.x < m) staged[threadIdx.x] = ptri_of(a, item_at(c + threadIdx.x));
    __syncthreads();
    for (uint32_t j = 0; j < m; ++j) each(staged[j]);
  }
}

// 2: the big items, a thread per sample.
template <class P>
__global__ void __launch_bounds__(kPixBlock) k_pp_big(HybArgs<P> a, uint64_t n_tiles, uint32_t parts) {
  TV_KERNEL_WAIT();
  __shared__ PTri staged[kPixChunk];
  __shared__ unsigned long long generated_sum;
  for (uint64_t job = blockIdx.x; job < n_tiles * parts; job += gridDim.x) {
    const uint64_t tile = job / parts;
    if (a.cause[tile] == 0) continue;  // uniform over the block
    const uint32_t nb = a.big_count[tile];
    if (nb == 0) continue;
    if (threadIdx.x == 0) generated_sum = 0;
    int64_t px = 0, py = 0;
    uint32_t k = 0;
    const bool mine = pp_sample(a, tile, uint32_t(job % parts), px, py, k);
    const Pt s = mine ? sample_pt(a, px, py, k) : Pt{0, 0};
    uint32_t generated = 0, best = ~0u;
    exact::Plane best_plane{};
    const uint32_t* const big = a.big + a.item_begin[tile];
    staged_items(a, nb, staged, [&](uint32_t x) { return big[x]; }, [&](const PTri& t) {
      if (!mine || !covers(t, s)) return;
      ++generated;
      if (!t.opaque) return;
      if (best != ~0u) {
        const int d = sample_depth_order(t.plane, best_plane, s);
        if (d > 0 || (d == 0 && best < t.item)) return;
      }
      best = t.item;
      best_plane = t.plane;
    });
    if (mine && best != ~0u) merge_owner(a, sample_at(a, px, py, k), best, best_plane, s);
    atomicAdd(&generated_sum, static_cast<unsigned long long>(generated));
    __syncthreads();
    if (threadIdx.x == 0)
      atomicAdd(reinterpret_cast<unsigned long long*>(&a.rows[tile * kTileColumns + kColFragments]), generated_sum);
    __syncthreads();
  }
}

// 3: the owners final: non-opaque items' shading (cause 2), ids, owned and covered samples.
template <class P>
__global__ void __launch_bounds__(kPixBlock) k_pp_finish(HybArgs<P> a, uint64_t n_tiles, uint32_t parts) {
  TV_KERNEL_WAIT();
  __shared__ PTri staged[kPixChunk];
  __shared__ unsigned long long sums[2];
  for (uint64_t job = blockIdx.x; job < n_tiles * parts; job += gridDim.x) {
    const uint64_t tile = job / parts;
    const uint32_t cause = a.cause[tile];
    if (cause == 0) continue;  // uniform over the block
    if (threadIdx.x == 0) sums[0] = sums[1] = 0;
    __syncthreads();  // zeroed before any thread adds
    int64_t px = 0, py = 0;
    uint32_t k = 0;
    const bool mine = pp_sample(a, tile, uint32_t(job % parts), px, py, k);
    const Pt s = mine ? sample_pt(a, px, py, k) : Pt{0, 0};
    const uint64_t at = mine ? sample_at(a, px, py, k) : 0;
    const int o = mine ? a.ids[at] : -1;
    uint32_t shaded = 0;
    if (cause == 2) {
      // Non-opaque triangles are shaded where they cover the sample in front of its owner
      // (per_pixel_resolver.cpp; at 1 sample a pixel is a sample).
      const exact::Plane op = o >= 0 ? exact_plane(a.tris[a.item_tri[o]]) : exact::Plane{};
      const uint32_t begin = a.item_begin[tile], n = uint32_t(a.rows[tile * kTileColumns + kColTriangles]);
      staged_items(a, n, staged, [&](uint32_t x) { return begin + x; }, [&](const PTri& t) {
        if (mine && !t.opaque && covers(t, s) && (o < 0 || sample_depth_order(t.plane, op, s) < 0)) ++shaded;
      });
    }
    if (o >= 0) {
      a.ids[at] = int32_t(a.tris[a.item_tri[o]].id);
      atomicAdd(&a.owned[o], 1u);
    }
    atomicAdd(&sums[0], static_cast<unsigned long long>(o >= 0 ? 1 : 0));
    atomicAdd(&sums[1], static_cast<unsigned long long>(shaded));
    __syncthreads();
    if (threadIdx.x == 0) {
      atomicAdd(reinterpret_cast<unsigned long long*>(&a.rows[tile * kTileColumns + kColSamplesCovered]), sums[0]);
      atomicAdd(reinterpret_cast<unsigned long long*>(&a.shaded[tile]), sums[0] + sums[1]);
    }
    __syncthreads();
  }
}

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
  a.flag = p.hyb_flag.need(ni + 1);
  a.active_stride = ni + 1;
  a.active = p.hyb_active.need(kDetWarps * a.active_stride);
  a.batch = p.hyb_batch.need(nt * kDetWarps * 2 * WarpTeam::kSize + 1);
  {
    const Bins g = bins_of(a, a.grid.rect(0));
    a.bins_per_tile = g.x * g.y;
  }
  a.bin_counts = p.hyb_bin_counts.need(nt * a.bins_per_tile * 2 + 1);
  a.sample_xy = p.sample_xy.get();
  a.n_samples = p.f.n_samples;
  a.width = p.f.width;
  a.height = p.f.height;
  a.ids = p.ids.get();
  a.owned = p.hyb_owned.need(ni + 1);
  a.shaded = p.hyb_shaded.need(nt + 1);
  a.big = p.hyb_big.need(ni + 1);
  a.big_count = p.hyb_big_count.need(nt + 1);
  return a;
}

}  // namespace

template <class P>
void stage_verdicts(Pipeline<P>& p) {
  Exec& ex = p.ex;
  const uint64_t nt = p.n_tiles;
  const HybArgs<P> a = hybrid_args(p);
  if (ex.where == Where::cpu) {
    for (uint64_t t = 0; t < nt; ++t) verdict_host<P>(a, ex.host_index(t, nt));
  } else {
    k_verdict<P><<<uint32_t(tmin<uint64_t>(nt, uint64_t(ex.grid_blocks) * 8)), kDetWarps * 32, 0, ex.stream>>>(a, nt);
    TV_CUDA(cudaGetLastError());
    ++ex.queued;
  }
}

template <class P>
void stage_hybrid(Pipeline<P>& p) {
  Exec& ex = p.ex;
  const uint64_t ni = p.n_items, nt = p.n_tiles;
  const HybArgs<P> a = hybrid_args(p);
  ex.zero(a.owned, (ni + 1) * 4);
  if (ex.where == Where::cpu) {
    for (uint64_t t = 0; t < nt; ++t) per_pixel_tile<P>(a, ex.host_index(t, nt));
  } else {
    const uint32_t parts = (p.grid.tile_w * p.grid.tile_h * p.f.n_samples + kPixBlock - 1) / kPixBlock;
    const uint32_t tiles = uint32_t(tmin<uint64_t>(nt, uint64_t(ex.grid_blocks) * 8));
    const uint32_t jobs = uint32_t(tmin<uint64_t>(nt * parts, uint64_t(ex.grid_blocks) * 8));
    k_pp_small<P><<<tiles, kPixThreads, 0, ex.stream>>>(a, nt);
    TV_CUDA(cudaGetLastError());
    k_pp_big<P><<<jobs, kPixBlock, 0, ex.stream>>>(a, nt, parts);
    TV_CUDA(cudaGetLastError());
    k_pp_finish<P><<<jobs, kPixBlock, 0, ex.stream>>>(a, nt, parts);
    TV_CUDA(cudaGetLastError());
    ex.queued += 3;
  }
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

template void stage_verdicts<ExactP>(Pipeline<ExactP>&);
template void stage_verdicts<FloatP>(Pipeline<FloatP>&);
template void stage_hybrid<ExactP>(Pipeline<ExactP>&);
template void stage_hybrid<FloatP>(Pipeline<FloatP>&);

}  // namespace tilevis::cuda
