// Z-buffer rasterisers of a trace frame (cuda_ref.h, run_cuda_zbuffer): the baselines the
// analytic pipeline is measured against on the same GPU.
//
// tiled (exact, equal to the z-buffer truth): setup.cu's setup, then the front opaque triangles
// binned by pixel bounding box into bins of 256 samples (count -> scan -> emit, one stable
// radix sort by bin: a bin's triangles stay in setup order), then a block per bin, a thread
// per sample, the bin's triangles staged through shared memory 64 at a time. Per sample the
// owner's depth numerator N = alpha x + beta y + gamma (area * z) is kept in registers; a
// covering triangle t passes when N_t area_o < N_o area_t (zbuffer.h: strictly nearer, so at
// equal depth the earlier triangle keeps the sample). With depth bits D <= 26 every plane is
// "small" (geom/depth.h): |N| < 2^(51+D), |N area| < 2^(100+D) <= 2^126: I128.
//
// naive: a thread per trace triangle, from clip space in float, snapped to the sub-pixel grid,
// top-left coverage, float depth, one 64-bit atomicMin of (depth bits << 32 | id) per sample.
#include <algorithm>
#include <chrono>
#include <cstring>

#include "pipeline.cuh"

namespace tilevis::cuda {
namespace {

constexpr uint32_t kZBinSamples = 256;  // samples per bin: a block of threads, one per sample

// A front opaque triangle as the bins hold it (128 bytes).
struct alignas(16) ZTri {
  int64_t c[3];
  int32_t a[3], b[3];      // |a|, |b| <= 2^24 (exact.cuh ILine)
  int64_t alpha, beta;
  I128 gamma;
  int64_t area;            // > 0
  int32_t px0, py0, px1, py1;  // pixel bounding box, inside the screen
  uint32_t id;             // trace triangle
  uint32_t owns;           // bit i: edge i owns its boundary (top-left rule)
};

// Per sample: the nearest covering triangle so far.
struct Owner {
  I128 n = 0;
  int64_t area = 0;
  int32_t tri = -1;  // index into the ZTri array
};

struct ZArgs {
  const SetupTri* setup;
  ZTri* tris;
  uint32_t* bin_count;
  const uint64_t* bin_offset;
  uint64_t* pair_key;
  uint32_t* pair_tri;
  const uint64_t* key_sorted;
  const uint32_t* tri_sorted;
  uint64_t* bin_begin;  // n_bins + 1
  uint64_t n_pairs, n_setup;
  const uint32_t* sample_xy;
  int32_t* ids;
  uint32_t width, height, samples, sb, bin_w, bin_h, bins_x, bins_y;
};

TV_HD inline bool is_drawn(const SetupTri& s) {
  return s.front && s.opaque && orient2d(s.v[0].xy(), s.v[1].xy(), s.v[2].xy()) != 0;
}

TV_HD void zb_prepare(const ZArgs& a, uint64_t i) {
  const SetupTri& s = a.setup[i];
  a.bin_count[i] = 0;
  if (!is_drawn(s)) return;
  const TileTri<ExactP> t = make_tile_tri<ExactP>(s.v[0], s.v[1], s.v[2], s.id, true);
  ZTri z;
  for (int k = 0; k < 3; ++k) {
    z.a[k] = int32_t(t.edge[k].a);
    z.b[k] = int32_t(t.edge[k].b);
    z.c[k] = t.edge[k].c;
  }
  z.owns = (t.edge[0].owns_boundary() ? 1u : 0u) | (t.edge[1].owns_boundary() ? 2u : 0u) |
           (t.edge[2].owns_boundary() ? 4u : 0u);
  z.alpha = t.plane.alpha;
  z.beta = t.plane.beta;
  z.gamma = t.plane.gamma;
  z.area = t.plane.area;
  z.id = s.id;
  // zbuffer.h for_covered_samples: pixels bbox >> sb, cut at the screen.
  const int64_t px0 = tmax<int64_t>(0, t.bbox.x0 >> a.sb), px1 = tmin<int64_t>(int64_t(a.width) - 1, t.bbox.x1 >> a.sb);
  const int64_t py0 = tmax<int64_t>(0, t.bbox.y0 >> a.sb), py1 = tmin<int64_t>(int64_t(a.height) - 1, t.bbox.y1 >> a.sb);
  z.px0 = int32_t(px0);
  z.py0 = int32_t(py0);
  z.px1 = int32_t(px1);
  z.py1 = int32_t(py1);
  a.tris[i] = z;
  if (px0 > px1 || py0 > py1) return;
  a.bin_count[i] = uint32_t((px1 / a.bin_w - px0 / a.bin_w + 1) * (py1 / a.bin_h - py0 / a.bin_h + 1));
}

// A thread per (bin, triangle) pair, so a triangle over many bins costs no more than many
// small ones: the pair's triangle is the last whose offset is <= it (binary search), its bin
// the pair's rank in the triangle's bins, row-major.
TV_HD void zb_emit(const ZArgs& a, uint64_t o) {
  uint64_t lo = 0, hi = a.n_setup;  // bin_offset[lo] <= o < bin_offset[hi]
  while (hi - lo > 1) {
    const uint64_t mid = (lo + hi) / 2;
    if (a.bin_offset[mid] <= o) lo = mid;
    else hi = mid;
  }
  const ZTri& z = a.tris[lo];
  const uint64_t r = o - a.bin_offset[lo];
  const uint32_t bx0 = uint32_t(z.px0) / a.bin_w, by0 = uint32_t(z.py0) / a.bin_h;
  const uint32_t w = uint32_t(z.px1) / a.bin_w - bx0 + 1;
  a.pair_key[o] = uint64_t(by0 + uint32_t(r / w)) * a.bins_x + (bx0 + uint32_t(r % w));
  a.pair_tri[o] = uint32_t(lo);
}

// bin_begin[b]: the first sorted pair of bin b or after (lower bound), for b in [0, n_bins].
TV_HD void zb_bounds(const ZArgs& a, uint64_t b) {
  uint64_t lo = 0, hi = a.n_pairs;
  while (lo < hi) {
    const uint64_t mid = (lo + hi) / 2;
    if (a.key_sorted[mid] < b) lo = mid + 1;
    else hi = mid;
  }
  a.bin_begin[b] = lo;
}

// One triangle at one sample (x, y sub-pixel; px, py its pixel).
TV_HD inline void zb_test(const ZTri& z, uint32_t index, int32_t px, int32_t py, int64_t x, int64_t y, Owner& o) {
  if (px < z.px0 || px > z.px1 || py < z.py0 || py > z.py1) return;
  for (int k = 0; k < 3; ++k) {
    const int64_t e = int64_t(z.a[k]) * x + int64_t(z.b[k]) * y + z.c[k];
    if (e < 0 || (e == 0 && !((z.owns >> k) & 1u))) return;
  }
  const I128 n = I128{z.alpha} * x + I128{z.beta} * y + z.gamma;
  if (o.tri < 0 || n * o.area < o.n * z.area) {
    o.n = n;
    o.area = z.area;
    o.tri = int32_t(index);
  }
}

// The sample a thread of a bin owns: u = pixel_in_bin * samples + k.
struct SampleAt {
  int32_t px, py;
  int64_t x, y;
  uint64_t out;
  bool inside;
};

TV_HD inline SampleAt sample_at(const ZArgs& a, uint64_t bin, uint32_t u) {
  const uint32_t k = u % a.samples, p = u / a.samples;
  SampleAt s;
  s.px = int32_t((bin % a.bins_x) * a.bin_w + p % a.bin_w);
  s.py = int32_t((bin / a.bins_x) * a.bin_h + p / a.bin_w);
  s.inside = s.px < int32_t(a.width) && s.py < int32_t(a.height);
  const uint32_t sxy = a.sample_xy[k];
  s.x = (int64_t(s.px) << a.sb) + (sxy & 0xffffu);
  s.y = (int64_t(s.py) << a.sb) + (sxy >> 16);
  s.out = (uint64_t(s.py) * a.width + uint64_t(s.px)) * a.samples + k;
  return s;
}

// Host emulation of a bin (cpu device): every sample walks the bin's list from global memory.
void zb_raster_host(const ZArgs& a, uint64_t bin) {
  for (uint32_t u = 0; u < kZBinSamples; ++u) {
    const SampleAt s = sample_at(a, bin, u);
    if (!s.inside) continue;
    Owner o;
    for (uint64_t j = a.bin_begin[bin]; j < a.bin_begin[bin + 1]; ++j) {
      const uint32_t i = a.tri_sorted[j];
      zb_test(a.tris[i], i, s.px, s.py, s.x, s.y, o);
    }
    a.ids[s.out] = o.tri < 0 ? -1 : int32_t(a.tris[o.tri].id);
  }
}

constexpr uint32_t kChunk = 64;

__global__ void __launch_bounds__(kZBinSamples) k_zb_raster(ZArgs a, uint64_t n_bins) {
  __shared__ ZTri staged[kChunk];
  __shared__ uint32_t staged_index[kChunk];
  for (uint64_t bin = blockIdx.x; bin < n_bins; bin += gridDim.x) {
    const SampleAt s = sample_at(a, bin, threadIdx.x);
    const uint64_t begin = a.bin_begin[bin], end = a.bin_begin[bin + 1];
    Owner o;
    for (uint64_t c = begin; c < end; c += kChunk) {
      const uint32_t m = uint32_t(tmin<uint64_t>(kChunk, end - c));
      __syncthreads();  // the previous chunk is done with
      if (threadIdx.x < m) {
        const uint32_t i = a.tri_sorted[c + threadIdx.x];
        staged[threadIdx.x] = a.tris[i];
        staged_index[threadIdx.x] = i;
      }
      __syncthreads();
      if (s.inside)
        for (uint32_t j = 0; j < m; ++j) zb_test(staged[j], staged_index[j], s.px, s.py, s.x, s.y, o);
    }
    if (s.inside) a.ids[s.out] = o.tri < 0 ? -1 : int32_t(a.tris[o.tri].id);
    __syncthreads();
  }
}

__global__ void k_zb_prepare(ZArgs a, uint64_t n) { TV_GRID_LOOP(i, n) zb_prepare(a, i); }
__global__ void k_zb_emit(ZArgs a, uint64_t n) { TV_GRID_LOOP(i, n) zb_emit(a, i); }
__global__ void k_zb_bounds(ZArgs a, uint64_t n) { TV_GRID_LOOP(i, n) zb_bounds(a, i); }

// ---- naive ----------------------------------------------------------------------------------

struct NaiveArgs {
  FrameDev f;
  const float4* vertices;
  const uint32_t* indices;
  const uint32_t* tri_draw;
  const DrawInfo* draws;
  const uint32_t* sample_xy;
  unsigned long long* zkey;  // per sample: float depth bits << 32 | id; all ones: empty
  int32_t* ids;
  unsigned long long* counters;  // 0: drawn, 1: skipped
};

TV_HD void naive_triangle(const NaiveArgs& a, uint64_t t) {
  if (!a.draws[a.tri_draw[t]].opaque) return;
  const float half_w = 0.5f * float(a.f.width), half_h = 0.5f * float(a.f.height);
  const float sub = float(1u << a.f.subpixel_bits);
  const float range = a.f.depth_far - a.f.depth_near;
  int64_t x[3], y[3];
  float z[3];
  for (int k = 0; k < 3; ++k) {
    const float4 v = a.vertices[a.indices[3 * t + k]];
    const float inv = 1.0f / v.w;
    const float xw = (v.x * inv + 1.0f) * half_w, yw = (1.0f - v.y * inv) * half_h;
    if (!(v.w > 0.0f) || !(xw > -32768.0f && xw < 32768.0f && yw > -32768.0f && yw < 32768.0f)) {
#if defined(__CUDA_ARCH__)
      atomicAdd(&a.counters[1], 1ull);
#else
      ++a.counters[1];
#endif
      return;
    }
    x[k] = int64_t(rintf(xw * sub));
    y[k] = int64_t(rintf(yw * sub));
    z[k] = a.f.depth_near + range * 0.5f * (v.z * inv + 1.0f);
  }
  // Front-facing: negative doubled area in window space (y down), as setup.cu decides it.
  const int64_t area = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
  if (area >= 0) return;
  // Counter-clockwise in orient2d's sense: swap 1 and 2 so that every edge function is >= 0 inside.
  const int64_t X[3] = {x[0], x[2], x[1]}, Y[3] = {y[0], y[2], y[1]};
  const float Z[3] = {z[0], z[2], z[1]};
  int64_t ea[3], eb[3], ec[3], floor[3];
  for (int k = 0; k < 3; ++k) {
    const int j = (k + 1) % 3;
    ea[k] = Y[k] - Y[j];
    eb[k] = X[j] - X[k];
    ec[k] = X[k] * Y[j] - Y[k] * X[j];
    floor[k] = (ea[k] > 0 || (ea[k] == 0 && eb[k] > 0)) ? -1 : 0;
  }
#if defined(__CUDA_ARCH__)
  atomicAdd(&a.counters[0], 1ull);
#else
  ++a.counters[0];
#endif
  const uint32_t sb = a.f.subpixel_bits;
  const int64_t px0 = tmax<int64_t>(0, tmin(tmin(X[0], X[1]), X[2]) >> sb);
  const int64_t px1 = tmin<int64_t>(int64_t(a.f.width) - 1, tmax(tmax(X[0], X[1]), X[2]) >> sb);
  const int64_t py0 = tmax<int64_t>(0, tmin(tmin(Y[0], Y[1]), Y[2]) >> sb);
  const int64_t py1 = tmin<int64_t>(int64_t(a.f.height) - 1, tmax(tmax(Y[0], Y[1]), Y[2]) >> sb);
  const float inv_area = 1.0f / float(-area);
  for (int64_t py = py0; py <= py1; ++py)
    for (int64_t px = px0; px <= px1; ++px)
      for (uint32_t k = 0; k < a.f.n_samples; ++k) {
        const uint32_t sxy = a.sample_xy[k];
        const int64_t sx = (px << sb) + (sxy & 0xffffu), sy = (py << sb) + (sxy >> 16);
        int64_t e[3];
        bool in = true;
        for (int i = 0; i < 3; ++i) {
          e[i] = ea[i] * sx + eb[i] * sy + ec[i];
          in &= e[i] > floor[i];
        }
        if (!in) continue;
        // e[i] is the doubled area opposite vertex i + 2 (mod 3).
        const float d = (float(e[1]) * Z[0] + float(e[2]) * Z[1] + float(e[0]) * Z[2]) * inv_area;
        const float dz = d < 0.0f ? 0.0f : d;
        uint32_t bits;
        memcpy(&bits, &dz, 4);
        const unsigned long long key = (static_cast<unsigned long long>(bits) << 32) | t;
        unsigned long long* slot = &a.zkey[(uint64_t(py) * a.f.width + uint64_t(px)) * a.f.n_samples + k];
#if defined(__CUDA_ARCH__)
        atomicMin(slot, key);
#else
        if (key < *slot) *slot = key;
#endif
      }
}

TV_HD void naive_resolve(const NaiveArgs& a, uint64_t k) {
  const unsigned long long key = a.zkey[k];
  a.ids[k] = key == ~0ull ? -1 : int32_t(uint32_t(key));
}

__global__ void k_naive_triangle(NaiveArgs a, uint64_t n) { TV_GRID_LOOP(i, n) naive_triangle(a, i); }
__global__ void k_naive_resolve(NaiveArgs a, uint64_t n) { TV_GRID_LOOP(i, n) naive_resolve(a, i); }

double median_of(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Marks on the stream: CUDA events on the GPU, the host clock on the cpu path.
class Marks {
 public:
  explicit Marks(Exec& ex, int n) : m_ex(ex), m_ev(size_t(n)), m_host(size_t(n)) {
    if (ex.where == Where::gpu)
      for (auto& e : m_ev) TV_CUDA(cudaEventCreate(&e));
  }
  ~Marks() {
    for (auto e : m_ev)
      if (e) cudaEventDestroy(e);
  }
  void mark(int k) {
    if (m_ex.where == Where::gpu) TV_CUDA(cudaEventRecord(m_ev[size_t(k)], m_ex.main_stream));
    else m_host[size_t(k)] = std::chrono::steady_clock::now();
  }
  double ms(int a, int b) {
    if (m_ex.where == Where::gpu) {
      TV_CUDA(cudaEventSynchronize(m_ev[size_t(b)]));
      float t = 0;
      TV_CUDA(cudaEventElapsedTime(&t, m_ev[size_t(a)], m_ev[size_t(b)]));
      return t;
    }
    return std::chrono::duration<double, std::milli>(m_host[size_t(b)] - m_host[size_t(a)]).count();
  }

 private:
  Exec& m_ex;
  std::vector<cudaEvent_t> m_ev;
  std::vector<std::chrono::steady_clock::time_point> m_host;
};

struct ZBufs {
  Buf<ZTri> tris;
  Buf<uint32_t> bin_count, pair_tri, tri_sorted;
  Buf<uint64_t> bin_offset, pair_key, key_sorted, bin_begin;
  Buf<unsigned long long> zkey, ncount;
  explicit ZBufs(Exec& e) {
    for (auto* b : {&bin_count, &pair_tri, &tri_sorted}) b->bind(&e);
    for (auto* b : {&bin_offset, &pair_key, &key_sorted, &bin_begin}) b->bind(&e);
    tris.bind(&e);
    zkey.bind(&e);
    ncount.bind(&e);
  }
};

}  // namespace

ZBufferResult run_cuda_zbuffer(const trace::Frame& frame, const CudaConfig& cfg, ZBufferKind kind) {
  const uint32_t S = uint32_t(frame.samples.size());
  if (S == 0 || S > 16 || (S & (S - 1)) != 0) throw std::runtime_error("cuda zbuffer: samples must be 1, 2, 4, 8 or 16");
  if (cfg.depth_bits < 1 || cfg.depth_bits > 26) throw std::runtime_error("cuda zbuffer: depth bits must be 1..26");
  if (cfg.device == Device::gpu) {
    std::string why;
    if (!cuda_available(&why)) throw std::runtime_error("cuda: no usable GPU (" + why + ")");
  }
  Exec ex(cfg.device == Device::cpu ? Where::cpu : Where::gpu, cfg.shuffle_cpu);
  Pipeline<ExactP> p(ex);
  p.cfg = cfg;
  upload_frame_common(ex, frame, cfg.depth_bits, p.f, p.draws_host, p.vertices, p.indices, p.tri_draw, p.draws,
                      p.sample_xy);
  p.counters.need(kCounterCount);
  ex.sync();
  ZBufs z(ex);
  ZBufferResult r;
  r.device_name = ex.device_name;
  r.width = p.f.width;
  r.height = p.f.height;
  r.samples = S;
  const uint64_t n_samples = uint64_t(r.width) * r.height * S;
  int32_t* ids = p.ids.need(n_samples + 1);
  // Bins of 256 samples: 16x16 pixels at 1 sample, 16x8 at 2, 8x8 at 4, 8x4 at 8, 4x4 at 16.
  uint32_t bw = 16, bh = 16;
  for (uint32_t s = S; s > 1; s >>= 1) (bw > bh ? bw : bh) >>= 1;
  r.bin_w = bw;
  r.bin_h = bh;
  const uint32_t bins_x = (r.width + bw - 1) / bw, bins_y = (r.height + bh - 1) / bh;
  const uint64_t n_bins = uint64_t(bins_x) * bins_y;

  const bool naive = kind == ZBufferKind::naive;
  const int n_marks = naive ? 2 : 5;
  Marks marks(ex, n_marks);
  std::vector<std::vector<double>> stage(size_t(n_marks - 1));
  std::vector<double> total;
  auto once = [&] {
    ex.syncs = 0;
    ex.zero(p.counters.get(), kCounterCount * 8);
    marks.mark(0);
    if (naive) {
      NaiveArgs na{p.f, p.vertices.get(), p.indices.get(), p.tri_draw.get(), p.draws.get(), p.sample_xy.get(),
                   z.zkey.need(n_samples + 1), ids, z.ncount.need(2)};
      ex.fill_ones(na.zkey, n_samples * 8);
      ex.zero(na.counters, 16);
      ex.launch(k_naive_triangle, naive_triangle, p.f.n_triangles, na);
      ex.launch(k_naive_resolve, naive_resolve, n_samples, na);
      marks.mark(1);
      return;
    }
    stage_setup(p);
    marks.mark(1);
    ZArgs a{};
    a.setup = p.setup.get();
    a.tris = z.tris.need(p.n_setup + 1);
    a.bin_count = z.bin_count.need(p.n_setup + 1);
    a.bin_offset = z.bin_offset.need(p.n_setup + 1);
    a.sample_xy = p.sample_xy.get();
    a.ids = ids;
    a.width = r.width;
    a.height = r.height;
    a.samples = S;
    a.sb = p.f.subpixel_bits;
    a.bin_w = bw;
    a.bin_h = bh;
    a.bins_x = bins_x;
    a.bins_y = bins_y;
    ex.launch(k_zb_prepare, zb_prepare, p.n_setup, a);
    ex.exclusive_scan(a.bin_count, z.bin_offset.get(), p.n_setup);
    const uint64_t n_pairs = ex.read(z.bin_offset.get() + p.n_setup);  // sync: sizes the bin lists
    r.bin_entries = n_pairs;
    a.n_pairs = n_pairs;
    a.pair_key = z.pair_key.need(n_pairs + 1);
    a.pair_tri = z.pair_tri.need(n_pairs + 1);
    a.key_sorted = z.key_sorted.need(n_pairs + 1);
    a.tri_sorted = z.tri_sorted.need(n_pairs + 1);
    a.bin_begin = z.bin_begin.need(n_bins + 1);
    a.n_setup = p.n_setup;
    ex.launch(k_zb_emit, zb_emit, n_pairs, a);
    marks.mark(2);
    ex.sort_pairs(a.pair_key, z.key_sorted.get(), a.pair_tri, z.tri_sorted.get(), n_pairs, int(bits_for(n_bins)));
    ex.launch(k_zb_bounds, zb_bounds, n_bins + 1, a);
    marks.mark(3);
    if (ex.where == Where::cpu) {
      for (uint64_t b = 0; b < n_bins; ++b) zb_raster_host(a, ex.host_index(b, n_bins));
    } else {
      const uint32_t blocks = uint32_t(std::min<uint64_t>(n_bins, uint64_t(ex.grid_blocks) * 16));
      k_zb_raster<<<blocks, kZBinSamples, 0, ex.main_stream>>>(a, n_bins);
      TV_CUDA(cudaGetLastError());
    }
    marks.mark(4);
  };
  const uint32_t runs = ex.where == Where::cpu ? 1 : std::max<uint32_t>(cfg.runs, 1);
  const uint32_t warm = ex.where == Where::cpu ? 0 : std::max<uint32_t>(cfg.warmup, 1);
  for (uint32_t k = 0; k < warm + runs; ++k) {
    once();
    ex.sync();
    if (k < warm) continue;
    for (int s = 0; s + 1 < n_marks; ++s) stage[size_t(s)].push_back(marks.ms(s, s + 1));
    total.push_back(marks.ms(0, n_marks - 1));
  }
  r.runs = runs;
  r.host_syncs = ex.syncs;
  const char* const names_tiled[] = {"setup", "binning", "sort", "raster"};
  const char* const names_naive[] = {"raster"};
  for (int s = 0; s + 1 < n_marks; ++s)
    r.stage_ms.push_back({naive ? names_naive[s] : names_tiled[s], median_of(stage[size_t(s)])});
  r.total_ms = median_of(total);
  r.ids.resize(n_samples);
  ex.download(r.ids.data(), ids, n_samples * 4);
  if (naive) {
    unsigned long long c[2] = {0, 0};
    ex.download(c, z.ncount.get(), sizeof(c));
    r.triangles_drawn = c[0];
    r.skipped = c[1];
  } else {
    uint64_t c[kCounterCount];
    ex.download(c, p.counters.get(), sizeof(c));
    r.triangles_drawn = 0;
    std::vector<SetupTri> st(p.n_setup);
    ex.download(st.data(), p.setup.get(), p.n_setup * sizeof(SetupTri));
    for (const SetupTri& s : st) r.triangles_drawn += s.front && s.opaque ? 1 : 0;
  }
  return r;
}

}  // namespace tilevis::cuda
