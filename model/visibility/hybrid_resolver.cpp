// The hybrid mode (DESIGN.md "Visibility modes"): a tile goes per pixel where the analytic
// answer can be wrong, and is resolved analytically everywhere else:
//   1 interpenetration: two opaque triangles of the tile (other trace triangles) whose
//     planes cross strictly inside their overlap within the tile (exact predicates);
//   2 non-opaque content: such a triangle never occludes; its samples are the z-buffer's;
//   3 budget: triangles x edges over ResolverOptions::pair_budget (the overloaded tile).
// Where no pair of a tile's triangles crosses, silhouette splitting makes the analytic
// answer exact (SVGPU §4.3's assumption), so the result equals the z-buffer truth.
#include "geom/clip.h"
#include "geom/polygon.h"
#include "visibility/tile_resolver.h"

namespace tilevis::vis {
namespace {

class HybridResolver final : public TileResolver {
 public:
  explicit HybridResolver(const ResolverOptions& o)
      : m_opt(o), m_analytic(make_analytic_resolver(o)), m_per_pixel(make_per_pixel_resolver(o)) {}

  TileVerdict resolve(const TileFrame& f, uint32_t tile, FrameOutput& out, TileCounters& c,
                      std::vector<TileTriangleWork>* per_triangle) override {
    if (const int cause = fallback_cause(f, tile)) {
      m_per_pixel->resolve(f, tile, out, c, per_triangle);
      TileVerdict v{cause};
      if (cause == kPerPixelInterpenetration) {  // measured for the choice of granularity
        const geom::Rect rect = f.grid().rect(tile);
        for (uint32_t i : f.tile_triangles(tile)) v.crossing_triangles += crosses_an_occluder(f, f.triangles()[i], rect);
      }
      return v;
    }
    return m_analytic->resolve(f, tile, out, c, per_triangle);
  }

  std::vector<std::string> extra_columns() const override { return {"per_pixel", "per_pixel_cause"}; }
  void write_extra(const TileVerdict& v, int64_t* row) const override {
    row[0] = v.per_pixel_cause != 0;
    row[1] = v.per_pixel_cause;
  }

 private:
  int fallback_cause(const TileFrame& f, uint32_t tile) {
    const auto& tris = f.tile_triangles(tile);
    for (uint32_t i : tris)
      if (!f.triangles()[i].t->opaque) return kPerPixelNonOpaque;
    if (m_opt.pair_budget && uint64_t(tris.size()) * f.tile_edges(tile).size() > m_opt.pair_budget)
      return kPerPixelBudget;
    f.occluders(tile, m_occluders);
    const geom::Rect rect = f.grid().rect(tile);
    for (uint32_t i : tris)
      if (crosses_an_occluder(f, f.triangles()[i], rect)) return kPerPixelInterpenetration;
    return 0;
  }

  // Is there an opaque triangle u of the tile (another trace triangle) whose plane crosses
  // t's strictly inside their overlap within the tile? (svgpu::planes_cross, exact; the depth
  // ranges of a crossing pair overlap, so the pair is found from either member.)
  bool crosses_an_occluder(const TileFrame& f, const FrontTriangle& t, const geom::Rect& rect) const {
    const geom::ConvexPolygon poly = geom::clip_to_rect(geom::ConvexPolygon::from_triangle(t.tri), rect);
    if (poly.empty()) return false;
    for (uint32_t oi : m_occluders) {
      const FrontTriangle& u = f.triangles()[oi];
      if (u.z_min >= t.z_max) break;  // u at or behind t everywhere: so are all later occluders
      if (u.t->id != t.t->id && svgpu::planes_cross(poly, t, u)) return true;
    }
    return false;
  }

  ResolverOptions m_opt;
  std::unique_ptr<TileResolver> m_analytic, m_per_pixel;
  std::vector<uint32_t> m_occluders;
};

}  // namespace

std::unique_ptr<TileResolver> make_hybrid_resolver(const ResolverOptions& o) { return std::make_unique<HybridResolver>(o); }

}  // namespace tilevis::vis
