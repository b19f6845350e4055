#include "visibility/tile_resolver.h"

#include <algorithm>
#include <iterator>
#include <stdexcept>

#include "geom/overlap.h"

namespace tilevis::vis {

void FrameOutput::add(TileOutput&& tile) {
  for (const auto& [id, area] : tile.areas) visible_area[id] += area;
  pieces.insert(pieces.end(), std::make_move_iterator(tile.pieces.begin()), std::make_move_iterator(tile.pieces.end()));
  visible_triangles += tile.visible_triangles;
  shader_invocations += tile.shader_invocations;
  max_tile_pieces = std::max(max_tile_pieces, tile.max_tile_pieces);
  if (tile.longest_walk.steps > longest_walk.steps) longest_walk = tile.longest_walk;
}

TileFrame::TileFrame(const Setup& s, const geom::TileGrid& grid) : m_s(s), m_grid(grid) {
  m_tris.reserve(s.triangles.size());
  for (size_t i = 0; i < s.triangles.size(); ++i) {
    const SetupTriangle& t = s.triangles[i];
    if (!t.front) continue;
    FrontTriangle ft;
    static_cast<svgpu::Triangle&>(ft) = svgpu::Triangle::from(t.v[0], t.v[1], t.v[2]);
    ft.t = &t;
    ft.setup_index = uint32_t(i);
    m_tris.push_back(ft);
  }
  m_edges.reserve(s.silhouettes.size());
  for (const SilhouetteEdge& se : s.silhouettes) m_edges.push_back(svgpu::Edge::from(se.a, se.b));
}

void TileFrame::bin() {
  m_tile_tris.assign(m_grid.tile_count(), {});
  m_tile_edges.assign(m_tile_tris.size(), {});
  for (uint32_t i = 0; i < m_tris.size(); ++i) {
    const FrontTriangle& t = m_tris[i];
    m_grid.for_tiles(t.bbox, [&](uint32_t tile, const geom::Rect& r) {
      if (geom::triangle_overlaps_rect(t.tri, r)) m_tile_tris[tile].push_back(i);
    });
  }
  for (uint32_t i = 0; i < m_edges.size(); ++i) {
    const svgpu::Edge& e = m_edges[i];
    m_grid.for_tiles(e.bbox, [&](uint32_t tile, const geom::Rect& r) {
      if (geom::segment_overlaps_rect(e.a.xy(), e.b.xy(), r)) m_tile_edges[tile].push_back(i);
    });
  }
}

void TileFrame::occluders(uint32_t tile, std::vector<uint32_t>& out) const {
  out.clear();
  for (uint32_t i : m_tile_tris[tile])
    if (m_tris[i].t->opaque) out.push_back(i);
  std::stable_sort(out.begin(), out.end(), [&](uint32_t a, uint32_t b) { return m_tris[a].z_min < m_tris[b].z_min; });
}

uint64_t TileFrame::pair_tests(uint32_t tile) const {
  std::vector<uint32_t> z;
  z.reserve(m_tile_edges[tile].size());
  for (uint32_t e : m_tile_edges[tile]) z.push_back(m_edges[e].z_min);
  std::sort(z.begin(), z.end());
  uint64_t n = 0;
  for (uint32_t i : m_tile_tris[tile])
    n += uint64_t(std::partition_point(z.begin(), z.end(), [&](uint32_t z_min) { return !svgpu::edge_behind(z_min, m_tris[i]); }) -
                  z.begin());
  return n;
}

namespace {

struct Registration {
  const char* mode;
  std::unique_ptr<TileResolver> (*make)(const ResolverOptions&);
};

// The registry: one line per mode.
constexpr Registration kRegistry[] = {
    {"analytic", make_analytic_resolver},
    {"hybrid", make_hybrid_resolver},
    {"per_pixel", make_per_pixel_resolver},
};

}  // namespace

const std::vector<std::string>& tile_resolver_modes() {
  static const std::vector<std::string> modes = [] {
    std::vector<std::string> m;
    for (const Registration& r : kRegistry) m.emplace_back(r.mode);
    return m;
  }();
  return modes;
}

std::unique_ptr<TileResolver> make_tile_resolver(std::string_view mode, const ResolverOptions& options) {
  for (const Registration& r : kRegistry)
    if (mode == r.mode) return r.make(options);
  std::string known;
  for (const Registration& r : kRegistry) known += std::string(known.empty() ? "" : ", ") + r.mode;
  throw std::invalid_argument("unknown visibility mode '" + std::string(mode) + "' (known: " + known + ")");
}

}  // namespace tilevis::vis
