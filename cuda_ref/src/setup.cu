// Primitive setup on the GPU, one thread per trace triangle: facing from the exact sign of
// det[x y w] (edge-on triangles culled), near/far and guard-band clipping in clip space (double
// precision, Sutherland-Hodgman, intersection in homogeneous form from the inside vertex),
// viewport transform and snapping (x, y to 1/2^subpixel_bits pixel,
// round half to even; depth to 2^D - 1 levels), fan triangulation, pieces turned against their facing dropped, and
// the edge keys of silhouette extraction (SVGPU §3.1). The double arithmetic uses explicit
// round-to-nearest operations (never contracted to FMA), so the device reproduces the
// host's setup bit for bit.
#include <cmath>

#include "setup.cuh"

namespace tilevis::cuda {
namespace {

struct SetupArgs {
  FrameDev f;
  const float4* vertices;
  const uint32_t* indices;
  const uint32_t* tri_draw;
  const DrawInfo* draws;
  const uint32_t* weld;
  uint32_t* fan_count;
  const uint64_t* fan_offset;
  SetupTri* setup;
  uint64_t* use_key;
  uint32_t* use_forward;
  uint64_t* counters;
  double gx, gy;  // guard band half-widths in NDC
  int4* vtx;             // per vertex: snapped x, y, z, 1 when inside every plane (k_setup_vertex)
  uint32_t* front_flag;  // per setup triangle: front-facing (silhouettes scans them into the front list)
  int8_t* facing;        // per trace triangle: clip_facing, from setup_count (emit reads it back)
};

// The exact facing; the double filter settles nearly every triangle (the expansion took most
// of setup's double arithmetic). Made once per triangle, by setup_count, and kept for the emit.
TV_HD inline int clip_facing(const SetupArgs& a, uint64_t t) {
  return clip_facing_fast(a.vertices[a.indices[3 * t]], a.vertices[a.indices[3 * t + 1]],
                          a.vertices[a.indices[3 * t + 2]]);
}

// Per vertex: its snap and whether it lies inside every plane (as zbuffer.cu's zb_vertex). A
// triangle whose three vertices are inside is its own clipped polygon, and its setup triangle's
// vertices are these snaps (the same function of the same vertex), so a vertex is snapped once
// rather than once per triangle corner (three double divisions per triangle, twice).
TV_HD void setup_vertex(const SetupArgs& a, uint64_t i) { a.vtx[i] = snapped_vertex(a.f, a.gx, a.gy, a.vertices, i); }

// The common case: every vertex inside every plane, so clipping changes nothing (the polygon
// stays the triangle's three vertices in order). Decided from the vertices' flags, without the
// clipper.
TV_HD inline bool all_inside(const SetupArgs& a, uint64_t t) {
  return (a.vtx[a.indices[3 * t]].w & a.vtx[a.indices[3 * t + 1]].w & a.vtx[a.indices[3 * t + 2]].w) != 0;
}

TV_HD __noinline__ uint32_t count_clipped(const SetupArgs& a, uint64_t t) {
  ClipV poly[kMaxClipVerts];
  bool cut = false;
  const uint32_t n = clip_triangle(a.vertices, a.indices, a.gx, a.gy, t, poly, cut);
  if (n == 0) count_add(&a.counters[kFrustumCulled], 1);
  else if (cut) count_add(&a.counters[kClippedTris], 1);
  return n ? n - 2 : 0;
}

TV_HD void setup_count(const SetupArgs& a, uint64_t t) {
  const int facing = clip_facing(a, t);
  a.facing[t] = int8_t(facing);
  if (facing == 0) {
    count_add(&a.counters[kEdgeOn], 1);
    a.fan_count[t] = 0;
    return;
  }
  a.fan_count[t] = all_inside(a, t) ? 1 : count_clipped(a, t);
}

// Where a setup triangle's record and its three edge uses go: straight to the lists.
struct DirectOut {
  TV_HD SetupTri& rec(const SetupArgs& a, uint64_t out) const { return a.setup[out]; }
  TV_HD void use(const SetupArgs& a, uint64_t out, int e, uint64_t key, uint32_t forward) const {
    a.use_key[3 * out + e] = key;
    a.use_forward[3 * out + e] = forward;
  }
};

// One setup triangle: facing after the snap, and its three edge keys for silhouettes.
template <class Out>
TV_HD inline void emit_one(const SetupArgs& a, uint64_t t, uint64_t out, const Vtx& v0, const Vtx& v1, const Vtx& v2,
                           const uint32_t* idx, bool cut, int facing, const Out& o) {
  const uint32_t d = a.tri_draw[t];
  const DrawInfo& di = a.draws[d];
  SetupTri st;
  st.v[0] = v0;
  st.v[1] = v1;
  st.v[2] = v2;
  st.id = uint32_t(t);
  st.draw = d;
  st.opaque = di.opaque;
  st.cut = cut;
  const int64_t area = orient2d(v0.xy(), v1.xy(), v2.xy());
  // Counter-clockwise in NDC is clockwise in y-down window space: negative area. Facing is the
  // trace triangle's (clip_facing); a piece whose snapped area is zero or turns against it
  // covers nothing.
  const bool turns_as_facing = facing > 0 ? area < 0 : area > 0;
  st.front = facing > 0 && turns_as_facing;
  count_add(&a.counters[!turns_as_facing ? kDegenerate : facing < 0 ? kBackFacing : kFrontFacing], 1);
  o.rec(a, out) = st;
  a.front_flag[out] = st.front;
  // Edges made by clipping have no neighbour: boundaries, sorted after the draw's keyed edges.
  const uint64_t boundary = (uint64_t(di.vertex_offset + di.vertex_count - 1) << 32) | 0xffffffffu;
  for (int e = 0; e < 3; ++e) {
    uint64_t key;
    uint32_t forward = 0;
    if (!di.opaque) {
      key = ~uint64_t{0};  // no silhouettes from non-opaque draws
    } else if (cut) {
      key = boundary;
    } else {
      uint32_t i0 = idx[e], i1 = idx[(e + 1) % 3];
      if (di.soup) {
        i0 = a.weld[i0];
        i1 = a.weld[i1];
      }
      key = (uint64_t(i0 < i1 ? i0 : i1) << 32) | (i0 < i1 ? i1 : i0);
      forward = i0 < i1;
    }
    o.use(a, out, e, key, forward);
  }
}

template <class Out>
TV_HD __noinline__ void emit_clipped(const SetupArgs& a, uint64_t t, const Out& o) {
  ClipV poly[kMaxClipVerts];
  bool cut = false;
  const uint32_t n = clip_triangle(a.vertices, a.indices, a.gx, a.gy, t, poly, cut);
  if (n == 0) return;
  const int facing = a.facing[t];  // non-zero: emit_triangle returned for edge-on triangles
  Vtx sv[kMaxClipVerts];
  for (uint32_t k = 0; k < n; ++k) sv[k] = snap(a.f, a.gx, a.gy, poly[k]);
  uint64_t out = a.fan_offset[t];
  for (uint32_t k = 1; k + 1 < n; ++k, ++out) {
    const uint32_t idx[3] = {poly[0].index, poly[k].index, poly[k + 1].index};
    emit_one(a, t, out, sv[0], sv[k], sv[k + 1], idx, cut, facing, o);
  }
}

template <class Out>
TV_HD void emit_triangle(const SetupArgs& a, uint64_t t, const Out& o) {
  const int facing = a.facing[t];
  if (facing == 0) return;  // edge-on: setup_count gave it no fan
  const uint32_t idx[3] = {a.indices[3 * t], a.indices[3 * t + 1], a.indices[3 * t + 2]};
  const int4 q0 = a.vtx[idx[0]], q1 = a.vtx[idx[1]], q2 = a.vtx[idx[2]];
  if (!(q0.w & q1.w & q2.w)) {
    emit_clipped(a, t, o);
    return;
  }
  emit_one(a, t, a.fan_offset[t], Vtx{q0.x, q0.y, uint32_t(q0.z)}, Vtx{q1.x, q1.y, uint32_t(q1.z)},
           Vtx{q2.x, q2.y, uint32_t(q2.z)}, idx, false, facing, o);
}

TV_HD void setup_emit(const SetupArgs& a, uint64_t t) { emit_triangle(a, t, DirectOut{}); }

// On the GPU the records come out through shared memory. A block takes kEmitBlock trace
// triangles; their setup triangles are one run of the list (fan_offset scans the fans in trace
// order), so the block stages the run's first kEmitStage records and their edge uses and writes
// them out as consecutive words. Each thread writing its own 56-byte record made 14 stores,
// each touching other sectors. Records past the stage (a block of many clipped fans) go
// straight out.
inline constexpr uint32_t kEmitBlock = 256, kEmitStage = 320;

struct StagedOut {
  uint64_t o0;
  uint32_t* rec_words;  // kEmitStage records
  uint64_t* key;        // 3 kEmitStage
  uint32_t* forward;    // 3 kEmitStage
  TV_HD SetupTri& rec(const SetupArgs& a, uint64_t out) const {
    return out - o0 < kEmitStage ? reinterpret_cast<SetupTri*>(rec_words)[out - o0] : a.setup[out];
  }
  TV_HD void use(const SetupArgs& a, uint64_t out, int e, uint64_t k, uint32_t f) const {
    if (out - o0 < kEmitStage) {
      key[3 * (out - o0) + e] = k;
      forward[3 * (out - o0) + e] = f;
    } else {
      DirectOut{}.use(a, out, e, k, f);
    }
  }
};

__global__ void k_setup_vertex(SetupArgs a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) setup_vertex(a, i);
}
__global__ void k_setup_count(SetupArgs a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) setup_count(a, i);
}
__global__ void __launch_bounds__(kEmitBlock) k_setup_emit(SetupArgs a, uint64_t n_tagged) {
  TV_KERNEL_WAIT();
  __shared__ alignas(16) uint32_t rec[kEmitStage * kSetupWords];
  __shared__ alignas(16) uint64_t key[3 * kEmitStage];
  __shared__ uint32_t forward[3 * kEmitStage];
  const uint64_t n = count_of(n_tagged);
  for (uint64_t base = uint64_t(blockIdx.x) * kEmitBlock; base < n; base += uint64_t(gridDim.x) * kEmitBlock) {
    const uint32_t m = uint32_t(n - base < kEmitBlock ? n - base : kEmitBlock);
    const uint64_t o0 = a.fan_offset[base], o1 = a.fan_offset[base + m];
    if (threadIdx.x < m) emit_triangle(a, base + threadIdx.x, StagedOut{o0, rec, key, forward});
    __syncthreads();
    const uint32_t staged = uint32_t(o1 - o0 < kEmitStage ? o1 - o0 : kEmitStage);
    block_copy(reinterpret_cast<uint32_t*>(a.setup + o0), rec, staged * kSetupWords);
    block_copy(a.use_key + 3 * o0, key, 3 * staged);
    block_copy(a.use_forward + 3 * o0, forward, 3 * staged);
    __syncthreads();
  }
}

// ---- welding of triangle-soup draws by position -------------------------------------------

struct WeldArgs {
  const float4* vertices;
  const DrawInfo* draws;
  uint32_t n_draws;
  uint32_t* table;
  uint64_t mask;
  uint32_t* weld;
};

TV_HD inline uint32_t draw_of_vertex(const WeldArgs& a, uint32_t v) {
  uint32_t lo = 0, hi = a.n_draws;  // last draw whose vertex_offset <= v
  while (hi - lo > 1) {
    const uint32_t mid = (lo + hi) / 2;
    if (a.draws[mid].vertex_offset <= v) lo = mid;
    else hi = mid;
  }
  return lo;
}

TV_HD inline uint32_t float_key(float v) {  // -0 and +0 compare equal: one key
  uint32_t b;
  __builtin_memcpy(&b, &v, 4);
  return v == 0.0f ? 0u : b;
}

TV_HD inline bool same_position(const float4& p, const float4& q) {
  return p.x == q.x && p.y == q.y && p.z == q.z && p.w == q.w;
}

TV_HD inline uint64_t weld_hash(const float4& p, uint32_t draw) {
  uint64_t h = 0x9e3779b97f4a7c15ull * (draw + 1);
  for (uint32_t k : {float_key(p.x), float_key(p.y), float_key(p.z), float_key(p.w)}) {
    h ^= k;
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33;
  }
  return h;
}

// The slot of v's position class in the table (inserting v if the class is new).
TV_HD inline uint64_t weld_slot(const WeldArgs& a, uint32_t v, bool insert) {
  const uint32_t d = draw_of_vertex(a, v);
  const float4 p = a.vertices[v];
  uint64_t h = weld_hash(p, d) & a.mask;
  for (;;) {
    uint32_t cur = a.table[h];
    if (cur == kNone && insert) {
      cur = atomic_cas(&a.table[h], kNone, v);
      if (cur == kNone) return h;
    }
    if (cur != kNone && draw_of_vertex(a, cur) == d && same_position(a.vertices[cur], p)) return h;
    h = (h + 1) & a.mask;
  }
}

TV_HD void weld_insert(const WeldArgs& a, uint64_t v) {
  if (!a.draws[draw_of_vertex(a, uint32_t(v))].soup) return;
  const uint64_t h = weld_slot(a, uint32_t(v), true);
  atomic_min(&a.table[h], uint32_t(v));  // the class's lowest index
}

TV_HD void weld_resolve(const WeldArgs& a, uint64_t v) {
  if (!a.draws[draw_of_vertex(a, uint32_t(v))].soup) {
    a.weld[v] = uint32_t(v);
    return;
  }
  a.weld[v] = a.table[weld_slot(a, uint32_t(v), false)];
}

__global__ void k_weld_insert(WeldArgs a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) weld_insert(a, i);
}
__global__ void k_weld_resolve(WeldArgs a, uint64_t n) {
  TV_KERNEL_WAIT();
  TV_GRID_LOOP(i, n) weld_resolve(a, i);
}

}  // namespace

void upload_frame_common(Exec& ex, const trace::Frame& frame, uint32_t depth_bits, FrameDev& f,
                         std::vector<DrawInfo>& draws_host, Buf<float4>& vertices, Buf<uint32_t>& indices,
                         Buf<uint32_t>& tri_draw, Buf<DrawInfo>& draws, Buf<uint32_t>& sample_xy) {
  f = {};
  f.width = frame.width;
  f.height = frame.height;
  f.subpixel_bits = frame.subpixel_bits;
  f.depth_bits = depth_bits;
  f.n_samples = uint32_t(frame.samples.size());
  f.depth_near = frame.depth_near;
  f.depth_far = frame.depth_far;
  f.n_draws = uint32_t(frame.draws.size());
  std::vector<float4> v;
  std::vector<uint32_t> idx, td;
  draws_host.clear();
  for (uint32_t d = 0; d < frame.draws.size(); ++d) {
    const trace::Draw& dr = frame.draws[d];
    DrawInfo di{};
    di.vertex_offset = uint32_t(v.size());
    di.vertex_count = uint32_t(dr.vertices.size());
    di.triangle_offset = uint32_t(td.size());
    di.triangle_count = uint32_t(dr.indices.size() / 3);
    di.opaque = dr.opaque() && !dr.per_pixel_only();
    di.soup = (dr.flags & trace::kTriangleSoup) != 0;
    if (v.size() + dr.vertices.size() >= 0xffffffffull) throw std::runtime_error("cuda: more than 2^32 - 2 vertices");
    for (const auto& p : dr.vertices) v.push_back(make_float4(p.x, p.y, p.z, p.w));
    for (size_t k = 0; k + 2 < dr.indices.size(); k += 3) {
      for (int j = 0; j < 3; ++j) idx.push_back(di.vertex_offset + dr.indices[k + j]);
      td.push_back(d);
    }
    draws_host.push_back(di);
  }
  f.n_vertices = v.size();
  f.n_triangles = td.size();
  std::vector<uint32_t> s;
  for (const auto& sp : frame.samples) s.push_back(uint32_t(sp.x) | uint32_t(sp.y) << 16);
  ex.upload(vertices.need(v.size() + 1), v.data(), v.size() * sizeof(float4));
  ex.upload(indices.need(idx.size() + 1), idx.data(), idx.size() * 4);
  ex.upload(tri_draw.need(td.size() + 1), td.data(), td.size() * 4);
  ex.upload(draws.need(draws_host.size() + 1), draws_host.data(), draws_host.size() * sizeof(DrawInfo));
  ex.upload(sample_xy.need(s.size() + 1), s.data(), s.size() * 4);
}

template <class P>
void stage_setup(Pipeline<P>& p) {
  Exec& ex = p.ex;
  const FrameDev& f = p.f;
  const uint64_t n = f.n_triangles;
  const double gx = guard_band(f.width), gy = guard_band(f.height);

  uint32_t* weld = p.weld.need(f.n_vertices + 1);
  bool any_soup = false;
  for (const auto& d : p.draws_host) any_soup |= d.soup && d.vertex_count > 0;
  if (any_soup) {
    uint64_t cap = 1;
    while (cap < 2 * f.n_vertices + 2) cap <<= 1;
    uint32_t* table = p.weld_table.need(cap);
    ex.fill_ones(table, cap * 4);
    WeldArgs w{p.vertices.get(), p.draws.get(), f.n_draws, table, cap - 1, weld};
    ex.launch(k_weld_insert, weld_insert, f.n_vertices, w);
    ex.launch(k_weld_resolve, weld_resolve, f.n_vertices, w);
  }

  SetupArgs a{f,       p.vertices.get(), p.indices.get(), p.tri_draw.get(), p.draws.get(), weld, p.fan_count.need(n + 1),
              nullptr, nullptr,          nullptr,         nullptr,          p.counters.get(), gx, gy, nullptr, nullptr,
              p.tri_facing.need(n + 1)};
  a.fan_offset = p.fan_offset.need(n + 1);
  a.vtx = p.setup_vtx.need(f.n_vertices + 1);
  ex.launch(k_setup_vertex, setup_vertex, f.n_vertices, a);
  ex.launch(k_setup_count, setup_count, n, a);
  ex.exclusive_scan(a.fan_count, p.fan_offset.get(), n);
  if (p.dev) {  // the count stays on the device, within the learned bound
    p.n_setup = p.caps.setup;
    SizeArgs s{p.sizes.get(), 0, {p.fan_offset.get() + n, nullptr}, {p.n_setup, 0}, n, 0, {}, 0};
    queue_take_sizes(ex, s);
  } else {
    p.n_setup = ex.read(p.fan_offset.get() + n);  // sync: the setup triangle count sizes what follows
    Capacities::learn(p.caps.setup, p.n_setup);
  }
  a.setup = p.setup.need(p.n_setup + 1);
  a.use_key = p.use_key.need(3 * p.n_setup + 1);
  a.use_forward = p.use_forward.need(3 * p.n_setup + 1);
  a.front_flag = p.front_flag.need(p.n_setup + 1);
  ex.launch(k_setup_emit, setup_emit, p.N(kSzSetupEmit, n), a, kEmitBlock);
}

template void stage_setup<ExactP>(Pipeline<ExactP>&);
template void stage_setup<FloatP>(Pipeline<FloatP>&);

}  // namespace tilevis::cuda
