// The hybrid mode (DESIGN.md "Visibility modes"): a tile goes per pixel where the analytic
// answer can be wrong, and is resolved analytically everywhere else:
//   1 interpenetration: two opaque triangles of the tile (other trace triangles) whose
//     planes cross strictly inside their overlap within the tile (exact predicates);
//   2 non-opaque content: such a triangle never occludes; its samples are the z-buffer's;
//   3 budget: triangles x edges over ResolverOptions::pair_budget, or more triangles or edges
//     than the unit's on-chip lists hold (list_triangles, list_edges): the overloaded tile.
// Where no pair of a tile's triangles crosses, silhouette splitting makes the analytic
// answer exact (SVGPU §4.3's assumption), so the result equals the z-buffer truth.
#include <algorithm>
#include <vector>

#include "geom/clip.h"
#include "geom/polygon.h"
#include "visibility/tile_resolver.h"

namespace tilevis::vis {
namespace {

class HybridResolver final : public TileResolver {
 public:
  explicit HybridResolver(const ResolverOptions& o)
      : m_opt(o), m_analytic(make_analytic_resolver(o)), m_per_pixel(make_per_pixel_resolver(o)) {}

  TileVerdict resolve(const TileFrame& f, uint32_t tile, TileOutput& out, TileCounters& c,
                      std::vector<TileTriangleWork>* per_triangle) override {
    m_screens = m_tests = 0;
    TileVerdict v{fallback_cause(f, tile)};
    v.detection_screens = m_screens;
    v.detection_tests = m_tests;
    if (v.per_pixel_cause) {
      m_per_pixel->resolve(f, tile, out, c, per_triangle);
      // Measured for the choice of granularity: the triangles a per-triangle fallback would take.
      if (v.per_pixel_cause == kPerPixelInterpenetration) v.crossing_triangles = crossing_pairs(f, tile, true);
      return v;
    }
    m_analytic->resolve(f, tile, out, c, per_triangle);
    return v;
  }

  std::vector<std::string> extra_columns() const override {
    return {"per_pixel", "per_pixel_cause", "detection_screens", "detection_tests"};
  }
  void write_extra(const TileVerdict& v, int64_t* row) const override {
    row[0] = v.per_pixel_cause != 0;
    row[1] = v.per_pixel_cause;
    row[2] = int64_t(v.detection_screens);
    row[3] = int64_t(v.detection_tests);
  }

 private:
  int fallback_cause(const TileFrame& f, uint32_t tile) {
    const auto& tris = f.tile_triangles(tile);
    for (uint32_t i : tris)
      if (!f.triangles()[i].t->opaque) return kPerPixelNonOpaque;
    const size_t edges = f.tile_edges(tile).size();
    if ((m_opt.pair_budget && uint64_t(tris.size()) * edges > m_opt.pair_budget) ||
        (m_opt.list_triangles && tris.size() > m_opt.list_triangles) || (m_opt.list_edges && edges > m_opt.list_edges))
      return kPerPixelBudget;
    return crossing_pairs(f, tile, false) ? kPerPixelInterpenetration : 0;
  }

  // Pairs of the tile's opaque triangles (other trace triangles) whose planes cross strictly
  // inside their overlap within the tile (svgpu::planes_cross, exact, symmetric in the pair).
  // Only pairs whose boxes overlap with area and whose depth ranges overlap can cross. The
  // tile is cut into detection bins (ResolverOptions::detection_bin pixels); a triangle joins
  // every bin its box (closed) meets, so a pair whose boxes overlap with area shares a bin,
  // and the pair is decided in the first bin it shares (row-major). In each bin a sweep in
  // order of nearest depth keeps the triangles whose range reaches the current one's nearest
  // depth: a stack of disjoint depth ranges costs n log n, small triangles meet few others.
  // Returns 1 at the first crossing pair, or with `count_all` the number of triangles in some
  // crossing pair.
  uint32_t crossing_pairs(const TileFrame& f, uint32_t tile, bool count_all) {
    f.occluders(tile, m_occluders);  // nearest z_min first
    const geom::TileGrid& g = f.grid();
    const geom::Rect rect = g.rect(tile);
    const uint32_t n = uint32_t(m_occluders.size());
    const int64_t step = int64_t(m_opt.detection_bin ? m_opt.detection_bin : std::max(g.tile_w, g.tile_h))
                         << g.subpixel_bits;
    const uint32_t bins_x = uint32_t((int64_t(rect.x1) - rect.x0 + step - 1) / step);
    const uint32_t bins_y = uint32_t((int64_t(rect.y1) - rect.y0 + step - 1) / step);
    auto bin_of = [&](int64_t v, int64_t origin, uint32_t bins) {
      return uint32_t(std::clamp<int64_t>(v < origin ? 0 : (v - origin) / step, 0, int64_t(bins) - 1));
    };
    m_bins.assign(size_t(bins_x) * bins_y, {});
    m_range.resize(n);
    m_polys.resize(n);
    m_crossing.assign(n, 0);
    for (uint32_t k = 0; k < n; ++k) {  // in z_min order, so every bin's list is too
      const FrontTriangle& t = f.triangles()[m_occluders[k]];
      m_polys[k] = geom::clip_to_rect(geom::ConvexPolygon::from_triangle(t.tri), rect);
      if (m_polys[k].empty()) continue;
      m_range[k] = {bin_of(t.bbox.x0, rect.x0, bins_x), bin_of(t.bbox.y0, rect.y0, bins_y),
                    bin_of(t.bbox.x1, rect.x0, bins_x), bin_of(t.bbox.y1, rect.y0, bins_y)};
      for (uint32_t by = m_range[k].y0; by <= m_range[k].y1; ++by)
        for (uint32_t bx = m_range[k].x0; bx <= m_range[k].x1; ++bx) m_bins[size_t(by) * bins_x + bx].push_back(k);
    }
    uint32_t found = 0;
    for (uint32_t b = 0; b < m_bins.size(); ++b) {
      const uint32_t bx = b % bins_x, by = b / bins_x;
      m_active.clear();
      for (uint32_t k : m_bins[b]) {
        const FrontTriangle& t = f.triangles()[m_occluders[k]];
        std::erase_if(m_active, [&](uint32_t a) { return f.triangles()[m_occluders[a]].z_max <= t.z_min; });
        for (uint32_t a : m_active) {
          const FrontTriangle& u = f.triangles()[m_occluders[a]];
          if (u.t->id == t.t->id) continue;
          m_screens += !count_all;
          // Decided in the first bin the two share, by boxes that overlap with area only.
          if (std::max(m_range[k].x0, m_range[a].x0) != bx || std::max(m_range[k].y0, m_range[a].y0) != by) continue;
          if (!svgpu::may_cross(t, u) || svgpu::opposite_neighbours(t.tri, u.tri)) continue;
          m_tests += !count_all;
          if (!svgpu::planes_cross(m_polys[k], t, u)) continue;
          if (!count_all) return 1;
          found += !m_crossing[k] + !m_crossing[a];
          m_crossing[k] = m_crossing[a] = 1;
        }
        m_active.push_back(k);
      }
    }
    return found;
  }

  struct BinRange {
    uint32_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  };
  ResolverOptions m_opt;
  std::unique_ptr<TileResolver> m_analytic, m_per_pixel;
  std::vector<uint32_t> m_occluders, m_active;  // m_active: positions in m_occluders
  std::vector<uint8_t> m_crossing;
  uint64_t m_screens = 0, m_tests = 0;  // the current tile's detection work
  std::vector<geom::ConvexPolygon> m_polys;
  std::vector<BinRange> m_range;                // per position in m_occluders: its bins
  std::vector<std::vector<uint32_t>> m_bins;    // per detection bin: positions, nearest first
};

}  // namespace

std::unique_ptr<TileResolver> make_hybrid_resolver(const ResolverOptions& o) { return std::make_unique<HybridResolver>(o); }

}  // namespace tilevis::vis
