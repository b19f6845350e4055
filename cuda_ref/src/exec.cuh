// Where the stages run: on the GPU (kernels, CUB scans and sorts, one stream) or, for checking
// the kernels' logic without a GPU, on the host, calling the same __host__ __device__ stage
// bodies one element at a time. Buffers are grow-only and counted, so the peak device
// footprint of a scene is reported.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <utility>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "wide.cuh"

namespace tilevis::cuda {

void cuda_check(cudaError_t e, const char* what);
#define TV_CUDA(call) ::tilevis::cuda::cuda_check((call), #call)

// An element count passed to a kernel is either a value or, tagged by kDevCount, the address
// of a uint64_t in device memory that holds it (a size the host never reads: a device-sized
// run). Bits 48-55 of a tagged count hold bits_for(upper bound), so a launch can size its grid.
inline constexpr uint64_t kDevCount = uint64_t{1} << 63;
inline constexpr uint64_t kDevAddr = (uint64_t{1} << 48) - 1;
TV_HD inline uint64_t count_of(uint64_t n) {
  return n & kDevCount ? *reinterpret_cast<const uint64_t*>(static_cast<uintptr_t>(n & kDevAddr)) : n;
}
// Tagged count at p, at most `bound` (the host's upper bound: the buffers' capacity).
inline uint64_t dev_count(const uint64_t* p, uint64_t bound) {
  const uint64_t a = uint64_t(reinterpret_cast<uintptr_t>(p));
  if (a > kDevAddr) throw std::runtime_error("cuda: a device address past 48 bits cannot tag a count");
  uint64_t b = 0;
  while (b < 63 && (bound >> b) != 0) ++b;
  return kDevCount | b << 48 | a;
}
inline bool is_dev_count(uint64_t n) { return (n & kDevCount) != 0; }
inline uint64_t dev_count_bound(uint64_t n) {  // 2^bits >= the bound the tag was made with
  const uint64_t b = (n >> 48) & 0x7f;
  return b >= 63 ? ~uint64_t{0} : uint64_t{1} << b;
}

// Every kernel of this library starts with this: in a graph whose edge into the kernel is
// programmatic (pipeline.cu's programmatic_edges), the kernel is launched before the one it
// depends on has finished and waits here for it to complete with its memory visible; launched
// any other way it does nothing. Nothing before it may touch memory.
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
#define TV_KERNEL_WAIT() asm volatile("griddepcontrol.wait;" ::: "memory")
#else
#define TV_KERNEL_WAIT() ((void)0)
#endif

// Grid-stride loop over [0, n) (64-bit safe; n a value or a tagged device count, read once).
#define TV_GRID_LOOP(i, n)                                                                      \
  for (uint64_t i = uint64_t(blockIdx.x) * blockDim.x + threadIdx.x,                             \
                i##_end = ::tilevis::cuda::count_of(uint64_t(n));                                \
       i < i##_end; i += uint64_t(gridDim.x) * blockDim.x)

// A block's threads copy n elements, consecutive threads consecutive elements (the staged
// records of setup's emit and the front triangles, in and out of shared memory).
template <class T>
__device__ inline void block_copy(T* dst, const T* src, uint32_t n) {
  for (uint32_t k = threadIdx.x; k < n; k += blockDim.x) dst[k] = src[k];
}

// Fragment-parallel drawing in rounds (CudaRaster's fine raster; the tiled z-buffer and the
// hybrid's per-pixel tiles): in each round every lane takes the next set bit u of its coverage
// `cov` and `value(u)` for it, and lanes meeting at one u take turns at `merge(u, value)`, in lane
// order. Every lane of the warp calls it.
template <class V, class Value, class Merge>
__device__ inline void warp_fragment_rounds(uint64_t cov, Value value, Merge merge) {
  const uint32_t lane = threadIdx.x & 31u;
  while (__any_sync(0xffffffffu, cov != 0)) {
    int u = -1;
    V v{};
    if (cov) {
      u = __ffsll(static_cast<long long>(cov)) - 1;
      cov &= cov - 1;
      v = value(uint32_t(u));
    }
    const unsigned act = __ballot_sync(0xffffffffu, u >= 0);
    if (u >= 0) {
      const unsigned peers = __match_any_sync(act, u);
      for (unsigned pend = peers; pend; pend &= pend - 1) {
        if (int(lane) == __ffs(pend) - 1) merge(uint32_t(u), v);
        __syncwarp(peers);
      }
    }
    __syncwarp();  // a round's writes before the next round's reads (the votes order no memory)
  }
}

// ---- atomics that also run single-threaded on the host -------------------------------------

TV_HD inline uint32_t atomic_add(uint32_t* p, uint32_t v) {
#if defined(__CUDA_ARCH__)
  return atomicAdd(p, v);
#else
  const uint32_t o = *p;
  *p = o + v;
  return o;
#endif
}
TV_HD inline uint64_t atomic_add(uint64_t* p, uint64_t v) {
#if defined(__CUDA_ARCH__)
  return atomicAdd(reinterpret_cast<unsigned long long*>(p), static_cast<unsigned long long>(v));
#else
  const uint64_t o = *p;
  *p = o + v;
  return o;
#endif
}
TV_HD inline void atomic_add(int64_t* p, int64_t v) { atomic_add(reinterpret_cast<uint64_t*>(p), uint64_t(v)); }
template <class T, std::enable_if_t<sizeof(T) == 4, int> = 0>  // int32_t or uint32_t
TV_HD inline void atomic_max(T* p, T v) {
#if defined(__CUDA_ARCH__)
  atomicMax(p, v);
#else
  if (v > *p) *p = v;
#endif
}
TV_HD inline void atomic_max(uint64_t* p, uint64_t v) {
#if defined(__CUDA_ARCH__)
  atomicMax(reinterpret_cast<unsigned long long*>(p), static_cast<unsigned long long>(v));
#else
  if (v > *p) *p = v;
#endif
}
TV_HD inline void atomic_min(uint32_t* p, uint32_t v) {
#if defined(__CUDA_ARCH__)
  atomicMin(p, v);
#else
  if (v < *p) *p = v;
#endif
}
TV_HD inline uint32_t atomic_cas(uint32_t* p, uint32_t expect, uint32_t v) {
#if defined(__CUDA_ARCH__)
  return atomicCAS(p, expect, v);
#else
  const uint32_t o = *p;
  if (o == expect) *p = v;
  return o;
#endif
}
TV_HD inline uint64_t atomic_cas(uint64_t* p, uint64_t expect, uint64_t v) {
#if defined(__CUDA_ARCH__)
  return atomicCAS(reinterpret_cast<unsigned long long*>(p), static_cast<unsigned long long>(expect),
                   static_cast<unsigned long long>(v));
#else
  const uint64_t o = *p;
  if (o == expect) *p = v;
  return o;
#endif
}

// Counter updates from many threads to few addresses (a frame-wide count, a tile's row): the
// updates of a warp's active lanes to the same address are combined into one atomic, since
// atomics to one address are served one at a time (70 K of them cost tens of microseconds).
template <class T>  // uint32_t, uint64_t or int64_t
TV_HD inline void count_add(T* p, uint32_t v) {
#if defined(__CUDA_ARCH__)
  const unsigned group = __match_any_sync(__activemask(), reinterpret_cast<unsigned long long>(p));
  const unsigned s = __reduce_add_sync(group, v);
  if ((threadIdx.x & 31u) == unsigned(__ffs(group) - 1) && s) atomic_add(p, T(s));
#else
  *p += T(v);
#endif
}
TV_HD inline void count_max(uint64_t* p, uint32_t v) {
#if defined(__CUDA_ARCH__)
  const unsigned group = __match_any_sync(__activemask(), reinterpret_cast<unsigned long long>(p));
  const unsigned m = __reduce_max_sync(group, v);
  if ((threadIdx.x & 31u) == unsigned(__ffs(group) - 1) && m > 0)
    atomicMax(reinterpret_cast<unsigned long long*>(p), static_cast<unsigned long long>(m));
#else
  if (v > *p) *p = v;
#endif
}

// Bump allocation from a pool of `cap` elements; the counter keeps counting past the end so
// the host learns the size it needs. Returns UINT64_MAX on overflow.
TV_HD inline uint64_t bump(uint64_t* counter, uint64_t n, uint64_t cap) {
  const uint64_t at = atomic_add(counter, n);
  return at + n <= cap ? at : ~uint64_t{0};
}

// One slot from a bump counter, the atomics of a warp's active lanes combined into one.
TV_HD inline uint64_t bump_one(uint64_t* counter, uint64_t cap) {
#if defined(__CUDA_ARCH__)
  const unsigned mask = __activemask();
  const unsigned lane = threadIdx.x & 31u;
  const int leader = __ffs(mask) - 1;
  unsigned long long base = 0;
  if (int(lane) == leader) base = atomicAdd(reinterpret_cast<unsigned long long*>(counter), __popc(mask));
  base = __shfl_sync(mask, base, leader);
  const uint64_t at = base + __popc(mask & ((1u << lane) - 1u));
  return at < cap ? at : ~uint64_t{0};
#else
  return bump(counter, 1, cap);
#endif
}

// A team of lanes working on one element: a warp on the device (every lane of the warp takes
// the same element, so control flow that depends only on the element stays uniform), one lane
// on the host. A lane takes the element's sub-tasks lane(), lane() + kSize, ...
struct HostTeam {
  static constexpr uint32_t kSize = 1;
  TV_HD uint32_t lane() const { return 0; }
  TV_HD uint32_t ballot(bool p) const { return p ? 1u : 0u; }
  TV_HD uint64_t bcast(uint64_t v) const { return v; }
  TV_HD uint64_t sum(uint64_t v) const { return v; }
  TV_HD uint32_t scan(uint32_t v) const { return v; }  // inclusive prefix sum over the lanes
  TV_HD void sync() const {}
};

struct WarpTeam {
  static constexpr uint32_t kSize = 32;
  TV_HD uint32_t lane() const {
#if defined(__CUDA_ARCH__)
    return threadIdx.x & 31;
#else
    return 0;
#endif
  }
  TV_HD uint32_t ballot(bool p) const {
#if defined(__CUDA_ARCH__)
    return __ballot_sync(0xffffffffu, p);
#else
    return p;
#endif
  }
  TV_HD uint64_t bcast(uint64_t v) const {
#if defined(__CUDA_ARCH__)
    return __shfl_sync(0xffffffffu, static_cast<unsigned long long>(v), 0);
#else
    return v;
#endif
  }
  TV_HD uint64_t sum(uint64_t v) const {
#if defined(__CUDA_ARCH__)
    for (int d = 16; d > 0; d >>= 1) v += __shfl_xor_sync(0xffffffffu, static_cast<unsigned long long>(v), d);
#endif
    return v;
  }
  TV_HD uint32_t scan(uint32_t v) const {
#if defined(__CUDA_ARCH__)
    for (unsigned d = 1; d < 32; d <<= 1) {
      const uint32_t t = __shfl_up_sync(0xffffffffu, v, d);
      if ((threadIdx.x & 31u) >= d) v += t;
    }
#endif
    return v;
  }
  TV_HD void sync() const {
#if defined(__CUDA_ARCH__)
    __syncwarp();
#endif
  }
};

// Warp-stride loop over [0, n): warp w takes elements w, w + warps, ... (64-bit safe).
#define TV_WARP_LOOP(w, n)                                                                   \
  for (uint64_t w = (uint64_t(blockIdx.x) * blockDim.x + threadIdx.x) / 32,                  \
                w##_end = ::tilevis::cuda::count_of(uint64_t(n));                            \
       w < w##_end; w += uint64_t(gridDim.x) * blockDim.x / 32)

enum class Where { gpu, cpu };

class Exec {
 public:
  Exec(Where where, bool shuffle);
  ~Exec();
  Exec(const Exec&) = delete;
  Exec& operator=(const Exec&) = delete;

  const Where where;
  const bool shuffle;
  // The stream work is queued on: the frame's main stream, or a side stream between branch()
  // and on_main(). A side stream's work starts after the main stream's work queued before the
  // branch and runs beside what the main stream does next; merge(k) makes the main stream wait
  // for side k (each branch is merged before the run ends: merge_all). The host emulation runs
  // everything in order. Host reads happen on the main stream, after the merges they need.
  static constexpr int kSides = 6;  // 3 and 4: the hybrid verdicts, 5: the per-pixel tiles the counts decide
  cudaStream_t stream = nullptr;
  cudaStream_t main_stream = nullptr;
  void branch(int k);
  void resume(int k);  // back to side k, after the work it holds (a branch still pending: no new fork)
  void on_main();
  void merge(int k);
  void wait_for(int k);  // the stream in use waits for side k's work queued so far
  cudaEvent_t record();   // a point of the stream in use (null on the host)...
  void wait(cudaEvent_t point);  // ... that the stream in use waits for
  void merge_all();
  void begin_frame() {
    m_event_next = 0;
    m_checks.clear();
  }
  uint32_t grid_blocks = 0;  // blocks of 256 that fill the GPU (grid-stride kernels)
  std::string device_name;

  void* alloc(size_t bytes);
  void release(void* p, size_t bytes);
  uint64_t live_bytes() const { return m_live; }
  // Work queued and host round trips since the last reset (per-run accounting).
  uint32_t queued = 0, syncs = 0;

  // Host reads of device values inside a run (sizes, overflow counters): `direct` reads each
  // (a round trip); `log` does too and appends the bytes to read_log; `replay`, while a run is
  // captured into a CUDA graph, returns the bytes the last logged run read and notes where
  // they came from; queue_checks(), at the end of the run, copies those device values to the
  // same offsets of `read_check`, so that every replay of the graph can be checked against
  // the log (same frame, same sizes). The copies wait for the end of the run, off the stages'
  // chain: no stage writes a value once the host has read it.
  enum class Reads { direct, log, replay };
  Reads reads = Reads::direct;
  std::vector<uint8_t> read_log;
  size_t read_pos = 0;
  uint8_t* read_check = nullptr;
  void queue_checks();
  uint64_t peak_bytes() const { return m_peak; }

  void upload(void* dst, const void* src, size_t bytes);
  void download(void* dst, const void* src, size_t bytes);
  void zero(void* p, size_t bytes);
  void copy(void* dst, const void* src, size_t bytes);  // device to device, queued
  void fill_ones(void* p, size_t bytes);
  void sync();
  template <class T>
  T read(const T* p) {
    T v;
    download(&v, p, sizeof(T));
    return v;
  }
  // Several device scalars with one host round trip.
  void read_many(std::initializer_list<std::pair<uint64_t*, const uint64_t*>> items);

  // Visiting order of a host loop over n elements (identity, or scrambled when shuffling).
  uint64_t host_index(uint64_t k, uint64_t n) const;

  // Runs body(args, i) for i in [0, n): the kernel on the GPU, a loop on the host.
  template <class Args>
  void launch(void (*kernel)(Args, uint64_t), void (*body)(const Args&, uint64_t), uint64_t n, const Args& args,
              uint32_t block = 256) {
    if (n == 0) return;
    ++queued;
    if (where == Where::cpu) {
      const uint64_t m = count_of(n);
      for (uint64_t k = 0; k < m; ++k) body(args, host_index(k, m));
      return;
    }
    const uint64_t want = ((is_dev_count(n) ? dev_count_bound(n) : n) + block - 1) / block;
    const uint32_t blocks = uint32_t(want < grid_blocks * 8ull ? want : grid_blocks * 8ull);
    launch_kernel(reinterpret_cast<const void*>(kernel), blocks, block, &args, n);
  }
  // A kernel whose grid-stride (or warp-stride) loop reads its element count from device
  // memory (no host round trip); on the host the count is read first. `blocks`: the grid
  // (0: 4 x grid_blocks).
  template <class Args>
  void launch_dyn(void (*kernel)(Args, const uint64_t*, uint64_t), void (*body)(const Args&, uint64_t),
                  const uint64_t* count, uint64_t cap, const Args& args, uint32_t block = 256, uint32_t blocks = 0) {
    ++queued;
    if (where == Where::cpu) {
      uint64_t n = *count < cap ? *count : cap;
      for (uint64_t k = 0; k < n; ++k) body(args, host_index(k, n));
      return;
    }
    kernel<<<blocks ? blocks : grid_blocks * 4, block, 0, stream>>>(args, count, cap);
    TV_CUDA(cudaGetLastError());
  }

  // out[i] = sum of in[0..i) for i in [0, n]; in has n elements. Returns nothing: out[n]
  // holds the total on the device.
  // n may be a tagged device count (count_of): the scan then runs over `bound` elements, those
  // past the count read as zeros, and out[bound] holds the total.
  void exclusive_scan(const uint32_t* in, uint64_t* out, uint64_t n, uint64_t bound = 0);
  void exclusive_scan(const uint32_t* in, uint32_t* out, uint64_t n, uint64_t bound = 0);
  // Stable sort of (key, value) pairs by the key's bits [0, end_bit). n may be a tagged device
  // count: the keys from the count to `bound` are set to all ones first and `bound` pairs are
  // sorted (stable: the padding stays after every real pair, also one whose key is all ones);
  // `padded`: the caller has padded them (take_sizes).
  void sort_pairs(const uint64_t* keys_in, uint64_t* keys_out, const uint32_t* vals_in, uint32_t* vals_out, uint64_t n,
                  int end_bit, uint64_t bound = 0, bool padded = false);
  uint64_t generation() const { return m_generation; }  // counts allocations and releases

 private:
  template <class T>
  void scan_into(const uint32_t* in, T* out, uint64_t n, uint64_t bound);  // both exclusive_scan overloads
  void launch_kernel(const void* fn, uint32_t blocks, uint32_t block, const void* args, uint64_t n);
  void* temp(size_t bytes);  // scratch of CUB calls, one per stream (branches run at once)
  cudaEvent_t next_event();
  void join(int k, cudaStream_t into);  // `into` waits for side k's work queued so far
  uint64_t m_live = 0, m_peak = 0, m_generation = 0;
  cudaStream_t m_side[kSides] = {};
  int m_cur = 0;             // 0: main stream, k + 1: side k
  bool m_pending[kSides] = {};
  std::vector<cudaEvent_t> m_events;
  size_t m_event_next = 0;
  struct Check {
    size_t at;
    const void* src;
    size_t bytes;
  };
  std::vector<Check> m_checks;
  void* m_temp[kSides + 1] = {};
  size_t m_temp_bytes[kSides + 1] = {};
};

// A grow-only buffer on the executing side (device memory, or host memory for the cpu path).
template <class T>
class Buf {
 public:
  Buf() = default;
  explicit Buf(Exec* ex) : m_ex(ex) {}
  Buf(const Buf&) = delete;
  Buf& operator=(const Buf&) = delete;
  ~Buf() { reset(); }
  void bind(Exec* ex) { m_ex = ex; }
  // Ensures room for n elements (contents are not kept when it grows).
  T* need(uint64_t n) {
    if (n > m_cap) {
      reset();
      const uint64_t cap = n + n / 4 + 16;
      m_p = static_cast<T*>(m_ex->alloc(cap * sizeof(T)));
      m_cap = cap;
    }
    return m_p;
  }
  void reset() {
    if (m_p) m_ex->release(m_p, m_cap * sizeof(T));
    m_p = nullptr;
    m_cap = 0;
  }
  T* get() const { return m_p; }
  uint64_t cap() const { return m_cap; }
  void zero(uint64_t n) { m_ex->zero(m_p, n * sizeof(T)); }

 private:
  Exec* m_ex = nullptr;
  T* m_p = nullptr;
  uint64_t m_cap = 0;
};

}  // namespace tilevis::cuda
