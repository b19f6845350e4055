// run_cuda: the stages in order on one stream, per-stage times from CUDA events (median over
// the timed runs), grow-and-retry when a device counter reports an overflow, and the result
// brought back to the host in the canonical layout.
#include <algorithm>
#include <bit>
#include <chrono>
#include <cstdlib>
#include <iterator>
#include <numeric>

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>

#include "geom/tile_grid.h"
#include "sort_probe.h"
#include "tilevis/fnv1a.h"
#include "pieces.cuh"

namespace tilevis::cuda {

void cuda_check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw std::runtime_error(std::string("cuda: ") + what + ": " + cudaGetErrorString(e));
}

// ---- Exec --------------------------------------------------------------------------------

Exec::Exec(Where w, bool shuf) : where(w), shuffle(shuf) {
  if (where == Where::cpu) {
    device_name = "host emulation (cpu)";
    return;
  }
  int count = 0;
  TV_CUDA(cudaGetDeviceCount(&count));
  if (count == 0) throw std::runtime_error("cuda: no CUDA device");
  TV_CUDA(cudaSetDevice(0));
  cudaDeviceProp prop{};
  TV_CUDA(cudaGetDeviceProperties(&prop, 0));
  device_name = prop.name;
  grid_blocks = uint32_t(prop.multiProcessorCount) * 2;
  // The main stream carries the longest chain: its blocks are scheduled first.
  int least = 0, greatest = 0;
  TV_CUDA(cudaDeviceGetStreamPriorityRange(&least, &greatest));
  TV_CUDA(cudaStreamCreateWithPriority(&main_stream, cudaStreamNonBlocking, greatest));
  for (auto& s : m_side) TV_CUDA(cudaStreamCreateWithPriority(&s, cudaStreamNonBlocking, least));
  stream = main_stream;
}

Exec::~Exec() {
  for (int k = 0; k <= kSides; ++k)
    if (m_temp[k]) release(m_temp[k], m_temp_bytes[k]);
  for (auto e : m_events) cudaEventDestroy(e);
  for (auto s : m_side)
    if (s) cudaStreamDestroy(s);
  if (main_stream) cudaStreamDestroy(main_stream);
}

cudaEvent_t Exec::next_event() {
  if (m_event_next == m_events.size()) {
    cudaEvent_t e;
    TV_CUDA(cudaEventCreateWithFlags(&e, cudaEventDisableTiming));
    m_events.push_back(e);
  }
  return m_events[m_event_next++];
}

void Exec::branch(int k) {
  if (where == Where::cpu) return;
  const cudaEvent_t e = next_event();
  TV_CUDA(cudaEventRecord(e, main_stream));
  TV_CUDA(cudaStreamWaitEvent(m_side[k], e, 0));
  stream = m_side[k];
  m_cur = k + 1;
  m_pending[k] = true;
}

void Exec::resume(int k) {
  if (where == Where::cpu) return;
  if (!m_pending[k]) throw std::logic_error("cuda: resume of a side stream with no pending branch");
  stream = m_side[k];
  m_cur = k + 1;
}

void Exec::on_main() {
  stream = main_stream;
  m_cur = 0;
}

void Exec::join(int k, cudaStream_t into) {
  if (where == Where::cpu || !m_pending[k]) return;
  const cudaEvent_t e = next_event();
  TV_CUDA(cudaEventRecord(e, m_side[k]));
  TV_CUDA(cudaStreamWaitEvent(into, e, 0));
}

void Exec::merge(int k) {
  join(k, main_stream);
  m_pending[k] = false;
}

void Exec::wait_for(int k) { join(k, stream); }

cudaEvent_t Exec::record() {
  if (where == Where::cpu) return nullptr;
  const cudaEvent_t e = next_event();
  TV_CUDA(cudaEventRecord(e, stream));
  return e;
}

void Exec::wait(cudaEvent_t point) {
  if (point) TV_CUDA(cudaStreamWaitEvent(stream, point, 0));
}

void Exec::queue_checks() {
  for (const Check& c : m_checks) copy(read_check + c.at, c.src, c.bytes);
  m_checks.clear();
}

void Exec::merge_all() {
  on_main();
  for (int k = 0; k < kSides; ++k) merge(k);
}

void* Exec::alloc(size_t bytes) {
  void* p = nullptr;
  if (where == Where::cpu) {
    p = std::aligned_alloc(64, (bytes + 63) / 64 * 64);
    if (!p) throw std::runtime_error("cuda (cpu): out of host memory");
  } else {
    TV_CUDA(cudaMalloc(&p, bytes));
  }
  m_live += bytes;
  m_peak = std::max(m_peak, m_live);
  ++m_generation;
  return p;
}

void Exec::release(void* p, size_t bytes) {
  if (where == Where::cpu) std::free(p);
  else cudaFree(p);
  m_live -= bytes;
  ++m_generation;
}

void Exec::upload(void* dst, const void* src, size_t bytes) {
  if (bytes == 0) return;
  if (where == Where::cpu) std::memcpy(dst, src, bytes);
  else TV_CUDA(cudaMemcpyAsync(dst, src, bytes, cudaMemcpyHostToDevice, stream));
}

void Exec::download(void* dst, const void* src, size_t bytes) {
  if (bytes == 0) return;
  if (reads == Reads::replay) {
    if (read_pos + bytes > read_log.size()) throw std::runtime_error("cuda: a captured run reads more than its log");
    std::memcpy(dst, read_log.data() + read_pos, bytes);
    m_checks.push_back({read_pos, src, bytes});
    read_pos += bytes;
    return;
  }
  ++syncs;
  if (where == Where::cpu) {
    std::memcpy(dst, src, bytes);
  } else {
    TV_CUDA(cudaMemcpyAsync(dst, src, bytes, cudaMemcpyDeviceToHost, main_stream));
    TV_CUDA(cudaStreamSynchronize(main_stream));
  }
  if (reads == Reads::log) read_log.insert(read_log.end(), static_cast<uint8_t*>(dst), static_cast<uint8_t*>(dst) + bytes);
}

void Exec::read_many(std::initializer_list<std::pair<uint64_t*, const uint64_t*>> items) {
  if (reads == Reads::replay) {
    for (const auto& [dst, src] : items) download(dst, src, 8);
    return;
  }
  ++syncs;
  for (const auto& [dst, src] : items) {
    if (where == Where::cpu) *dst = *src;
    else TV_CUDA(cudaMemcpyAsync(dst, src, 8, cudaMemcpyDeviceToHost, main_stream));
  }
  if (where == Where::gpu) TV_CUDA(cudaStreamSynchronize(main_stream));
  if (reads == Reads::log)
    for (const auto& [dst, src] : items)
      read_log.insert(read_log.end(), reinterpret_cast<uint8_t*>(dst), reinterpret_cast<uint8_t*>(dst) + 8);
}

void Exec::copy(void* dst, const void* src, size_t bytes) {
  ++queued;
  if (where == Where::cpu) std::memcpy(dst, src, bytes);
  else TV_CUDA(cudaMemcpyAsync(dst, src, bytes, cudaMemcpyDeviceToDevice, stream));
}

void Exec::zero(void* p, size_t bytes) {
  if (bytes == 0) return;
  ++queued;
  if (where == Where::cpu) std::memset(p, 0, bytes);
  else TV_CUDA(cudaMemsetAsync(p, 0, bytes, stream));
}

void Exec::fill_ones(void* p, size_t bytes) {
  if (bytes == 0) return;
  ++queued;
  if (where == Where::cpu) std::memset(p, 0xff, bytes);
  else TV_CUDA(cudaMemsetAsync(p, 0xff, bytes, stream));
}

void Exec::sync() {
  if (where == Where::gpu && reads != Reads::replay) TV_CUDA(cudaStreamSynchronize(main_stream));
}

uint64_t Exec::host_index(uint64_t k, uint64_t n) const {
  if (!shuffle || n < 3) return k;
  // A fixed permutation of [0, n): k -> (k * s + n / 3) mod n with gcd(s, n) = 1.
  static thread_local uint64_t last_n = 0, stride = 1;
  if (n != last_n) {
    stride = n * 5 / 8 | 1;
    while (std::gcd(stride, n) != 1) stride += 2;
    last_n = n;
  }
  return static_cast<uint64_t>((static_cast<U128>(k) * stride + n / 3) % n);
}

void Exec::launch_kernel(const void* fn, uint32_t blocks, uint32_t block, const void* args, uint64_t n) {
  void* params[] = {const_cast<void*>(args), &n};
  TV_CUDA(cudaLaunchKernel(fn, dim3(blocks), dim3(block), params, 0, stream));
}

void* Exec::temp(size_t bytes) {
  void*& t = m_temp[m_cur];
  size_t& have = m_temp_bytes[m_cur];
  if (bytes > have) {
    if (t) {
      TV_CUDA(cudaStreamSynchronize(stream));  // the scratch may still be in use
      release(t, have);
    }
    have = bytes + bytes / 4 + 256;
    t = alloc(have);
  }
  return t;
}

namespace {
// in[0..n) followed by one zero: an exclusive scan over n + 1 elements leaves the total in
// out[n], with no extra kernel.
struct ZeroPadded {
  using iterator_category = std::random_access_iterator_tag;
  using value_type = uint32_t;
  using difference_type = std::ptrdiff_t;
  using pointer = const uint32_t*;
  using reference = uint32_t;
  const uint32_t* in;
  uint64_t n;  // a value or a tagged device count (count_of)
  std::ptrdiff_t at = 0;
  __host__ __device__ uint32_t operator[](std::ptrdiff_t i) const {
    const uint64_t k = uint64_t(at + i);
    return k < count_of(n) ? in[k] : 0u;
  }
  __host__ __device__ uint32_t operator*() const { return (*this)[0]; }
  __host__ __device__ ZeroPadded operator+(std::ptrdiff_t d) const { return {in, n, at + d}; }
};

__global__ void k_pad_keys(uint64_t* keys, uint64_t n, uint64_t bound) {
  TV_KERNEL_WAIT();
  const uint64_t from = count_of(n);
  for (uint64_t i = from + uint64_t(blockIdx.x) * blockDim.x + threadIdx.x; i < bound; i += uint64_t(gridDim.x) * blockDim.x)
    keys[i] = ~uint64_t{0};
}

// A sort of at most kRankSort pairs by counting, in one launch over the whole GPU: an
// element's place is the number of keys (their bits below end_bit) under its own plus the equal
// keys before it, so the order is the stable one CUB's sorts give. A block places kRankPer
// elements; its threads count in kRankParts interleaved parts of every key (a warp's lanes read
// the same key, broadcast from shared memory), summed at the end. n^2 comparisons: for the few
// thousand pairs of the silhouette and tile-edge lists, one launch instead of CUB's histogram,
// scan and pass per digit (about 9 us each on an H200 with Nsight Compute, armadillo's 5,374
// silhouette edges: 5 passes), or the one block of the cub::BlockRadixSort it replaces (24 us
// for elephant's). Limit 8,192, measured on an H200 (new frame, 15 scenes, 5 runs) against
// 4,096 and 16,384 and against that block sort up to 4,096 with CUB above: armadillo float
// 0.499 -> 0.423 ms, exact 0.772 -> 0.703, decals float -9 %, dragon -6 to -8 %; 4,096 does
// not reach armadillo's lists and 16,384 gains nothing more.
constexpr uint32_t kRankThreads = 256, kRankParts = 8, kRankPer = kRankThreads / kRankParts, kRankTile = 2048;
constexpr uint32_t kRankSort = 8192;
__global__ void __launch_bounds__(kRankThreads)
    k_sort_rank(const uint64_t* keys_in, uint64_t* keys_out, const uint32_t* vals_in, uint32_t* vals_out, uint32_t n,
                uint64_t mask) {
  TV_KERNEL_WAIT();
  __shared__ uint64_t tile[kRankTile];
  __shared__ uint32_t parts[kRankParts][kRankPer];
  const uint32_t slot = threadIdx.x % kRankPer, part = threadIdx.x / kRankPer;
  const uint32_t e = blockIdx.x * kRankPer + slot;
  const uint64_t ke = e < n ? keys_in[e] & mask : 0;
  uint32_t before = 0;
  for (uint32_t t0 = 0; t0 < n; t0 += kRankTile) {
    const uint32_t m = n - t0 < kRankTile ? n - t0 : kRankTile;
    __syncthreads();  // every thread is done with the last tile
    for (uint32_t k = threadIdx.x; k < m; k += kRankThreads) tile[k] = keys_in[t0 + k] & mask;
    __syncthreads();
    // Keys before e count when not above its own, keys from e on when below it (e itself: not).
    const uint32_t split = e <= t0 ? 0u : e - t0 < m ? e - t0 : m;
    uint32_t k = part;
#pragma unroll 4
    for (; k < split; k += kRankParts) before += tile[k] <= ke;
#pragma unroll 4
    for (; k < m; k += kRankParts) before += tile[k] < ke;
  }
  parts[part][slot] = before;
  __syncthreads();
  if (part == 0 && e < n) {
    uint32_t r = 0;
    for (uint32_t q = 0; q < kRankParts; ++q) r += parts[q][slot];
    keys_out[r] = keys_in[e];
    vals_out[r] = vals_in[e];
  }
}

// A scan of at most kSmallScan elements in one block and one pass (cub::BlockScan): one
// launch where CUB's device scan takes two (its tile states' initialisation, then the scan),
// each a node of the frame's chain (every scan of broken_mesh and decals, some of the
// bunny's). Integer sums: the same values as the device scan. Measured on the H200 against
// CUB's (new frame, 10 runs): decals float 0.309 -> 0.297 ms, bunny exact 1.093 -> 1.070.
constexpr uint32_t kSmallScanThreads = 1024, kSmallScanItems = 8, kSmallScan = kSmallScanThreads * kSmallScanItems;
template <class T>
__global__ void __launch_bounds__(kSmallScanThreads) k_scan_small(const uint32_t* in, uint64_t n_in, T* out, uint64_t n) {
  TV_KERNEL_WAIT();
  using Scan = cub::BlockScan<T, kSmallScanThreads>;
  __shared__ typename Scan::TempStorage tmp;
  const uint64_t m = count_of(n_in);  // elements past the count read as zeros
  T v[kSmallScanItems];
  for (uint32_t j = 0; j < kSmallScanItems; ++j) {  // blocked: thread t holds t * items + j
    const uint64_t i = uint64_t(threadIdx.x) * kSmallScanItems + j;
    v[j] = i < m && i < n ? T(in[i]) : T{0};
  }
  Scan(tmp).ExclusiveSum(v, v);
  for (uint32_t j = 0; j < kSmallScanItems; ++j) {
    const uint64_t i = uint64_t(threadIdx.x) * kSmallScanItems + j;
    if (i < n) out[i] = v[j];
  }
}

__global__ void k_take_sizes(SizeArgs a, uint64_t pads) {
  TV_KERNEL_WAIT();
  const bool over = sizes_over(a);  // before element 0 writes the sizes
  const uint64_t i0 = uint64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i0 == 0) take_sizes(a);
  for (uint64_t i = i0; i < pads; i += uint64_t(gridDim.x) * blockDim.x) pad_keys(a, over, i);
}

}  // namespace

void queue_take_sizes(Exec& ex, const SizeArgs& a) {
  ++ex.queued;
  uint64_t pads = 0;  // the most padding elements there can be (every count 0)
  for (uint32_t k = 0; k < a.n_pads; ++k) pads += a.pad[k].bound;
  if (ex.where == Where::cpu) {
    const bool over = sizes_over(a);
    take_sizes(a);
    for (uint64_t i = 0; i < pads; ++i) pad_keys(a, over, i);  // past the ranges' ends: nothing
    return;
  }
  const uint64_t want = (pads + 255) / 256;
  k_take_sizes<<<uint32_t(want < 1 ? 1 : want < ex.grid_blocks ? want : ex.grid_blocks), 256, 0, ex.stream>>>(a, pads);
  TV_CUDA(cudaGetLastError());
}

template <class T>
void Exec::scan_into(const uint32_t* in, T* out, uint64_t n_in, uint64_t bound) {
  ++queued;
  const uint64_t n = is_dev_count(n_in) ? bound : n_in;  // elements scanned (past the count: zeros)
  if (where == Where::cpu) {
    const uint64_t m = count_of(n_in);
    T s = 0;
    for (uint64_t i = 0; i < n; ++i) {
      const T v = i < m ? in[i] : 0;
      out[i] = s;
      s += v;
    }
    out[n] = s;
    return;
  }
  const ZeroPadded padded{in, n_in};
  if (n + 1 <= kSmallScan) {
    k_scan_small<T><<<1, kSmallScanThreads, 0, stream>>>(in, n_in, out, n + 1);
    TV_CUDA(cudaGetLastError());
    return;
  }
  size_t bytes = 0;
  TV_CUDA(cub::DeviceScan::ExclusiveScan(nullptr, bytes, padded, out, ::cuda::std::plus<T>{}, T{0}, n + 1, stream));
  void* t = temp(bytes);
  TV_CUDA(cub::DeviceScan::ExclusiveScan(t, bytes, padded, out, ::cuda::std::plus<T>{}, T{0}, n + 1, stream));
}

void Exec::exclusive_scan(const uint32_t* in, uint64_t* out, uint64_t n, uint64_t bound) { scan_into(in, out, n, bound); }
void Exec::exclusive_scan(const uint32_t* in, uint32_t* out, uint64_t n, uint64_t bound) { scan_into(in, out, n, bound); }

void Exec::sort_pairs(const uint64_t* keys_in, uint64_t* keys_out, const uint32_t* vals_in, uint32_t* vals_out,
                      uint64_t n_in, int end_bit, uint64_t bound, bool padded) {
  uint64_t n = n_in;
  if (is_dev_count(n_in)) {
    n = bound;
    if (n == 0) return;
  }
  if (is_dev_count(n_in) && !padded) {
    ++queued;
    uint64_t* keys = const_cast<uint64_t*>(keys_in);
    if (where == Where::cpu) {
      for (uint64_t i = count_of(n_in); i < bound; ++i) keys[i] = ~uint64_t{0};
    } else {
      const uint64_t want = (bound + 255) / 256;
      k_pad_keys<<<uint32_t(want < grid_blocks ? want : grid_blocks), 256, 0, stream>>>(keys, n_in, bound);
      TV_CUDA(cudaGetLastError());
    }
  }
  if (n == 0) return;
  ++queued;
  if (end_bit < 1) end_bit = 1;
  if (where == Where::cpu) {
    std::vector<uint64_t> order(n);
    std::iota(order.begin(), order.end(), 0);
    const uint64_t mask = end_bit >= 64 ? ~uint64_t{0} : (uint64_t{1} << end_bit) - 1;
    std::stable_sort(order.begin(), order.end(),
                     [&](uint64_t a, uint64_t b) { return (keys_in[a] & mask) < (keys_in[b] & mask); });
    for (uint64_t i = 0; i < n; ++i) {
      keys_out[i] = keys_in[order[i]];
      vals_out[i] = vals_in[order[i]];
    }
    return;
  }
  if (n <= kRankSort) {
    const uint64_t mask = end_bit >= 64 ? ~uint64_t{0} : (uint64_t{1} << end_bit) - 1;
    k_sort_rank<<<uint32_t((n + kRankPer - 1) / kRankPer), kRankThreads, 0, stream>>>(keys_in, keys_out, vals_in,
                                                                                     vals_out, uint32_t(n), mask);
    TV_CUDA(cudaGetLastError());
    return;
  }
  size_t bytes = 0;
  TV_CUDA(cub::DeviceRadixSort::SortPairs(nullptr, bytes, keys_in, keys_out, vals_in, vals_out, n, 0, end_bit, stream));
  void* t = temp(bytes);
  TV_CUDA(cub::DeviceRadixSort::SortPairs(t, bytes, keys_in, keys_out, vals_in, vals_out, n, 0, end_bit, stream));
}

void sort_pairs_probe(bool gpu, std::vector<uint64_t>& keys, std::vector<uint32_t>& vals, int end_bit, uint64_t count) {
  if (vals.size() != keys.size()) throw std::invalid_argument("sort_pairs_probe: as many values as keys");
  Exec ex(gpu ? Where::gpu : Where::cpu, false);
  const uint64_t n = keys.size();
  auto* k = static_cast<uint64_t*>(ex.alloc((n + 1) * 8));
  auto* ko = static_cast<uint64_t*>(ex.alloc((n + 1) * 8));
  auto* v = static_cast<uint32_t*>(ex.alloc((n + 1) * 4));
  auto* vo = static_cast<uint32_t*>(ex.alloc((n + 1) * 4));
  ex.upload(k, keys.data(), n * 8);
  ex.upload(v, vals.data(), n * 4);
  uint64_t n_arg = n;
  if (count < n) {  // the count after the keys, as a device-sized run's sizes hold it
    ex.upload(k + n, &count, 8);
    n_arg = dev_count(k + n, n);
  }
  ex.sort_pairs(k, ko, v, vo, n_arg, end_bit, n);
  ex.download(keys.data(), ko, n * 8);
  ex.download(vals.data(), vo, n * 4);
  ex.release(k, (n + 1) * 8);
  ex.release(ko, (n + 1) * 8);
  ex.release(v, (n + 1) * 4);
  ex.release(vo, (n + 1) * 4);
}

// ---- the run -------------------------------------------------------------------------------

namespace {

// The main chain's stages (marks 0..7), then the unclipped pieces' occlusion and raster, which
// run beside clipping on a side stream (marks 8, 9) and are not part of the total.
const char* const kStages[] = {"setup", "silhouettes", "binning", "cull", "clip", "occlusion", "raster"};
constexpr int kStageCount = 7;
constexpr const char* kBesideClip = "unclipped_pieces";

class Timer {
 public:
  explicit Timer(Exec& ex) : m_ex(ex) {
    if (ex.where == Where::gpu)
      for (auto& e : m_ev) TV_CUDA(cudaEventCreate(&e));
  }
  ~Timer() {
    for (auto& e : m_ev)
      if (e) cudaEventDestroy(e);
  }
  // Only the first and last marks (the total) when `all` is off: the frame without probes.
  bool all = true;
  // Mark k on the stream work is queued on now (the main stream, or a side stream in a branch).
  void mark(int k) {
    if (!all && k != 0 && k != kStageCount) return;
    // While a graph is captured, an external event record becomes a node of the graph.
    if (m_ex.where == Where::cpu) {
      m_host[k] = std::chrono::steady_clock::now();
      return;
    }
    cudaStreamCaptureStatus capture = cudaStreamCaptureStatusNone;
    if (m_ex.reads == Exec::Reads::replay) TV_CUDA(cudaStreamIsCapturing(m_ex.stream, &capture));
    if (capture == cudaStreamCaptureStatusActive)
      TV_CUDA(cudaEventRecordWithFlags(m_ev[k], m_ex.stream, cudaEventRecordExternal));
    else TV_CUDA(cudaEventRecord(m_ev[k], m_ex.stream));  // presized runs replay reads without a capture
  }
  // Stage k's time (between marks k and k + 1), after the stream has finished.
  double ms(int a, int b) {
    if (m_ex.where == Where::gpu) {
      float t = 0;
      TV_CUDA(cudaEventElapsedTime(&t, m_ev[a], m_ev[b]));
      return t;
    }
    return std::chrono::duration<double, std::milli>(m_host[b] - m_host[a]).count();
  }

 private:
  Exec& m_ex;
  cudaEvent_t m_ev[kStageCount + 3] = {};
  std::chrono::steady_clock::time_point m_host[kStageCount + 3];
};

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

template <class P>
bool run_once(Pipeline<P>& p, Timer& t) {
  p.ex.queued = p.ex.syncs = 0;
  if (p.ex.reads == Exec::Reads::replay) p.ex.read_pos = 0;
  else p.ex.read_log.clear();
  p.ex.begin_frame();
  p.ex.zero(p.counters.get(), kCounterCount * 8);
  if (p.dev) p.ex.zero(p.sizes.get(), kSizeSlots * 8);
  // The id and area buffers are cleared beside the stages (side stream 2) long before the
  // raster passes and the fold, which wait for that point.
  p.ex.branch(2);
  raster_begin(p);
  const cudaEvent_t cleared = p.ex.record();
  p.ex.on_main();
  t.mark(0);
  stage_setup(p);
  t.mark(1);
  stage_silhouettes(p);
  t.mark(2);
  stage_binning(p);
  t.mark(3);
  stage_cull(p);
  t.mark(4);
  p.ex.merge(1);  // the occluder lists (binning)
  if (p.cfg.hybrid) {
    // The verdicts need the tiles' lists and counts only: they run beside the analytic stages,
    // and so do the per-pixel tiles. Both rasters and the analytic stages write every tile's
    // ids and row, and stage_per_pixel_out writes the per-pixel tiles' over them at the end.
    p.ex.branch(5);
    stage_per_pixel(p, PerPixelTiles::counted);
    p.ex.branch(3);
    stage_verdicts(p);
    stage_per_pixel(p, PerPixelTiles::found);
    p.ex.on_main();
  }
  p.ex.branch(0);
  t.mark(kStageCount + 1);
  stage_occlusion(p, Pass::unclipped);
  const cudaEvent_t unclipped_visible = p.ex.record();  // the fold needs this pass's verdicts, not its raster
  p.ex.wait(cleared);
  stage_raster(p, Pass::unclipped);
  t.mark(kStageCount + 2);
  p.ex.on_main();
  if (!stage_clip(p)) {  // a pool overflowed: finish the branches before the run is repeated
    p.ex.merge_all();
    p.ex.sync();
    return false;
  }
  t.mark(5);
  stage_occlusion(p, Pass::clipped);
  t.mark(6);
  // The visible areas beside the clipped pieces' raster, once the unclipped pieces' occlusion
  // and the area order (binning, side 2) are done (beside the unclipped pieces' raster too);
  // in hybrid mode once the per-pixel tiles are done too (sides 3 and 5).
  p.ex.branch(1);
  p.ex.wait(unclipped_visible);
  p.ex.wait_for(2);
  if (p.cfg.hybrid) {
    p.ex.wait_for(3);
    p.ex.wait_for(5);
    stage_hybrid(p);
  } else {
    stage_fold(p);
  }
  p.ex.on_main();
  p.ex.wait(cleared);
  stage_raster(p, Pass::clipped);
  p.ex.merge_all();
  if (p.cfg.hybrid) stage_per_pixel_out(p);
  t.mark(7);
  p.ex.queue_checks();
  p.ex.sync();
  return true;
}

// Programmatic dependent launch (sm_90) in the recorded graphs: every edge from a kernel to one
// of this library's kernels (each starts with TV_KERNEL_WAIT, exec.cuh) becomes a programmatic
// edge, so the next kernel is launched once every block of the one before has exited, without
// waiting for that grid to complete and flush, and waits for it (and its memory) at its first
// instruction. Edges into CUB's kernels, memsets, copies and event nodes stay full edges.
// TILEVIS_CUDA_PDL=off keeps every edge a full one (the A/B switch; `exit`, the default, is
// the above). Measured in reports/cuda/pdl_h100.md: float new frames 0.3-4.1 % faster, exact
// faster on 7 scenes of 10 and slower on 3 (million +3.2 %). Launch-completion edges were slower;
// programmatic edges only where the graph neither forks nor joins, or only into grids of at most
// one block per SM, kept million exact but lost most of the gain; full edges at the stage
// boundaries kept the gain and the loss.
enum class Pdl { off, exit };
Pdl pdl_mode() {
  const char* v = std::getenv("TILEVIS_CUDA_PDL");
  const std::string s = v ? v : "exit";
  if (s == "off" || s == "0") return Pdl::off;
  if (s == "exit" || s == "1") return Pdl::exit;
  throw std::runtime_error("TILEVIS_CUDA_PDL=" + s + ": expected off or exit");
}
const char* to_string(Pdl m) { return m == Pdl::off ? "off" : "exit"; }

bool is_kernel(cudaGraphNode_t n) {
  cudaGraphNodeType t{};
  TV_CUDA(cudaGraphNodeGetType(n, &t));
  return t == cudaGraphNodeTypeKernel;
}
// One of this library's kernels (namespace tilevis::cuda), as its mangled or demangled name says.
bool waits_first(cudaGraphNode_t n) {
  cudaKernelNodeParams kp{};
  TV_CUDA(cudaGraphKernelNodeGetParams(n, &kp));
  const char* name = nullptr;
  if (cudaFuncGetName(&name, kp.func) != cudaSuccess || !name) return false;
  std::string s = name;
  if (s.rfind("void ", 0) == 0) s.erase(0, 5);
  return s.rfind("_ZN7tilevis4cuda", 0) == 0 || s.rfind("tilevis::cuda::", 0) == 0;
}

uint32_t programmatic_edges(cudaGraph_t g) {
  const Pdl mode = pdl_mode();
  if (mode == Pdl::off) return 0;
  size_t n = 0;
  TV_CUDA(cudaGraphGetEdges(g, nullptr, nullptr, nullptr, &n));
  std::vector<cudaGraphNode_t> from(n), to(n);
  std::vector<cudaGraphEdgeData> data(n);
  TV_CUDA(cudaGraphGetEdges(g, from.data(), to.data(), data.data(), &n));
  uint32_t changed = 0;
  for (size_t i = 0; i < n; ++i) {
    if (data[i].type != cudaGraphDependencyTypeDefault || data[i].from_port != cudaGraphKernelNodePortDefault) continue;
    if (!is_kernel(from[i]) || !is_kernel(to[i]) || !waits_first(to[i])) continue;
    TV_CUDA(cudaGraphRemoveDependencies(g, &from[i], &to[i], &data[i], 1));
    cudaGraphEdgeData e{};
    e.from_port = cudaGraphKernelNodePortProgrammatic;
    e.type = cudaGraphDependencyTypeProgrammatic;
    TV_CUDA(cudaGraphAddDependencies(g, &from[i], &to[i], &e, 1));
    ++changed;
  }
  return changed;
}

// The whole frame as one CUDA graph: captured from a run whose host reads return what the
// last synchronous run read (Exec::Reads::replay), so no launch waits for the host; every
// replay copies the values those reads would have returned and checks them against the log.
class FrameGraph {
 public:
  explicit FrameGraph(Exec& ex) : m_ex(ex) {}
  ~FrameGraph() {
    if (m_exec) cudaGraphExecDestroy(m_exec);
    if (m_graph) cudaGraphDestroy(m_graph);
    if (m_check) m_ex.release(m_check, m_check_bytes);
  }
  FrameGraph(const FrameGraph&) = delete;
  FrameGraph& operator=(const FrameGraph&) = delete;

  template <class Run>
  void capture(Run&& run) {
    m_check_bytes = m_ex.read_log.size() + 8;
    m_check = static_cast<uint8_t*>(m_ex.alloc(m_check_bytes));
    m_ex.read_check = m_check;
    m_ex.reads = Exec::Reads::replay;
    TV_CUDA(cudaStreamBeginCapture(m_ex.main_stream, cudaStreamCaptureModeRelaxed));
    bool ok = false;
    try {
      ok = run();
    } catch (...) {
      cudaGraph_t g = nullptr;
      cudaStreamEndCapture(m_ex.main_stream, &g);
      if (g) cudaGraphDestroy(g);
      m_ex.reads = Exec::Reads::direct;
      throw;
    }
    m_ex.reads = Exec::Reads::direct;
    TV_CUDA(cudaStreamEndCapture(m_ex.main_stream, &m_graph));
    if (!ok || m_ex.read_pos != m_ex.read_log.size())
      throw std::runtime_error("cuda: the captured run did not repeat the logged run's reads");
    m_programmatic = programmatic_edges(m_graph);
    TV_CUDA(cudaGraphInstantiate(&m_exec, m_graph, 0));
    size_t nodes = 0;
    TV_CUDA(cudaGraphGetNodes(m_graph, nullptr, &nodes));
    m_nodes = uint32_t(nodes);
  }
  void replay() {
    TV_CUDA(cudaGraphLaunch(m_exec, m_ex.main_stream));
    TV_CUDA(cudaStreamSynchronize(m_ex.main_stream));
    std::vector<uint8_t> got(m_ex.read_log.size());
    m_ex.download(got.data(), m_check, got.size());
    if (got != m_ex.read_log) throw std::runtime_error("cuda: a graph replay read other sizes than its capture");
  }
  uint32_t nodes() const { return m_nodes; }
  uint32_t programmatic() const { return m_programmatic; }

 private:
  Exec& m_ex;
  cudaGraph_t m_graph = nullptr;
  cudaGraphExec_t m_exec = nullptr;
  uint8_t* m_check = nullptr;  // where this graph's replays copy the values it read
  size_t m_check_bytes = 0;
  uint32_t m_nodes = 0, m_programmatic = 0;
};

// After a device-sized run has ended: the one check of the frame (the clipping pools' counters
// and the size slots, two small copies). False: a pool or a bound was too small (pools grown;
// the caller runs the frame with host reads, which learns the bounds). True: the run's sizes
// are now on the host (n_setup ... n_tile_edges hold them, no longer the bounds).
template <class P>
bool dev_fits(Pipeline<P>& p) {
  uint64_t c[kFloatAnomalies], s[kSizeSlots];
  p.ex.download(c, p.counters.get(), sizeof(c));
  p.ex.download(s, p.sizes.get(), sizeof(s));
  const bool pools = pools_fit(p, c);
  if (s[kSzOverflow]) return false;
  p.n_setup = s[kSzSetup];
  p.n_edges = s[kSzEdges];
  p.n_tris = s[kSzTris];
  p.n_items = s[kSzItems];
  p.n_tile_edges = s[kSzTileEdges];
  return pools;
}

// Runs with host reads until every pool fits (they learn the bounds, Capacities), then
// device-sized runs until one fits (the first of them allocates what the bounds need, so a
// capture that follows allocates nothing). Returns the runs that did not fit.
template <class P>
uint32_t settle_dev(Pipeline<P>& p, Timer& t) {
  uint32_t misses = 0;
  for (;;) {
    p.dev = false;
    p.ex.reads = Exec::Reads::log;
    while (!run_once(p, t))
      if (++misses > 32) throw std::runtime_error("cuda: buffers still overflow after 32 retries");
    p.ex.reads = Exec::Reads::direct;
    p.dev = true;
    run_once(p, t);
    const bool fits = dev_fits(p);
    p.dev = false;
    if (fits) return misses;
    if (++misses > 32) throw std::runtime_error("cuda: a device-sized run still overflows after 32 retries");
  }
}

// The frame as one CUDA graph of a device-sized run: no size of any frame is in it (grids, scans
// and sorts over the learned bounds, counts read on the device), so any frame whose sizes fit the
// bounds runs through it unchanged, and a new frame costs one graph launch and one check after it
// (dev_fits). Valid while no buffer moves (Exec::generation), the frame's constants (FrameDev:
// vertex, triangle and sample counts, viewport) and the bounds stay.
template <class P>
class DevGraph {
 public:
  explicit DevGraph(Pipeline<P>& p) : m_p(p) {}
  ~DevGraph() { reset(); }
  DevGraph(const DevGraph&) = delete;
  DevGraph& operator=(const DevGraph&) = delete;
  void reset() {
    if (m_exec) cudaGraphExecDestroy(m_exec);
    if (m_graph) cudaGraphDestroy(m_graph);
    m_exec = nullptr;
    m_graph = nullptr;
  }
  bool valid() const {
    return m_exec && m_gen == m_p.ex.generation() && std::memcmp(&m_f, &m_p.f, sizeof(FrameDev)) == 0 &&
           m_bounds == m_p.caps.graph_bounds();
  }
  // Records run() (a device-sized run_once) after settle_dev: it must neither read nor allocate.
  template <class Run>
  void capture(Run&& run) {
    reset();
    Exec& ex = m_p.ex;
    std::vector<uint8_t> log;
    std::swap(log, ex.read_log);  // empty: any host read inside the capture throws
    ex.read_pos = 0;
    ex.reads = Exec::Reads::replay;
    m_p.dev = true;
    const uint64_t gen = ex.generation();
    TV_CUDA(cudaStreamBeginCapture(ex.main_stream, cudaStreamCaptureModeRelaxed));
    bool ok = false;
    try {
      ok = run();
    } catch (...) {
      cudaGraph_t g = nullptr;
      cudaStreamEndCapture(ex.main_stream, &g);
      if (g) cudaGraphDestroy(g);
      ex.reads = Exec::Reads::direct;
      std::swap(log, ex.read_log);
      m_p.dev = false;
      throw;
    }
    ex.reads = Exec::Reads::direct;
    std::swap(log, ex.read_log);
    m_p.dev = false;
    TV_CUDA(cudaStreamEndCapture(ex.main_stream, &m_graph));
    if (!ok || ex.generation() != gen) throw std::runtime_error("cuda: the device-sized capture allocated or failed");
    m_programmatic = programmatic_edges(m_graph);
    TV_CUDA(cudaGraphInstantiate(&m_exec, m_graph, 0));
    size_t nodes = 0;
    TV_CUDA(cudaGraphGetNodes(m_graph, nullptr, &nodes));
    m_nodes = uint32_t(nodes);
    m_gen = ex.generation();
    m_f = m_p.f;
    m_bounds = m_p.caps.graph_bounds();
  }
  // One frame: the graph launched, waited for, checked (dev_fits).
  bool launch() {
    TV_CUDA(cudaGraphLaunch(m_exec, m_p.ex.main_stream));
    TV_CUDA(cudaStreamSynchronize(m_p.ex.main_stream));
    return dev_fits(m_p);
  }
  uint32_t nodes() const { return m_nodes; }
  uint32_t programmatic() const { return m_programmatic; }

 private:
  Pipeline<P>& m_p;
  cudaGraph_t m_graph = nullptr;
  cudaGraphExec_t m_exec = nullptr;
  uint64_t m_gen = 0;
  FrameDev m_f{};
  std::vector<uint64_t> m_bounds;
  uint32_t m_nodes = 0, m_programmatic = 0;
};

__global__ void k_empty(uint64_t* p) {
  TV_KERNEL_WAIT();
  if (p && threadIdx.x == 1024) *p = 0;  // never: keeps the launch from being optimised away
}

// Launch and round-trip costs of this device, for the lower bound of a run.
void measure_launch_costs(Exec& ex, CudaResult& r) {
  uint64_t* d = static_cast<uint64_t*>(ex.alloc(8));
  uint64_t h = 0;
  cudaEvent_t a, b;
  TV_CUDA(cudaEventCreate(&a));
  TV_CUDA(cudaEventCreate(&b));
  for (int k = 0; k < 100; ++k) k_empty<<<1, 32, 0, ex.main_stream>>>(d);
  TV_CUDA(cudaEventRecord(a, ex.main_stream));
  constexpr int kLaunches = 2000;
  for (int k = 0; k < kLaunches; ++k) k_empty<<<1, 32, 0, ex.main_stream>>>(d);
  TV_CUDA(cudaEventRecord(b, ex.main_stream));
  TV_CUDA(cudaEventSynchronize(b));
  float ms = 0;
  TV_CUDA(cudaEventElapsedTime(&ms, a, b));
  r.launch_us = 1000.0 * ms / kLaunches;
  constexpr int kTrips = 200;
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < kTrips; ++k) {
    k_empty<<<1, 32, 0, ex.main_stream>>>(d);
    TV_CUDA(cudaMemcpyAsync(&h, d, 8, cudaMemcpyDeviceToHost, ex.main_stream));
    TV_CUDA(cudaStreamSynchronize(ex.main_stream));
  }
  r.round_trip_us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() / kTrips;
  cudaEventDestroy(a);
  cudaEventDestroy(b);
  ex.release(d, 8);
}

template <class P>
CudaResult run(const trace::Frame& frame, const CudaConfig& cfg) {
  Exec ex(cfg.device == Device::cpu ? Where::cpu : Where::gpu, cfg.shuffle_cpu);
  Pipeline<P> p(ex);
  p.cfg = cfg;
  if (cfg.initial_pool) {
    p.caps.deep_pairs = p.caps.candidates = p.caps.clip_slots = p.caps.clip_edges = cfg.initial_pool;
    p.caps.slot_factor = 1;
  }
  CudaResult r;
  r.device_name = ex.device_name;

  auto t0 = std::chrono::steady_clock::now();
  upload_frame_common(ex, frame, cfg.depth_bits, p.f, p.draws_host, p.vertices, p.indices, p.tri_draw, p.draws,
                      p.sample_xy);
  p.counters.need(kCounterCount);
  p.sizes.need(kSizeSlots);
  ex.sync();
  r.upload_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  Timer timer(ex);
  ex.reads = Exec::Reads::log;
  // First run: grow and retry until no device counter overflows.
  while (!run_once(p, timer)) {
    if (++r.retries > 32) throw std::runtime_error("cuda: buffers still overflow after 32 retries");
  }
  for (uint32_t w = 1; w < cfg.warmup; ++w)
    if (!run_once(p, timer)) ++r.retries;
  const uint32_t runs = std::max<uint32_t>(cfg.runs, 1);
  // Median stage (if the timer marks them) and total times of `runs` runs of `one` (false: not
  // timed, run again).
  auto timed = [&](auto&& one, std::vector<StageTime>& stage_ms, double& total_ms) {
    std::vector<std::vector<double>> stage(kStageCount);
    std::vector<double> total, beside;
    for (uint32_t k = 0; k < runs;) {
      if (!one()) {  // cannot happen with learned capacities, but never time a partial run
        ++r.retries;
        continue;
      }
      if (timer.all) {
        for (int s = 0; s < kStageCount; ++s) stage[s].push_back(timer.ms(s, s + 1));
        beside.push_back(timer.ms(kStageCount + 1, kStageCount + 2));
      }
      total.push_back(timer.ms(0, kStageCount));
      ++k;
    }
    if (timer.all) {
      for (int s = 0; s < kStageCount; ++s) stage_ms.push_back({kStages[s], median(stage[s])});
      stage_ms.push_back({kBesideClip, median(beside)});
    }
    total_ms = median(total);
  };
  // The stream: each stage's work queued as it comes, the host reading sizes between stages
  // (a new frame: the headline total_ms).
  timed([&] { return run_once(p, timer); }, r.stream_stage_ms, r.stream_total_ms);
  r.total_ms = r.stream_total_ms;
  r.queued_operations = ex.queued;
  r.host_syncs = ex.syncs;
  r.runs = runs;
  if (ex.where == Where::gpu) {
    // Presized: the same frame queued stage by stage, the same launches, but with no host round
    // trip: its host reads answered by the last run's (Reads::replay outside a capture), every
    // answer checked against the device's values after the run. new frame - presized = what the
    // host round trips cost; presized - graph = what queueing the launches one by one costs.
    const size_t log_bytes = ex.read_log.size();
    uint8_t* check = static_cast<uint8_t*>(ex.alloc(log_bytes + 8));
    ex.read_check = check;
    ex.reads = Exec::Reads::replay;
    std::vector<StageTime> unused;
    timed(
        [&] {
          const bool ok = run_once(p, timer);
          TV_CUDA(cudaStreamSynchronize(ex.main_stream));
          return ok;
        },
        unused, r.presized_total_ms);
    ex.reads = Exec::Reads::direct;
    std::vector<uint8_t> got(log_bytes);
    ex.download(got.data(), check, log_bytes);
    ex.release(check, log_bytes + 8);
    if (got != ex.read_log) throw std::runtime_error("cuda: a presized run read other sizes than the logged run");
    ex.reads = Exec::Reads::log;
  }
  if (ex.where == Where::gpu) {
    // Two graphs of the frame: one with an event at every stage boundary (stage times), one
    // with only the first and last (the total, without the probes' own cost).
    FrameGraph probed(ex), lean(ex);
    probed.capture([&] { return run_once(p, timer); });
    timer.all = false;
    lean.capture([&] { return run_once(p, timer); });
    r.graph_nodes = lean.nodes();
    r.graph_programmatic_edges = lean.programmatic();
    r.graph_pdl = to_string(pdl_mode());
    probed.replay();  // warm-up
    lean.replay();
    timed([&] { lean.replay(); return true; }, r.stage_ms, r.graph_total_ms);  // no stages: all is off
    timer.all = true;
    timed([&] { probed.replay(); return true; }, r.stage_ms, r.probed_total_ms);
  } else {
    r.stage_ms = r.stream_stage_ms;
    r.graph_total_ms = r.stream_total_ms;
  }
  ex.reads = Exec::Reads::direct;
  // The headline new frame: one launch of the device-sized graph (no size of this frame in it,
  // none read on the host during it; the check after it, dev_fits, is outside the events, like
  // the z-buffers' overflow check). The results below are this run's. Finer occlusion bins
  // read a size on the host: there the new frame stays the stream's.
  if (p.obins_x * p.obins_y == 1) {
    r.retries += settle_dev(p, timer);
    if (ex.where == Where::gpu) {
      // Two device-sized graphs, as for the known frame: one with an event at every stage
      // boundary (stage_ms, probed_total_ms: the headline's stages), one with only the ends.
      timer.all = true;
      DevGraph<P> probed(p), g(p);
      probed.capture([&] { return run_once(p, timer); });
      timer.all = false;
      g.capture([&] { return run_once(p, timer); });
      auto launch = [&](DevGraph<P>& d) {
        if (!d.launch()) throw std::runtime_error("cuda: the device-sized graph overflowed on its own frame");
        return true;
      };
      launch(probed);
      launch(g);
      r.device_graph_nodes = g.nodes();
      r.device_graph_programmatic_edges = g.programmatic();
      timer.all = true;
      r.stage_ms.clear();
      timed([&] { return launch(probed); }, r.stage_ms, r.probed_total_ms);
      timer.all = false;
      std::vector<StageTime> unused;
      timed([&] { return launch(g); }, unused, r.total_ms);  // last: the results are this graph's run
      timer.all = true;
    }
    r.device_sized = true;
  }

  // Results of the last run.
  t0 = std::chrono::steady_clock::now();
  r.width = p.f.width;
  r.height = p.f.height;
  r.samples = p.f.n_samples;
  const uint64_t n_samples = uint64_t(r.width) * r.height * r.samples;
  r.ids.resize(n_samples);
  ex.download(r.ids.data(), p.ids.get(), n_samples * 4);
  r.visible_area.resize(p.f.n_triangles);
  ex.download(r.visible_area.data(), p.area.get(), p.f.n_triangles * 8);
  std::vector<int64_t> rows(uint64_t(p.n_tiles) * kTileColumns);
  ex.download(rows.data(), p.tile_rows.get(), rows.size() * 8);
  uint64_t c[kCounterCount];
  ex.download(c, p.counters.get(), sizeof(c));
  std::vector<uint64_t> hyb_shaded;
  if (cfg.hybrid) {
    r.per_pixel_cause.resize(p.n_tiles);
    r.crossing_triangles.resize(p.n_tiles);
    r.detection_screens.resize(p.n_tiles);
    r.detection_tests.resize(p.n_tiles);
    ex.download(r.per_pixel_cause.data(), p.hyb_cause.get(), p.n_tiles * 4ull);
    ex.download(r.crossing_triangles.data(), p.hyb_crossing.get(), p.n_tiles * 4ull);
    ex.download(r.detection_screens.data(), p.hyb_screens.get(), p.n_tiles * 8ull);
    ex.download(r.detection_tests.data(), p.hyb_tests.get(), p.n_tiles * 8ull);
    hyb_shaded.resize(p.n_tiles);
    ex.download(hyb_shaded.data(), p.hyb_shaded.get(), p.n_tiles * 8ull);
  }
  r.download_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  r.tiles_x = p.tiles_x;
  r.tiles_y = p.tiles_y;
  r.tile_w = cfg.tile_w;
  r.tile_h = cfg.tile_h;
  static_assert(kTileColumns == vis::TileCounters::kCount, "device tile rows hold the TileCounters columns");
  r.tiles.resize(p.n_tiles);
  vis::TileCounters sum;
  for (uint32_t t = 0; t < p.n_tiles; ++t) {
    const vis::TileCounters& c = r.tiles[t] = vis::TileCounters::read(rows.data() + uint64_t(t) * kTileColumns);
    r.max_tile_triangles = std::max<uint64_t>(r.max_tile_triangles, uint64_t(c.triangles));
    r.max_tile_edges = std::max<uint64_t>(r.max_tile_edges, uint64_t(c.edges));
    sum += c;
    // At 1 sample: an analytic tile shades its visible pieces' samples; a per-pixel tile its
    // owners' pixels and the non-opaque triangles in front of them (k_per_pixel).
    r.fragments_shaded += cfg.hybrid && r.per_pixel_cause[t] != 0 ? hyb_shaded[t] : uint64_t(c.samples_covered);
  }
  r.pair_tests = uint64_t(sum.pair_tests);
  r.candidate_pairs = uint64_t(sum.candidate_pairs);
  r.clip_polygons = uint64_t(sum.clip_polygons);
  r.pieces = uint64_t(sum.pieces);
  r.visible_pieces = uint64_t(sum.visible_pieces);
  r.occlusion_tests = uint64_t(sum.occlusion_tests);
  r.samples_covered = uint64_t(sum.samples_covered);
  r.fragments_generated = uint64_t(sum.fragments_generated);
  r.triangles_in = p.f.n_triangles;
  r.triangles_front = c[kFrontFacing];
  r.triangles_back = c[kBackFacing];
  r.triangles_degenerate = c[kDegenerate];
  r.triangles_clipped = c[kClippedTris];
  r.triangles_frustum_culled = c[kFrustumCulled];
  r.triangles_edge_on = c[kEdgeOn];
  r.silhouette_edges = p.n_edges;
  r.visible_triangles = c[kVisibleTriangles];
  r.max_tile_pieces = c[kMaxTilePieces];
  r.float_anomalies = c[kFloatAnomalies];
  r.float_regularized = c[kFloatRegularized];
  r.float_negative_areas = c[kFloatNegativeAreas];
  r.float_exact_areas = c[kFloatExactAreas];
  r.deep_pairs = c[kDeepPairs];
  r.peak_device_bytes = ex.peak_bytes();
  if (ex.where == Where::gpu) r.walk_clock = walk_clock_totals();
  r.min_dram_bytes = p.f.n_vertices * 16 + p.f.n_triangles * 12 + n_samples * 4;
  if (ex.where == Where::gpu) {
    int khz = 0, bus_bits = 0;
    if (cudaDeviceGetAttribute(&khz, cudaDevAttrMemoryClockRate, 0) == cudaSuccess &&
        cudaDeviceGetAttribute(&bus_bits, cudaDevAttrGlobalMemoryBusWidth, 0) == cudaSuccess)
      r.dram_bandwidth_gbs = 2.0 * khz * 1e3 * (bus_bits / 8.0) / 1e9;  // double data rate
    // Thousands of empty launches: left out where each launch is slow (compute-sanitizer).
    if (!std::getenv("TILEVIS_CUDA_NO_LAUNCH_PROBE")) measure_launch_costs(ex, r);
  }
  return r;
}

template <class P>
std::vector<FrameTime> run_frames(const std::vector<trace::Frame>& frames, const CudaConfig& cfg, uint32_t laps) {
  Exec ex(cfg.device == Device::cpu ? Where::cpu : Where::gpu, cfg.shuffle_cpu);
  Pipeline<P> p(ex);
  p.cfg = cfg;
  p.counters.need(kCounterCount);
  p.sizes.need(kSizeSlots);
  Timer timer(ex);
  std::vector<FrameTime> out(frames.size());
  std::vector<std::vector<double>> lap_ms(frames.size());
  using clock = std::chrono::steady_clock;
  auto upload = [&](size_t k) {
    upload_frame_common(ex, frames[k], cfg.depth_bits, p.f, p.draws_host, p.vertices, p.indices, p.tri_draw, p.draws,
                        p.sample_xy);
    ex.sync();
  };
  // One new frame: one launch of the device-sized graph (DevGraph) when the pipeline has one
  // that still holds (no buffer moved, same frame constants and bounds) and the frame fits its
  // bounds: its time from the events. Otherwise (the first frames, a frame past a bound) runs
  // with host reads until everything fits, the bounds learned, and the graph recorded again:
  // the host clock around all of it. The host emulation: runs with host reads, then one
  // device-sized run (its results are the frame's).
  DevGraph<P> dg(p);
  const bool gpu = ex.where == Where::gpu;
  auto new_frame = [&](uint32_t& retries) {
    const auto t0 = clock::now();
    if (gpu && dg.valid()) {
      if (dg.launch()) return timer.ms(0, kStageCount);
      ++retries;
    } else if (!gpu && p.caps.items) {  // the emulation: a device-sized run within the bounds so far
      ex.reads = Exec::Reads::direct;
      p.dev = true;
      run_once(p, timer);
      p.dev = false;
      if (dev_fits(p)) return std::chrono::duration<double, std::milli>(clock::now() - t0).count();
      ++retries;
    }
    retries += settle_dev(p, timer);
    if (gpu) {
      const bool all = timer.all;
      timer.all = false;
      dg.capture([&] { return run_once(p, timer); });
      timer.all = all;
      if (!dg.launch()) throw std::runtime_error("cuda: the device-sized graph overflowed right after it was recorded");
    }
    return std::chrono::duration<double, std::milli>(clock::now() - t0).count();
  };
  for (uint32_t lap = 0; lap <= laps; ++lap)
    for (size_t k = 0; k < frames.size(); ++k) {
      upload(k);
      if (lap == 0) {
        const auto t0 = clock::now();
        new_frame(out[k].first_retries);
        out[k].first_ms = std::chrono::duration<double, std::milli>(clock::now() - t0).count();
        out[k].frame = uint32_t(k);
        uint64_t front = 0;
        ex.download(&front, p.counters.get() + kFrontFacing, 8);
        out[k].triangles_front = front;
      } else {
        lap_ms[k].push_back(new_frame(out[k].retries));
      }
      if (lap == laps) {
        std::vector<int32_t> ids(uint64_t(p.f.width) * p.f.height * p.f.n_samples);
        ex.download(ids.data(), p.ids.get(), ids.size() * 4);
        out[k].ids_hash = ids_hash(ids);
      }
    }
  for (size_t k = 0; k < frames.size(); ++k) out[k].new_frame_ms = median(lap_ms[k]);
  if (ex.where == Where::gpu) {
    // A known frame: its own graph (recorded from a run of it), replayed.
    const bool all = timer.all;
    for (size_t k = 0; k < frames.size(); ++k) {
      upload(k);
      timer.all = true;
      ex.reads = Exec::Reads::log;  // the read log of this frame
      for (uint32_t tries = 0; !run_once(p, timer);)
        if (++tries > 32) throw std::runtime_error("cuda: buffers still overflow after 32 retries");
      timer.all = false;
      FrameGraph g(ex);
      g.capture([&] { return run_once(p, timer); });
      g.replay();
      std::vector<double> ms;
      for (uint32_t r = 0; r < std::max<uint32_t>(cfg.runs, 1); ++r) {
        g.replay();
        ms.push_back(timer.ms(0, kStageCount));
      }
      out[k].graph_ms = median(ms);
    }
    timer.all = all;
  } else {
    for (auto& f : out) f.graph_ms = f.new_frame_ms;
  }
  ex.reads = Exec::Reads::direct;
  return out;
}

}  // namespace

uint64_t ids_hash(const std::vector<int32_t>& ids) {  // the ids' little-endian bytes
  static_assert(std::endian::native == std::endian::little);
  return fnv1a64(ids.data(), ids.size() * sizeof(int32_t));
}

std::vector<FrameTime> run_cuda_frames(const std::vector<trace::Frame>& frames, const CudaConfig& cfg, uint32_t laps) {
  if (frames.empty()) return {};
  if (!geom::TileGrid::valid_tile(cfg.tile_w) || !geom::TileGrid::valid_tile(cfg.tile_h))
    throw std::runtime_error("cuda: bad tile size");
  if (cfg.device == Device::gpu) {
    std::string why;
    if (!cuda_available(&why)) throw std::runtime_error("cuda: no usable GPU (" + why + ")");
  }
  return cfg.precision == Precision::exact ? run_frames<ExactP>(frames, cfg, laps) : run_frames<FloatP>(frames, cfg, laps);
}

bool cuda_available(std::string* why) {
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e != cudaSuccess || count == 0) {
    if (why) *why = e != cudaSuccess ? cudaGetErrorString(e) : "no CUDA device";
    return false;
  }
  return true;
}

CudaResult run_cuda(const trace::Frame& frame, const CudaConfig& cfg) {
  if (!geom::TileGrid::valid_tile(cfg.tile_w) || !geom::TileGrid::valid_tile(cfg.tile_h))
    throw std::runtime_error("cuda: tile " + std::to_string(cfg.tile_w) + "x" + std::to_string(cfg.tile_h) +
                             ": expected " + geom::TileGrid::valid_range() + " on each side");
  if (cfg.depth_bits < 1 || cfg.depth_bits > 32) throw std::runtime_error("cuda: depth bits must be 1..32");
  if (frame.samples.empty()) throw std::runtime_error("cuda: frame has no sample positions");
  if (cfg.device == Device::gpu) {
    std::string why;
    if (!cuda_available(&why)) throw std::runtime_error("cuda: no usable GPU (" + why + ")");
  }
  return cfg.precision == Precision::exact ? run<ExactP>(frame, cfg) : run<FloatP>(frame, cfg);
}

}  // namespace tilevis::cuda
