// Silhouette extraction (SVGPU §3.1) with a GPU hash table keyed by edge: one thread per edge
// use inserts its key (lowest global vertex index << 32 | highest) and counts the use and
// whether its triangle faces front; the lowest use index of each key is kept. An edge is a
// silhouette when some adjacent triangle faces front and not exactly two do. Edges made by
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
  const SetupTri* setup;
  uint64_t* keys;
  uint64_t* counts;
  uint32_t* first;
  uint64_t mask;
  uint32_t* flag;
  const uint64_t* offset;
  uint64_t* sil_key;
  uint32_t* sil_use;
};

TV_HD inline uint64_t find_slot(const HashArgs& a, uint64_t key, bool insert) {
  uint64_t h = hash64(key) & a.mask;
  for (;;) {
    uint64_t cur = a.keys[h];
    if (cur == kSkip && insert) cur = atomic_cas(&a.keys[h], kSkip, key);
    if (cur == key || (cur == kSkip && insert)) return h;
    h = (h + 1) & a.mask;
  }
}

TV_HD void hash_insert(const HashArgs& a, uint64_t u) {
  const uint64_t key = a.use_key[u];
  if (key == kSkip || is_boundary(key)) return;
  const uint64_t h = find_slot(a, key, true);
  atomic_add(&a.counts[h], 1 | (uint64_t(a.setup[u / 3].front) << 32));
  atomic_min(&a.first[h], uint32_t(u));
}

TV_HD void hash_judge(const HashArgs& a, uint64_t u) {
  const uint64_t key = a.use_key[u];
  uint32_t sil = 0;
  if (key == kSkip) {
    sil = 0;
  } else if (is_boundary(key)) {
    sil = a.setup[u / 3].front;
  } else {
    const uint64_t h = find_slot(a, key, false);
    if (a.first[h] == u) {
      const uint64_t c = a.counts[h];
      const uint64_t count = c & 0xffffffffu, front = c >> 32;
      sil = front > 0 && (count != 2 || front != count);
    }
  }
  a.flag[u] = sil;
}

TV_HD void sil_scatter(const HashArgs& a, uint64_t u) {
  if (!a.flag[u]) return;
  const uint64_t at = a.offset[u];
  a.sil_key[at] = a.use_key[u];
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
  HashArgs h{p.use_key.get(),        p.setup.get(), p.hash_keys.need(cap), p.hash_counts.need(cap),
             p.hash_first.need(cap), cap - 1,       p.sil_flag.need(uses + 1), p.sil_offset.need(uses + 1),
             nullptr,                nullptr};
  ex.fill_ones(h.keys, cap * 8);
  ex.zero(h.counts, cap * 8);
  ex.fill_ones(h.first, cap * 4);
  ex.launch(k_hash_insert, hash_insert, uses, h);
  ex.launch(k_hash_judge, hash_judge, uses, h);
  ex.exclusive_scan(h.flag, p.sil_offset.get(), uses);

  // Front triangles, scanned here so that one read brings back both counts.
  FrontArgs<P> fa{p.setup.get(), p.front_flag.need(p.n_setup + 1), p.front_offset.need(p.n_setup + 1), nullptr};
  ex.launch(k_front_flag<P>, front_flag<P>, p.n_setup, fa);
  ex.exclusive_scan(fa.flag, p.front_offset.get(), p.n_setup);

  // sync: silhouette and front-triangle counts size the tile stage.
  uint64_t counts[2];
  p.n_edges = ex.read(p.sil_offset.get() + uses);
  p.n_tris = ex.read(p.front_offset.get() + p.n_setup);
  (void)counts;

  fa.tris = p.tris.need(p.n_tris + 1);
  ex.launch(k_front_build<P>, front_build<P>, p.n_setup, fa);

  h.sil_key = p.sil_key.need(p.n_edges + 1);
  h.sil_use = p.sil_use.need(p.n_edges + 1);
  ex.launch(k_sil_scatter, sil_scatter, uses, h);
  const int end_bit = int(32 + bits_for(p.f.n_vertices));
  ex.sort_pairs(h.sil_key, p.sil_key_sorted.need(p.n_edges + 1), h.sil_use, p.sil_use_sorted.need(p.n_edges + 1),
                p.n_edges, end_bit > 64 ? 64 : end_bit);
  EdgeArgs<P> ea{p.setup.get(), p.sil_use_sorted.get(), p.edges.need(p.n_edges + 1)};
  ex.launch(k_build_edge<P>, build_edge<P>, p.n_edges, ea);
}

template void stage_silhouettes<ExactP>(Pipeline<ExactP>&);
template void stage_silhouettes<FloatP>(Pipeline<FloatP>&);

}  // namespace tilevis::cuda
