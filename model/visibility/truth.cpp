#include "visibility/truth.h"

#include <algorithm>
#include <numeric>

#include "geom/depth.h"
#include "geom/predicates.h"
#include "geom/tile_grid.h"
#include "visibility/zbuffer.h"

namespace tilevis::vis {
namespace {

class ZBuffer {
 public:
  ZBuffer(const Setup& s, const TruthConfig& cfg, const std::vector<svgpu::Triangle>& tris)
      : m_s(s), m_cfg(cfg), m_tris(tris), m_owner(size_t(s.width) * s.height * s.samples.size(), -1) {}

  // Does triangle t pass the depth test at s against the current owner (zbuffer.h), or with
  // quantized depth, is its rounded depth strictly smaller?
  bool passes(int32_t t, geom::Point s, int32_t current) const {
    if (current < 0) return true;
    const geom::DepthPlane &p = m_tris[size_t(t)].plane, &q = m_tris[size_t(current)].plane;
    if (m_cfg.quantized_depth_bits == 0) return zbuffer::passes(p, q, s);
    const int bits = int(m_cfg.quantized_depth_bits);
    return geom::quantized_depth(p, s, bits) < geom::quantized_depth(q, s, bits);
  }

  // Calls visit(sample index, px, py, point) for each sample of the frame the triangle covers.
  template <typename Visit>
  void raster(const svgpu::Triangle& t, Visit&& visit) const {
    zbuffer::for_covered_samples(m_s, t, zbuffer::whole_frame(m_s), [&](uint32_t px, uint32_t py, uint32_t k,
                                                                          geom::Point p) {
      visit(zbuffer::sample_index(m_s, px, py, k), px, py, p);
    });
  }

  std::vector<int32_t>& owner() { return m_owner; }
  void reset() { std::fill(m_owner.begin(), m_owner.end(), -1); }

 private:
  const Setup& m_s;
  const TruthConfig& m_cfg;
  const std::vector<svgpu::Triangle>& m_tris;
  std::vector<int32_t> m_owner;  // per sample: index into m_tris of the nearest so far
};

}  // namespace

TruthResult zbuffer_truth(const Setup& s, const TruthConfig& cfg) {
  TruthResult r;
  r.width = s.width;
  r.height = s.height;
  r.samples = uint32_t(s.samples.size());
  const size_t n_samples = size_t(s.width) * s.height * r.samples;

  std::vector<svgpu::Triangle> tris;
  std::vector<const SetupTriangle*> src;
  for (const auto& t : s.triangles)
    if (t.front) {
      tris.push_back(svgpu::Triangle::from(t.v[0], t.v[1], t.v[2]));
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

  // Pass 1, submission order: ids, generated fragments, early-Z (shader invocations: a
  // triangle's pixels with any covered / passing sample).
  bool any_translucent = false;
  auto& owner = zb.owner();
  for (size_t i = 0; i < tris.size(); ++i) {
    const bool opaque = src[i]->opaque;
    any_translucent = any_translucent || !opaque;
    const auto t = int32_t(i);
    zbuffer::PixelShades covered(src[i]->sample_rate), passed(src[i]->sample_rate);
    zb.raster(tris[i], [&](size_t k, uint32_t px, uint32_t py, geom::Point p) {
      ++r.fragments_generated;
      r.overdraw[k / r.samples] += 1.0f;
      ++r.tiles.at(tile_of(k), 0);
      covered.add(px, py, s.width);
      if (zb.passes(t, p, owner[k])) {
        passed.add(px, py, s.width);
        if (opaque) owner[k] = t;
      }
    });
    r.modes.none += covered.count;
    r.modes.early_z += passed.count;
  }
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
  // HSR and pre-pass shade each pixel once per triangle owning any of its samples.
  for (size_t pixel = 0; pixel < size_t(s.width) * s.height; ++pixel)
    zbuffer::for_invocations(
        owner.data() + pixel * r.samples, r.samples, int32_t(-1),
        [&](int32_t o) { return src[size_t(o)]->sample_rate; }, [&](int32_t) { ++r.modes.hsr; });
  r.modes.prepass = r.modes.hsr;

  // Translucent fragments after a pre-pass: shaded where in front of the final opaque depth.
  if (any_translucent) {
    std::vector<int32_t> final_owner = owner;
    for (size_t i = 0; i < tris.size(); ++i) {
      if (src[i]->opaque) continue;
      zbuffer::PixelShades shaded(src[i]->sample_rate);
      zb.raster(tris[i], [&](size_t k, uint32_t px, uint32_t py, geom::Point p) {
        if (zb.passes(int32_t(i), p, final_owner[k])) shaded.add(px, py, s.width);
      });
      r.modes.prepass += shaded.count;
      r.modes.hsr += shaded.count;
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
    zbuffer::PixelShades passed(src[i]->sample_rate);
    zb.raster(tris[i], [&](size_t k, uint32_t px, uint32_t py, geom::Point p) {
      if (zb.passes(int32_t(i), p, owner[k])) {
        passed.add(px, py, s.width);
        if (opaque) owner[k] = int32_t(i);
      }
    });
    r.modes.early_z_sorted += passed.count;
  }
  return r;
}

}  // namespace tilevis::vis
