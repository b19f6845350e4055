#include "visibility/setup.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "geom/homogeneous.h"
#include "geom/predicates.h"
#include "visibility/parallel.h"

namespace tilevis::vis {
namespace {

struct ClipVertex {
  double x, y, z, w;
  uint32_t index;  // vertex index in the draw, kNoVertex if made by clipping
};

// Clip planes as distance functions; a vertex is inside when d >= 0.
struct Plane {
  double cx, cy, cz, cw;
  double distance(const ClipVertex& v) const { return cx * v.x + cy * v.y + cz * v.z + cw * v.w; }
};

// Sutherland–Hodgman against one plane, in double precision, in homogeneous coordinates:
// the intersection of edge (in, out) is din·out − dout·in (din >= 0 > dout), the point
// in + t (out − in) with t = din / (din − dout) scaled by din − dout > 0, which projects to
// the same place. Unlike the interpolated form it keeps its relative precision when the
// point lies next to the eye (a vertex at w ~ 1e-29 keeps its direction, where t rounds to
// 1 and the interpolation cancels to 0). It is computed from the inside vertex, so a shared
// edge of two triangles is cut at the same point from both sides, and scaled by a power of
// two (exact) so that repeated cuts neither underflow nor overflow.
ClipVertex intersect(const ClipVertex& in, const ClipVertex& out, double din, double dout) {
  ClipVertex v{din * out.x - dout * in.x, din * out.y - dout * in.y, din * out.z - dout * in.z,
               din * out.w - dout * in.w, kNoVertex};
  const double m = std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z), std::fabs(v.w)});
  if (m > 0 && m <= std::numeric_limits<double>::max()) {
    const int e = std::ilogb(m);
    v.x = std::scalbn(v.x, -e);
    v.y = std::scalbn(v.y, -e);
    v.z = std::scalbn(v.z, -e);
    v.w = std::scalbn(v.w, -e);
  }
  return v;
}

void clip_polygon(std::vector<ClipVertex>& poly, std::vector<ClipVertex>& scratch, const Plane& p) {
  scratch.clear();
  const size_t n = poly.size();
  for (size_t i = 0; i < n; ++i) {
    const ClipVertex& a = poly[i];
    const ClipVertex& b = poly[(i + 1) % n];
    double da = p.distance(a), db = p.distance(b);
    if (da >= 0) scratch.push_back(a);
    if ((da >= 0) != (db >= 0))
      scratch.push_back(da >= 0 ? intersect(a, b, da, db) : intersect(b, a, db, da));
  }
  poly.swap(scratch);
}

// Viewport transform (y down) in double, then the snap of geom/fixed.h: x, y to
// 1/2^subpixel_bits pixel and depth to 2^depth_bits levels, both rounded to nearest-even.
struct Snapper {
  double half_w, half_h, depth_near, depth_range, gx, gy;
  int subpixel_bits, depth_bits;

  Snapper(const trace::Frame& f, uint32_t bits)
      : half_w(f.width * 0.5),
        half_h(f.height * 0.5),
        depth_near(f.depth_near),
        depth_range(double(f.depth_far) - double(f.depth_near)),
        gx(guard_band_ndc(f.width)),
        gy(guard_band_ndc(f.height)),
        subpixel_bits(int(f.subpixel_bits)),
        depth_bits(int(bits)) {}

  // A clipped vertex of a triangle whose plane misses the eye (setup culls the others) has
  // w > 0 and |x|, |y| <= g w exactly; rounding in the clipper can leave it a hair outside
  // the band, or, next to w = 0, give w <= 0 for a point that lies at the band's edge in
  // the direction of (x, y). Projecting onto the band keeps both on the band's edge.
  static double project(double c, double w, double g) {
    if (!(w > 0)) return c > 0 ? g : c < 0 ? -g : 0.0;
    const double n = c * (1.0 / w);
    return n > g ? g : n < -g ? -g : n;  // also maps an infinite quotient onto the band
  }

  geom::Vertex operator()(const ClipVertex& v) const {
    const double xn = project(v.x, v.w, gx), yn = project(v.y, v.w, gy);
    const double zn = v.w > 0 ? v.z * (1.0 / v.w) : 0.0;  // depth is clamped to [0, 1] by the snap
    const double xw = (xn + 1.0) * half_w;
    const double yw = (1.0 - yn) * half_h;
    const double zw = depth_near + depth_range * (zn + 1.0) * 0.5;
    const auto x = geom::snap_coord(xw, subpixel_bits), y = geom::snap_coord(yw, subpixel_bits);
    // Inside the band by construction: guard_band_ndc keeps |window| < 2^15 pixels.
    if (!x || !y) throw std::logic_error("primitive setup: a projected vertex left the guard band");
    return {*x, *y, geom::snap_depth(zw, depth_bits)};
  }
};

// One triangle edge seen from one setup triangle, for silhouette extraction.
struct EdgeUse {
  uint64_t key;        // (min index << 32) | max index within the draw
  uint32_t triangle;   // setup triangle
  uint8_t edge;        // 0..2: v[edge] -> v[(edge+1)%3]
  bool forward = true; // the edge runs from the smaller index to the larger
  bool front = false;  // the triangle's (beside it: the runs below need no look-up of it)
};

// Orders edge uses by (key, triangle, edge): a counting sort by the smaller vertex index (the
// key's high half), then each bucket, a vertex's few edges, sorted in place. Boundaries (key
// ~0: made by clipping) go last, in the (triangle, edge) order they were pushed in, as a
// comparison sort puts them. `out` and `bucket` are scratch kept across draws.
void sort_edge_uses(const std::vector<EdgeUse>& in, size_t vertices, std::vector<EdgeUse>& out,
                    std::vector<uint32_t>& bucket) {
  bucket.assign(vertices + 2, 0);
  for (const EdgeUse& e : in) ++bucket[e.key == ~uint64_t(0) ? vertices + 1 : size_t(e.key >> 32) + 1];
  for (size_t v = 1; v < bucket.size(); ++v) bucket[v] += bucket[v - 1];
  out.resize(in.size());
  std::vector<uint32_t> fill(bucket.begin(), bucket.end() - 1);
  for (const EdgeUse& e : in) out[fill[e.key == ~uint64_t(0) ? vertices : size_t(e.key >> 32)]++] = e;
  for (size_t v = 0; v < vertices; ++v)
    if (bucket[v + 1] - bucket[v] > 1)
      std::sort(out.begin() + bucket[v], out.begin() + bucket[v + 1], [](const EdgeUse& a, const EdgeUse& b) {
        return a.key != b.key ? a.key < b.key : a.triangle != b.triangle ? a.triangle < b.triangle : a.edge < b.edge;
      });
}

std::vector<uint32_t> weld_by_position(const std::vector<trace::Vec4>& v) {
  std::vector<uint32_t> order(v.size()), weld(v.size());
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  auto key = [&](uint32_t i) { return std::array<float, 4>{v[i].x, v[i].y, v[i].z, v[i].w}; };
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
  for (size_t k = 0; k < order.size(); ++k)
    weld[order[k]] = (k > 0 && key(order[k]) == key(order[k - 1])) ? weld[order[k - 1]] : order[k];
  return weld;
}

// One draw's share of the setup. Draws are independent (a draw's silhouettes pair only its
// own edges), so they run on threads and are joined in draw order.
struct DrawSetup {
  std::vector<SetupTriangle> triangles;
  std::vector<SilhouetteEdge> silhouettes;
  SetupStats stats;
};

struct DrawScratch {
  std::vector<ClipVertex> poly, scratch;
  std::vector<geom::Vertex> snapped;
  std::vector<EdgeUse> edges, sorted;
  std::vector<uint32_t> bucket;
};

// Draw `di`, whose first triangle has id `id`.
void setup_draw(const trace::Frame& frame, uint32_t di, uint32_t id, const Snapper& snap,
                const std::array<Plane, 6>& planes, DrawScratch& w, DrawSetup& out) {
  const trace::Draw& d = frame.draws[di];
  const bool opaque = d.opaque() && !d.per_pixel_only();
  // Soup draws key silhouettes by position: vertices with bit-identical clip-space
  // positions are welded to the lowest such index.
  std::vector<uint32_t> weld;
  if (d.flags & trace::kTriangleSoup) weld = weld_by_position(d.vertices);
  w.snapped.resize(d.vertices.size());
  std::vector<bool> snapped_ok(d.vertices.size(), false);
  w.edges.clear();
  for (size_t t = 0; t < d.indices.size(); t += 3, ++id) {
    ++out.stats.triangles_in;
    w.poly.clear();
    for (int k = 0; k < 3; ++k) {
      uint32_t vi = d.indices[t + k];
      const trace::Vec4& v = d.vertices[vi];
      w.poly.push_back({v.x, v.y, v.z, v.w, vi});
    }
    // Facing is decided once, in clip space, for every piece clipping leaves (the facing of
    // the clipped polygon: geom/homogeneous.h). Zero: the eye lies in the triangle's plane,
    // so it projects to a line (or, through the eye itself, nowhere): nothing to draw.
    const trace::Vec4 &c0 = d.vertices[d.indices[t]], &c1 = d.vertices[d.indices[t + 1]],
                      &c2 = d.vertices[d.indices[t + 2]];
    const int facing = geom::homogeneous_orientation(c0.x, c0.y, c0.w, c1.x, c1.y, c1.w, c2.x, c2.y, c2.w);
    if (facing == 0) {
      ++out.stats.edge_on;
      continue;
    }
    bool culled = false, cut = false;
    for (const Plane& p : planes) {
      int inside = 0;
      for (const auto& v : w.poly) inside += p.distance(v) >= 0;
      if (inside == 0) {
        culled = true;
        break;
      }
      if (inside < int(w.poly.size())) {
        clip_polygon(w.poly, w.scratch, p);
        cut = true;
      }
    }
    if (culled || w.poly.size() < 3) {
      ++out.stats.frustum_culled;
      continue;
    }
    out.stats.clipped += cut;
    std::array<geom::Vertex, 16> sv{};
    for (size_t k = 0; k < w.poly.size() && k < sv.size(); ++k) {
      uint32_t vi = w.poly[k].index;
      if (vi != kNoVertex) {
        if (!snapped_ok[vi]) {
          w.snapped[vi] = snap(w.poly[k]);
          snapped_ok[vi] = true;
        }
        sv[k] = w.snapped[vi];
      } else {
        sv[k] = snap(w.poly[k]);
      }
    }
    // Fan: (p0, pk, pk+1). Triangles made by clipping carry no vertex indices.
    for (size_t k = 1; k + 1 < w.poly.size(); ++k) {
      SetupTriangle st;
      st.v[0] = sv[0];
      st.v[1] = sv[k];
      st.v[2] = sv[k + 1];
      st.id = id;
      st.draw = di;
      st.opaque = opaque;
      st.sample_rate = d.sample_rate();
      st.clipped = cut;
      int64_t area = geom::orient2d(st.v[0].xy(), st.v[1].xy(), st.v[2].xy());
      // Counter-clockwise in NDC is clockwise in y-down window space: negative area. A piece
      // whose snapped area is zero or turns against its triangle's facing covers nothing.
      const bool turns_as_facing = facing > 0 ? area < 0 : area > 0;
      st.front = facing > 0 && turns_as_facing;
      if (!turns_as_facing) ++out.stats.degenerate;
      else if (facing < 0) ++out.stats.back_facing;
      else ++out.stats.front_facing;
      auto tri = static_cast<uint32_t>(out.triangles.size());
      uint32_t idx[3] = {cut ? kNoVertex : w.poly[0].index, cut ? kNoVertex : w.poly[k].index,
                         cut ? kNoVertex : w.poly[k + 1].index};
      if (!weld.empty())
        for (auto& i : idx)
          if (i != kNoVertex) i = weld[i];
      for (uint8_t e = 0; e < 3; ++e) {
        uint32_t i0 = idx[e], i1 = idx[(e + 1) % 3];
        if (i0 == kNoVertex || i1 == kNoVertex) {
          // An edge made by clipping has no neighbour to pair with: a boundary.
          w.edges.push_back({~uint64_t(0), tri, e, true, st.front});
          continue;
        }
        uint64_t key = (uint64_t(std::min(i0, i1)) << 32) | std::max(i0, i1);
        w.edges.push_back({key, tri, e, i0 < i1, st.front});
      }
      out.triangles.push_back(st);
    }
  }
  if (!opaque) return;
  // Silhouette extraction: order edge uses by (key, triangle, edge), then judge each run of
  // equal keys.
  sort_edge_uses(w.edges, d.vertices.size(), w.sorted, w.bucket);
  w.edges.swap(w.sorted);
  for (size_t i = 0; i < w.edges.size();) {
    size_t j = i + 1;
    if (w.edges[i].key != ~uint64_t(0))
      while (j < w.edges.size() && w.edges[j].key == w.edges[i].key) ++j;
    size_t front = 0;
    for (size_t k = i; k < j; ++k) front += w.edges[k].front;
    size_t count = j - i;
    // An edge is interior to the visible surface only where exactly two front-facing
    // triangles share it from opposite sides, i.e. traverse it in opposite directions. Two
    // that traverse it the same way (a duplicated face, a mesh folded onto itself, faces
    // wound inconsistently) lie on the same side of it on screen: it bounds them both.
    if (front > 0 && (count != 2 || front != count || w.edges[i].forward == w.edges[i + 1].forward)) {
      const SetupTriangle& t = out.triangles[w.edges[i].triangle];
      SilhouetteEdge se{t.v[w.edges[i].edge], t.v[(w.edges[i].edge + 1) % 3], di};
      out.silhouettes.push_back(se);
    }
    i = j;
  }
}

}  // namespace

double guard_band_ndc(uint32_t pixels) {
  // Window x = (ndc + 1) · pixels / 2 must stay below 2^15 pixels in magnitude.
  return std::floor(65536.0 / pixels) - 2.0;
}

Setup primitive_setup(const trace::Frame& frame, const SetupConfig& config) {
  Setup s;
  s.width = frame.width;
  s.height = frame.height;
  s.samples = frame.samples;
  s.subpixel_bits = frame.subpixel_bits;
  s.depth_bits = config.depth_bits;
  const Snapper snap(frame, config.depth_bits);
  const double gx = guard_band_ndc(frame.width), gy = guard_band_ndc(frame.height);
  const std::array<Plane, 6> planes = {{{0, 0, 1, 1},     // near: z >= -w
                                        {0, 0, -1, 1},    // far: z <= w
                                        {1, 0, 0, gx},    // guard band left
                                        {-1, 0, 0, gx},   // right
                                        {0, 1, 0, gy},    // bottom
                                        {0, -1, 0, gy}}};  // top

  const size_t n = frame.draws.size();
  std::vector<uint32_t> first(n + 1, 0);
  for (size_t di = 0; di < n; ++di) first[di + 1] = first[di] + uint32_t(frame.draws[di].triangle_count());
  std::vector<DrawSetup> draws(n);
  for_each_index<DrawScratch>(n, [&](size_t di, DrawScratch& w) { setup_draw(frame, uint32_t(di), first[di], snap, planes, w, draws[di]); });

  s.triangles.reserve(frame.triangle_count());
  s.triangle_draw.reserve(frame.triangle_count());
  for (size_t di = 0; di < n; ++di) {
    DrawSetup& d = draws[di];
    s.triangles.insert(s.triangles.end(), d.triangles.begin(), d.triangles.end());
    s.silhouettes.insert(s.silhouettes.end(), d.silhouettes.begin(), d.silhouettes.end());
    s.triangle_draw.insert(s.triangle_draw.end(), first[di + 1] - first[di], uint32_t(di));
    const SetupStats& t = d.stats;
    s.stats.triangles_in += t.triangles_in;
    s.stats.frustum_culled += t.frustum_culled;
    s.stats.clipped += t.clipped;
    s.stats.edge_on += t.edge_on;
    s.stats.degenerate += t.degenerate;
    s.stats.back_facing += t.back_facing;
    s.stats.front_facing += t.front_facing;
    d = DrawSetup{};
  }
  s.stats.setup_triangles = s.triangles.size();
  s.stats.silhouette_edges = s.silhouettes.size();
  return s;
}

}  // namespace tilevis::vis
