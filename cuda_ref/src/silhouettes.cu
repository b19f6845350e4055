// Silhouette extraction (SVGPU §3.1) with a GPU hash table keyed by edge: one thread per edge
// use inserts its key (lowest global vertex index << 32 | highest) and counts the use and
// whether its triangle faces front and whether it runs from its lower index; the lowest use
// index of each key is kept. An edge is a silhouette when some adjacent triangle faces front
// and not exactly two do from opposite sides (traversing it in opposite directions). Edges made by
// clip-space clipping are boundaries on their own. The canonical silhouette order (by draw,
// then key, then use; a draw's boundaries after its keyed edges) is one stable radix sort of
// the silhouettes by key, after compaction in use order.
#include "pipeline.cuh"

namespace tilevis::cuda {
namespace {

inline constexpr uint64_t kSkip = ~uint64_t{0};

TV_HD inline bool is_boundary(uint64_t key) { return key != kSkip && (key & 0xffffffffu) == 0xffffffffu; }

TV_HD inline uint64_t hash64(uint64_t k) {
  k ^= k >> 33;
  k *= 0xff51afd7ed558ccdull;
  k ^= k >> 33;
  k *= 0xc4ceb9fe1a85ec53ull;
  k ^= k >> 33;
  return k;
}

struct HashArgs {
  const uint64_t* use_key;
  const uint32_t* use_forward;
  HashSlot* slots;
  uint64_t mask;
  uint32_t* flag;
  const uint64_t* offset;
  uint64_t* sil_key;
  uint32_t* sil_use;
  uint64_t key_base;  // vertices + 1: the sort key of (lo, hi) is lo * key_base + hi (a boundary's hi: vertices)
  uint64_t stride;     // slots per vertex index (probe_first)
  const uint32_t* front;  // per setup triangle: front-facing (setup's flags: 4 bytes a triangle, not its record's sector)
};

// Where a key's slot is looked for. Nothing but time depends on it: a key's payload is the same
// wherever it lies. The first kLocalProbes slots from lo * stride plus a jitter of the key's
// hash (keys of nearby vertices, used by nearby triangles, share cache lines and stay in L2:
// the plain hash scattered them over a table larger than L2), then on from the key's hash over
// the whole table (a vertex of very many edges spills there instead of making one long run).
// Inserts and finds walk the same sequence; an insert stops at the key or the first empty slot,
// and slots only ever fill, so a find meets its key on the way.
inline constexpr uint32_t kLocalProbes = 32;

TV_HD inline uint64_t probe_first(const HashArgs& a, uint64_t key, uint64_t hk) {
  return ((key >> 32) * a.stride + (hk & 15)) & a.mask;
}
TV_HD inline uint64_t probe_next(const HashArgs& a, uint64_t h, uint64_t hk, uint32_t& step) {
  return ++step == kLocalProbes ? hk & a.mask : (h + 1) & a.mask;
}

TV_HD inline uint64_t find_slot(const HashArgs& a, uint64_t key, bool insert) {
  const uint64_t k1 = key + 1;  // keys are below 2^64 - 1 (their low half is a vertex index)
  const uint64_t hk = hash64(key);
  uint64_t h = probe_first(a, key, hk);
  uint32_t step = 0;
  for (;;) {
    uint64_t cur = a.slots[h].key1;
    if (cur == 0 && insert) {
      cur = atomic_cas(&a.slots[h].key1, 0, k1);
      if (cur == 0) return h;
    }
    if (cur == k1) return h;
    h = probe_next(a, h, hk, step);
  }
}

// A payload plus uses: counts saturating at 0x3ff (saturating sums of non-negative terms do not
// depend on their grouping or order), the complement of the lowest use index by maximum.
TV_HD inline uint64_t payload_add(uint64_t old, uint64_t count, uint64_t fronts, uint64_t forwards, uint64_t inv_first) {
  const uint64_t c = tmin<uint64_t>((old & 0x3ffu) + count, 0x3ffu);
  const uint64_t f = tmin<uint64_t>(((old >> 10) & 0x3ffu) + fronts, 0x3ffu);
  const uint64_t w = tmin<uint64_t>(((old >> 20) & 0x3ffu) + forwards, 0x3ffu);
  const uint64_t i = tmax<uint64_t>(old >> 32, inv_first);
  return c | f << 10 | w << 20 | i << 32;
}

#if defined(__CUDA_ARCH__)
// 16-byte compare-and-swap (sm_90): the slot held (c0, c1) -> (d0, d1); returns what it held.
__device__ inline void cas128(HashSlot* p, uint64_t c0, uint64_t c1, uint64_t d0, uint64_t d1, uint64_t& o0,
                              uint64_t& o1) {
  asm volatile(
      "{\n\t.reg .b128 tvc, tvd, tvo;\n\t"
      "mov.b128 tvc, {%3, %4};\n\t"
      "mov.b128 tvd, {%5, %6};\n\t"
      "atom.cas.relaxed.gpu.b128 tvo, [%2], tvc, tvd;\n\t"
      "mov.b128 {%0, %1}, tvo;\n\t}"
      : "=l"(o0), "=l"(o1)
      : "l"(p), "l"(c0), "l"(c1), "l"(d0), "l"(d1)
      : "memory");
}

// The device insert of a use: the slot's key and payload read together (one 16-byte load from
// L2), an empty slot claimed with its payload in one 16-byte CAS, a found key's payload updated
// by 64-bit CAS from the value read (the host's find_slot and payload CAS took up to four round
// trips: key, key CAS, payload, payload CAS).
__device__ inline void insert_wide(const HashArgs& a, uint64_t key, uint64_t count, uint64_t fronts, uint64_t forwards,
                                   uint64_t inv_first) {
  const uint64_t k1 = key + 1;
  const uint64_t hk = hash64(key);
  uint64_t h = probe_first(a, key, hk);
  uint32_t step = 0;
  for (;;) {
    HashSlot* s = &a.slots[h];
    const uint4 q = __ldcg(reinterpret_cast<const uint4*>(s));
    uint64_t cur = uint64_t(q.x) | uint64_t(q.y) << 32, old = uint64_t(q.z) | uint64_t(q.w) << 32;
    if (cur == 0) {  // an empty slot's payload is 0 too
      uint64_t o0, o1;
      cas128(s, 0, 0, k1, payload_add(0, count, fronts, forwards, inv_first), o0, o1);
      if (o0 == 0 && o1 == 0) return;
      cur = o0;
      old = o1;
    }
    if (cur == k1) {
      for (;;) {
        const uint64_t next = payload_add(old, count, fronts, forwards, inv_first);
        const uint64_t seen = atomic_cas(&s->payload, old, next);
        if (seen == old) return;
        old = seen;
      }
    }
    h = probe_next(a, h, hk, step);
  }
}
#endif

TV_HD void hash_insert(const HashArgs& a, uint64_t u) {
  const uint64_t key = a.use_key[u];
  if (key == kSkip || is_boundary(key)) return;
  // Payload: uses, front uses and forward uses in 10 bits each (saturating: only "two" matters),
  // the complement of the lowest use index in the high 32 bits.
  const uint64_t front = a.front[u / 3], forward = a.use_forward[u], inv_first = uint64_t(~uint32_t(u));
#if defined(__CUDA_ARCH__)
  insert_wide(a, key, 1, front, forward, inv_first);
#else
  const uint64_t h = find_slot(a, key, true);
  uint64_t* p = &a.slots[h].payload;
  uint64_t old = *p;
  for (;;) {
    const uint64_t next = payload_add(old, 1, front, forward, inv_first);
    const uint64_t seen = atomic_cas(p, old, next);
    if (seen == old) break;
    old = seen;
  }
#endif
}

TV_HD void hash_judge(const HashArgs& a, uint64_t u) {
  const uint64_t key = a.use_key[u];
  uint32_t sil = 0;
  if (key == kSkip) {
    sil = 0;
  } else if (is_boundary(key)) {
    sil = a.front[u / 3];
  } else {
    const uint64_t c = a.slots[find_slot(a, key, false)].payload;  // keys are never moved: the find's walk ends at it
    if (~uint32_t(c >> 32) == uint32_t(u)) {
      const uint64_t count = c & 0x3ffu, front = (c >> 10) & 0x3ffu, forwards = (c >> 20) & 0x3ffu;
      sil = front > 0 && (count != 2 || front != count || forwards != 1);
    }
  }
  a.flag[u] = sil;
}

TV_HD void sil_scatter(const HashArgs& a, uint64_t u) {
  if (!a.flag[u]) return;
  const uint64_t at = a.offset[u];
  // (lo, hi) as one number below key_base^2, in the same order as lo << 32 | hi (hi < key_base - 1,
  // or all ones for a boundary, which sorts last): fewer radix passes than the 64-bit key.
  const uint64_t k = a.use_key[u], hi = uint32_t(k);
  a.sil_key[at] = (k >> 32) * a.key_base + (hi == 0xffffffffu ? a.key_base - 1 : hi);
  a.sil_use[at] = uint32_t(u);
}

template <class P>
struct EdgeArgs {
  const SetupTri* setup;
  const uint32_t* sil_use;
  SilEdge<P>* edges;
};

template <class P>
TV_HD void build_edge(const EdgeArgs<P>& a, uint64_t i) {
  const uint32_t u = a.sil_use[i];
  const SetupTri& t = a.setup[u / 3];
  const uint32_t e = u % 3;
  a.edges[i] = make_sil_edge<P>(t.v[e], t.v[(e + 1) % 3]);
}

// Front-facing setup triangles in setup order: the tile stage's triangle list.
template <class P>
struct FrontArgs {
  const SetupTri* setup;
  uint32_t* flag;
  const uint64_t* offset;
  TileTri<P>* tris;
};

template <class P>
TV_HD void front_build(const FrontArgs<P>& a, uint64_t i) {
  const SetupTri& t = a.setup[i];
  if (!t.front) return;
  a.tris[a.offset[i]] = make_tile_tri<P>(t.v[0], t.v[1], t.v[2], t.id, t.opaque != 0);
}

__global__ void k_hash_insert(HashArgs a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) hash_insert(a, i);
}
__global__ void k_hash_judge(HashArgs a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) hash_judge(a, i);
}
__global__ void k_sil_scatter(HashArgs a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) sil_scatter(a, i);
}
template <class P>
__global__ void k_build_edge(EdgeArgs<P> a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) build_edge<P>(a, i);
}

// The front records (front_build's) built by a block for kFrontBlock setup triangles at a time,
// through shared memory: the block's front triangles are consecutive in the list (the scan keeps
// setup order), so their records leave as one run of words, every store coalesced (a thread per
// record, 140 bytes in float, made 35 stores each touching other sectors: 307 us on million with
// Nsight Compute, 56 us this way). The setup records come in the same way.
template <class P>
inline constexpr uint32_t kFrontBlock = sizeof(TileTri<P>) <= 160 ? 256 : 128;
template <class P>
__global__ void __launch_bounds__(kFrontBlock<P>) k_front_build_block(FrontArgs<P> a, uint64_t n_tagged) {
  TV_KERNEL_WAIT();
  constexpr uint32_t B = kFrontBlock<P>;
  static_assert(sizeof(TileTri<P>) % 4 == 0 && sizeof(SetupTri) % 4 == 0, "records of whole words");
  static_assert(sizeof(SetupTri) <= sizeof(TileTri<P>), "the staging holds either");
  constexpr uint32_t kTriWords = sizeof(TileTri<P>) / 4;
  __shared__ alignas(16) uint32_t buf[B * kTriWords];
  const uint64_t n = count_of(n_tagged);
  for (uint64_t base = uint64_t(blockIdx.x) * B; base < n; base += uint64_t(gridDim.x) * B) {
    const uint32_t m = uint32_t(n - base < B ? n - base : B);
    const uint64_t o0 = a.offset[base], o1 = a.offset[base + m];
    const uint32_t* src = reinterpret_cast<const uint32_t*>(a.setup + base);
    block_copy(buf, src, m * kSetupWords);
    __syncthreads();
    SetupTri t;
    bool front = false;
    uint64_t at = 0;
    if (threadIdx.x < m) {
      t = reinterpret_cast<const SetupTri*>(buf)[threadIdx.x];
      front = t.front != 0;
      if (front) at = a.offset[base + threadIdx.x] - o0;
    }
    __syncthreads();
    if (front) reinterpret_cast<TileTri<P>*>(buf)[at] = make_tile_tri<P>(t.v[0], t.v[1], t.v[2], t.id, t.opaque != 0);
    __syncthreads();
    block_copy(reinterpret_cast<uint32_t*>(a.tris + o0), buf, uint32_t(o1 - o0) * kTriWords);
    __syncthreads();
  }
}

}  // namespace

template <class P>
void stage_silhouettes(Pipeline<P>& p) {
  Exec& ex = p.ex;
  const uint64_t uses = 3 * p.n_setup;
  uint64_t cap = 16;
  while (cap < 2 * uses) cap <<= 1;  // load factor <= 1/2
  p.hash_cap = cap;
  HashArgs h{p.use_key.get(),    p.use_forward.get(),         p.hash_slots.need(cap), cap - 1,
             p.sil_flag.need(uses + 1), p.sil_offset.need(uses + 1), nullptr,       nullptr, 0,
             tmax<uint64_t>(1, cap / (p.f.n_vertices + 1)), p.front_flag.get() /* setup's */};
  // The table is all zeros between runs: cleared once when (re)allocated, and after each run's
  // last use on a side stream, off the stages' chain.
  if (p.hash_clean_at != h.slots || p.hash_clean < cap) ex.zero(h.slots, cap * sizeof(HashSlot));
  const uint64_t n_uses = p.N(kSzUses, uses), n_setup = p.N(kSzSetup, p.n_setup);
  ex.launch(k_hash_insert, hash_insert, n_uses, h);
  ex.launch(k_hash_judge, hash_judge, n_uses, h);
  ex.exclusive_scan(h.flag, p.sil_offset.get(), n_uses, uses);

  // Front triangles (setup's flags) beside the hash (side stream 0), scanned here so that one
  // read brings back both counts.
  FrontArgs<P> fa{p.setup.get(), p.front_flag.get(), p.front_offset.need(p.n_setup + 1), nullptr};
  ex.branch(0);
  ex.exclusive_scan(fa.flag, p.front_offset.get(), n_setup, p.n_setup);
  ex.on_main();
  ex.merge(0);

  if (p.dev) {  // the counts stay on the device, within the learned bounds
    p.n_edges = p.caps.edges;
    p.n_tris = p.caps.tris;
    SizeArgs s{p.sizes.get(), 1, {p.sil_offset.get() + uses, p.front_offset.get() + p.n_setup}, {p.n_edges, p.n_tris}, 0, 0,
               {{p.sil_key.need(p.n_edges + 1), 0, p.n_edges}}, 1};
    queue_take_sizes(ex, s);
  } else {
    // sync: silhouette and front-triangle counts size the tile stage.
    ex.read_many({{&p.n_edges, p.sil_offset.get() + uses}, {&p.n_tris, p.front_offset.get() + p.n_setup}});
    Capacities::learn(p.caps.edges, p.n_edges);
    Capacities::learn(p.caps.tris, p.n_tris);
  }

  // The silhouette edges on side stream 0, where binning goes on with them (stage_binning
  // resumes it), beside the front triangles on the main stream and their binning.
  ex.branch(0);
  h.sil_key = p.sil_key.need(p.n_edges + 1);
  h.sil_use = p.sil_use.need(p.n_edges + 1);
  h.key_base = p.f.n_vertices + 1;
  ex.launch(k_sil_scatter, sil_scatter, p.N(kSzSilScatter, uses), h);
  const cudaEvent_t scattered = ex.record();  // the table's last use
  const int end_bit = int(bits_for(h.key_base * h.key_base - 1));  // below 2^64: vertices < 2^32 - 1
  ex.sort_pairs(h.sil_key, p.sil_key_sorted.need(p.n_edges + 1), h.sil_use, p.sil_use_sorted.need(p.n_edges + 1),
                p.N(kSzEdges, p.n_edges), end_bit, p.n_edges, true);
  EdgeArgs<P> ea{p.setup.get(), p.sil_use_sorted.get(), p.edges.need(p.n_edges + 1)};
  ex.launch(k_build_edge<P>, build_edge<P>, p.N(kSzEdges, p.n_edges), ea);
  ex.on_main();

  fa.tris = p.tris.need(p.n_tris + 1);
  ex.launch(k_front_build_block<P>, front_build<P>, p.N(kSzFrontBuild, p.n_setup), fa, kFrontBlock<P>);
  ex.branch(1);
  ex.wait(scattered);
  ex.zero(h.slots, cap * sizeof(HashSlot));
  ex.on_main();
  p.hash_clean_at = h.slots;
  p.hash_clean = cap;
}

template void stage_silhouettes<ExactP>(Pipeline<ExactP>&);
template void stage_silhouettes<FloatP>(Pipeline<FloatP>&);

}  // namespace tilevis::cuda
