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
  const SetupTri* setup;
  HashSlot* slots;
  uint64_t mask;
  uint32_t* flag;
  const uint64_t* offset;
  uint64_t* sil_key;
  uint32_t* sil_use;
  uint64_t key_base;  // vertices + 1: the sort key of (lo, hi) is lo * key_base + hi (a boundary's hi: vertices)
};

TV_HD inline uint64_t find_slot(const HashArgs& a, uint64_t key, bool insert) {
  const uint64_t k1 = key + 1;  // keys are below 2^64 - 1 (their low half is a vertex index)
  uint64_t h = hash64(key) & a.mask;
  for (;;) {
    uint64_t cur = a.slots[h].key1;
    if (cur == 0 && insert) {
      cur = atomic_cas(&a.slots[h].key1, 0, k1);
      if (cur == 0) return h;
    }
    if (cur == k1) return h;
    h = (h + 1) & a.mask;
  }
}

TV_HD void hash_insert(const HashArgs& a, uint64_t u) {
  const uint64_t key = a.use_key[u];
  if (key == kSkip || is_boundary(key)) return;
  const uint64_t h = find_slot(a, key, true);
  const uint64_t front = a.setup[u / 3].front, forward = a.use_forward[u];
  // Payload: uses, front uses and forward uses in 10 bits each (saturating: only "two" matters),
  // the complement of the lowest use index in the high 32 bits.
  uint64_t* p = &a.slots[h].payload;
  uint64_t old = *p;
  for (;;) {
    const uint64_t count = tmin<uint64_t>((old & 0x3ffu) + 1, 0x3ffu);
    const uint64_t fronts = tmin<uint64_t>(((old >> 10) & 0x3ffu) + front, 0x3ffu);
    const uint64_t forwards = tmin<uint64_t>(((old >> 20) & 0x3ffu) + forward, 0x3ffu);
    const uint64_t inv_first = tmax<uint64_t>(old >> 32, uint64_t(~uint32_t(u)));
    const uint64_t next = count | fronts << 10 | forwards << 20 | inv_first << 32;
    const uint64_t seen = atomic_cas(p, old, next);
    if (seen == old) break;
    old = seen;
  }
}

TV_HD void hash_judge(const HashArgs& a, uint64_t u) {
  const uint64_t key = a.use_key[u];
  uint32_t sil = 0;
  if (key == kSkip) {
    sil = 0;
  } else if (is_boundary(key)) {
    sil = a.setup[u / 3].front;
  } else {
    const uint64_t c = a.slots[find_slot(a, key, false)].payload;
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
TV_HD void front_flag(const FrontArgs<P>& a, uint64_t i) { a.flag[i] = a.setup[i].front; }

template <class P>
TV_HD void front_build(const FrontArgs<P>& a, uint64_t i) {
  const SetupTri& t = a.setup[i];
  if (!t.front) return;
  a.tris[a.offset[i]] = make_tile_tri<P>(t.v[0], t.v[1], t.v[2], t.id, t.opaque != 0);
}

__global__ void k_hash_insert(HashArgs a, uint64_t n) {
  TV_GRID_LOOP(i, n) hash_insert(a, i);
}
__global__ void k_hash_judge(HashArgs a, uint64_t n) {
  TV_GRID_LOOP(i, n) hash_judge(a, i);
}
__global__ void k_sil_scatter(HashArgs a, uint64_t n) {
  TV_GRID_LOOP(i, n) sil_scatter(a, i);
}
template <class P>
__global__ void k_build_edge(EdgeArgs<P> a, uint64_t n) {
  TV_GRID_LOOP(i, n) build_edge<P>(a, i);
}
template <class P>
__global__ void k_front_flag(FrontArgs<P> a, uint64_t n) {
  TV_GRID_LOOP(i, n) front_flag<P>(a, i);
}
template <class P>
__global__ void k_front_build(FrontArgs<P> a, uint64_t n) {
  TV_GRID_LOOP(i, n) front_build<P>(a, i);
}

}  // namespace

template <class P>
void stage_silhouettes(Pipeline<P>& p) {
  Exec& ex = p.ex;
  const uint64_t uses = 3 * p.n_setup;
  uint64_t cap = 16;
  while (cap < 2 * uses) cap <<= 1;  // load factor <= 1/2
  p.hash_cap = cap;
  HashArgs h{p.use_key.get(),    p.use_forward.get(),         p.setup.get(), p.hash_slots.need(cap), cap - 1,
             p.sil_flag.need(uses + 1), p.sil_offset.need(uses + 1), nullptr,       nullptr, 0};
  // The table is all zeros between runs: cleared once when (re)allocated, and after each run's
  // last use on a side stream, off the stages' chain.
  if (p.hash_clean_at != h.slots || p.hash_clean < cap) ex.zero(h.slots, cap * sizeof(HashSlot));
  const uint64_t n_uses = p.N(kSzUses, uses), n_setup = p.N(kSzSetup, p.n_setup);
  ex.launch(k_hash_insert, hash_insert, n_uses, h);
  ex.launch(k_hash_judge, hash_judge, n_uses, h);
  ex.exclusive_scan(h.flag, p.sil_offset.get(), n_uses, uses);

  // Front triangles beside the hash (side stream 0), scanned here so that one read brings back
  // both counts.
  FrontArgs<P> fa{p.setup.get(), p.front_flag.need(p.n_setup + 1), p.front_offset.need(p.n_setup + 1), nullptr};
  ex.branch(0);
  ex.launch(k_front_flag<P>, front_flag<P>, n_setup, fa);
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

  fa.tris = p.tris.need(p.n_tris + 1);
  ex.branch(0);
  ex.launch(k_front_build<P>, front_build<P>, p.N(kSzFrontBuild, p.n_setup), fa);
  ex.on_main();

  h.sil_key = p.sil_key.need(p.n_edges + 1);
  h.sil_use = p.sil_use.need(p.n_edges + 1);
  h.key_base = p.f.n_vertices + 1;
  ex.launch(k_sil_scatter, sil_scatter, p.N(kSzSilScatter, uses), h);
  ex.branch(1);
  ex.zero(h.slots, cap * sizeof(HashSlot));
  ex.on_main();
  p.hash_clean_at = h.slots;
  p.hash_clean = cap;
  const int end_bit = int(bits_for(h.key_base * h.key_base - 1));  // below 2^64: vertices < 2^32 - 1
  ex.sort_pairs(h.sil_key, p.sil_key_sorted.need(p.n_edges + 1), h.sil_use, p.sil_use_sorted.need(p.n_edges + 1),
                p.N(kSzEdges, p.n_edges), end_bit, p.n_edges, true);
  EdgeArgs<P> ea{p.setup.get(), p.sil_use_sorted.get(), p.edges.need(p.n_edges + 1)};
  ex.launch(k_build_edge<P>, build_edge<P>, p.N(kSzEdges, p.n_edges), ea);
  ex.merge(0);
}

template void stage_silhouettes<ExactP>(Pipeline<ExactP>&);
template void stage_silhouettes<FloatP>(Pipeline<FloatP>&);

}  // namespace tilevis::cuda
