#include "visibility/truth.h"

#include <algorithm>
#include <numeric>

#include "geom/depth.h"
#include "geom/predicates.h"
#include "geom/tile_grid.h"

namespace tilevis::vis {
namespace {

// A front-facing setup triangle prepared for rasterisation.
struct RasterTriangle {
  geom::TriangleEdges edges;   // top-left rule coverage
  geom::DepthPlane plane;      // exact depth
  int32_t min_x, max_x, min_y, max_y;

  explicit RasterTriangle(const SetupTriangle& t)
      : edges(geom::TriangleEdges::from(t.v[0].xy(), t.v[1].xy(), t.v[2].xy())),
        plane(geom::DepthPlane::from(geom::Triangle{{t.v[0], t.v[1], t.v[2]}})),
        min_x(std::min({t.v[0].x, t.v[1].x, t.v[2].x})),
        max_x(std::max({t.v[0].x, t.v[1].x, t.v[2].x})),
        min_y(std::min({t.v[0].y, t.v[1].y, t.v[2].y})),
        max_y(std::max({t.v[0].y, t.v[1].y, t.v[2].y})) {}
};

class ZBuffer {
 public:
  ZBuffer(const Setup& s, const TruthConfig& cfg, const std::vector<RasterTriangle>& tris)
      : m_s(s), m_cfg(cfg), m_tris(tris), m_samples(uint32_t(s.samples.size())),
        m_owner(size_t(s.width) * s.height * m_samples, -1) {}

  // Does triangle t pass a less-than depth test at s against the current owner? Equal
  // depth fails, so the earlier-submitted triangle keeps the sample.
  bool passes(int32_t t, geom::Point s, int32_t current) const {
    if (current < 0) return true;
    const geom::DepthPlane &p = m_tris[size_t(t)].plane, &q = m_tris[size_t(current)].plane;
    if (m_cfg.quantized_depth_bits == 0) return geom::depth_order(p, q, s) < 0;
    const int bits = int(m_cfg.quantized_depth_bits);
    return geom::quantized_depth(p, s, bits) < geom::quantized_depth(q, s, bits);
  }

  // Calls visit(sample_index, point) for each sample the triangle covers.
  template <typename Visit>
  void raster(const RasterTriangle& r, Visit&& visit) const {
    const uint32_t sb = m_s.subpixel_bits;
    const int64_t px0 = std::max<int64_t>(0, r.min_x >> sb), px1 = std::min<int64_t>(m_s.width - 1, r.max_x >> sb);
    const int64_t py0 = std::max<int64_t>(0, r.min_y >> sb), py1 = std::min<int64_t>(m_s.height - 1, r.max_y >> sb);
    for (int64_t py = py0; py <= py1; ++py)
      for (int64_t px = px0; px <= px1; ++px)
        for (uint32_t k = 0; k < m_samples; ++k) {
          const geom::Point p{int32_t((px << sb) + m_s.samples[k].x), int32_t((py << sb) + m_s.samples[k].y)};
          if (r.edges.covers(p)) visit((size_t(py) * m_s.width + size_t(px)) * m_samples + k, p);
        }
  }

  std::vector<int32_t>& owner() { return m_owner; }
  void reset() { std::fill(m_owner.begin(), m_owner.end(), -1); }

 private:
  const Setup& m_s;
  const TruthConfig& m_cfg;
  const std::vector<RasterTriangle>& m_tris;
  uint32_t m_samples;
  std::vector<int32_t> m_owner;  // per sample: index into m_tris of the nearest so far
};

}  // namespace

TruthResult zbuffer_truth(const Setup& s, const TruthConfig& cfg) {
  TruthResult r;
  r.width = s.width;
  r.height = s.height;
  r.samples = uint32_t(s.samples.size());
  const size_t n_samples = size_t(s.width) * s.height * r.samples;

  std::vector<RasterTriangle> tris;
  std::vector<const SetupTriangle*> src;
  for (const auto& t : s.triangles)
    if (t.front) {
      tris.emplace_back(t);
      src.push_back(&t);
    }
  ZBuffer zb(s, cfg, tris);
  r.overdraw.assign(size_t(s.width) * s.height, 0.0f);
  const geom::TileGrid grid = geom::TileGrid::make(s.width, s.height, cfg.tile_w, cfg.tile_h, s.subpixel_bits);
  r.tiles.resize(cfg.tile_w, cfg.tile_h, s.width, s.height, {"fragments_generated", "samples_covered"});
  auto tile_of = [&](size_t sample) {
    const size_t pixel = sample / r.samples;
    return grid.tile_at_pixel(uint32_t(pixel % s.width), uint32_t(pixel / s.width));
  };

  // Pass 1, submission order: ids, generated fragments, early-Z.
  bool any_translucent = false;
  auto& owner = zb.owner();
  for (size_t i = 0; i < tris.size(); ++i) {
    const bool opaque = src[i]->opaque;
    any_translucent = any_translucent || !opaque;
    const auto t = int32_t(i);
    zb.raster(tris[i], [&](size_t k, geom::Point p) {
      ++r.fragments_generated;
      r.overdraw[k / r.samples] += 1.0f;
      ++r.tiles.at(tile_of(k), 0);
      if (zb.passes(t, p, owner[k])) {
        ++r.modes.early_z;
        if (opaque) owner[k] = t;
      }
    });
  }
  r.modes.none = r.fragments_generated;
  r.modes.hsr_depth_tests = r.fragments_generated;

  r.ids.assign(n_samples, -1);
  r.covered.assign(s.triangle_draw.size(), 0);
  for (size_t k = 0; k < n_samples; ++k) {
    if (owner[k] < 0) continue;
    uint32_t id = src[size_t(owner[k])]->id;
    r.ids[k] = int32_t(id);
    ++r.covered[id];
    ++r.samples_covered;
    ++r.tiles.at(tile_of(k), 1);
  }
  r.modes.prepass = r.modes.hsr = r.samples_covered;

  // Translucent fragments after a pre-pass: shaded where in front of the final opaque depth.
  if (any_translucent) {
    std::vector<int32_t> final_owner = owner;
    for (size_t i = 0; i < tris.size(); ++i) {
      if (src[i]->opaque) continue;
      zb.raster(tris[i], [&](size_t k, geom::Point p) {
        if (zb.passes(int32_t(i), p, final_owner[k])) {
          ++r.modes.prepass;
          ++r.modes.hsr;
        }
      });
    }
  }

  // Pass 2: early-Z with draws sorted front to back by their nearest vertex depth.
  std::vector<uint32_t> draw_min(s.triangle_draw.empty() ? 0 : s.triangle_draw.back() + 1, ~0u);
  for (size_t i = 0; i < tris.size(); ++i) {
    uint32_t zmin = std::min({src[i]->v[0].z, src[i]->v[1].z, src[i]->v[2].z});
    draw_min[src[i]->draw] = std::min(draw_min[src[i]->draw], zmin);
  }
  std::vector<size_t> order(tris.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return draw_min[src[a]->draw] < draw_min[src[b]->draw]; });
  zb.reset();
  for (size_t i : order) {
    const bool opaque = src[i]->opaque;
    zb.raster(tris[i], [&](size_t k, geom::Point p) {
      if (zb.passes(int32_t(i), p, owner[k])) {
        ++r.modes.early_z_sorted;
        if (opaque) owner[k] = int32_t(i);
      }
    });
  }
  return r;
}

}  // namespace tilevis::vis
