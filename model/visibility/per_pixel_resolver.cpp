// The per_pixel mode: the exact z-buffer (zbuffer.h) over one tile. Every binned triangle in
// submission order; opaque triangles take the samples whose depth test they pass; non-opaque
// ones are rasterised (fragments) but never own a sample. Visible areas are sample counts
// times a sample's share of a pixel. The rule and the result are the z-buffer truth's.
#include <algorithm>

#include "visibility/tile_resolver.h"
#include "visibility/zbuffer.h"

namespace tilevis::vis {
namespace {

class PerPixelResolver final : public TileResolver {
 public:
  explicit PerPixelResolver(const ResolverOptions& o) : m_opt(o) {}

  TileVerdict resolve(const TileFrame& f, uint32_t tile, TileOutput& out, TileCounters& c,
                      std::vector<TileTriangleWork>* per_triangle) override {
    const auto& tris = f.tile_triangles(tile);
    if (tris.empty()) return {kPerPixelMode};
    const Setup& s = f.setup();
    const uint32_t ns = uint32_t(s.samples.size());
    const zbuffer::PixelRect region = zbuffer::tile_pixels(f.grid(), tile);
    const uint32_t w = region.x1 - region.x0;
    auto local = [&](uint32_t px, uint32_t py, uint32_t k) {
      return (size_t(py - region.y0) * w + size_t(px - region.x0)) * ns + k;
    };
    // Owner of each sample of the tile: a position in the tile's list, or -1.
    m_owner.assign(size_t(w) * (region.y1 - region.y0) * ns, -1);
    const size_t first_record = per_triangle ? per_triangle->size() : 0;
    const uint64_t step = f.tile_edges(tile).size() + tris.size();
    int64_t generated = 0;
    for (size_t n = 0; n < tris.size(); ++n) {
      const FrontTriangle& t = f.triangles()[tris[n]];
      const int64_t before = generated;
      zbuffer::for_covered_samples(s, t, region, [&](uint32_t px, uint32_t py, uint32_t k, geom::Point p) {
        ++generated;
        int32_t& o = m_owner[local(px, py, k)];
        if (t.t->opaque && (o < 0 || zbuffer::passes(t.plane, f.triangles()[tris[size_t(o)]].plane, p)))
          o = int32_t(n);
      });
      if (per_triangle) {
        TileTriangleWork record;
        record.triangle = t.setup_index;
        record.counters.fragments_generated = generated - before;
        per_triangle->push_back(record);
      }
      if (m_opt.work_done) m_opt.work_done(step);
    }
    int64_t covered = 0;
    const double sample_area = 1.0 / double(ns);
    for (uint32_t py = region.y0; py < region.y1; ++py)
      for (uint32_t px = region.x0; px < region.x1; ++px) {
        for (uint32_t k = 0; k < ns; ++k) {
          const int32_t o = m_owner[local(px, py, k)];
          if (o < 0) continue;
          const uint32_t id = f.triangles()[tris[size_t(o)]].t->id;
          out.ids[zbuffer::sample_index(s, px, py, k)] = int32_t(id);
          out.areas.emplace_back(id, sample_area);
          ++covered;
          if (per_triangle) ++(*per_triangle)[first_record + size_t(o)].counters.samples_covered;
        }
        // Each owner of the pixel's samples shades it once.
        zbuffer::for_invocations(
            &m_owner[local(px, py, 0)], ns, int32_t(-1),
            [&](int32_t o) { return f.triangles()[tris[size_t(o)]].t->sample_rate; },
            [&](int32_t o) {
              ++out.shader_invocations;
              if (per_triangle) ++(*per_triangle)[first_record + size_t(o)].shader_invocations;
            });
      }
    // Non-opaque triangles own nothing but are shaded (blended over the result) in each pixel
    // where some covered sample is in front of the final opaque surface: the truth's hsr rule.
    for (size_t n = 0; n < tris.size(); ++n) {
      const FrontTriangle& t = f.triangles()[tris[n]];
      if (t.t->opaque) continue;
      zbuffer::PixelShades shaded(t.t->sample_rate);
      zbuffer::for_covered_samples(s, t, region, [&](uint32_t px, uint32_t py, uint32_t k, geom::Point p) {
        const int32_t o = m_owner[local(px, py, k)];
        if (o < 0 || zbuffer::passes(t.plane, f.triangles()[tris[size_t(o)]].plane, p)) shaded.add(px, py, s.width);
      });
      out.shader_invocations += shaded.count;
      if (per_triangle) (*per_triangle)[first_record + n].shader_invocations += shaded.count;
    }
    c.samples_covered += covered;
    c.fragments_generated += generated;
    return {kPerPixelMode};
  }

 private:
  ResolverOptions m_opt;
  std::vector<int32_t> m_owner;
};

}  // namespace

std::unique_ptr<TileResolver> make_per_pixel_resolver(const ResolverOptions& o) {
  return std::make_unique<PerPixelResolver>(o);
}

}  // namespace tilevis::vis
