#include "visibility/golden.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include "geom/clip.h"
#include "geom/depth.h"
#include "geom/overlap.h"
#include "geom/polygon.h"
#include "geom/predicates.h"
#include "geom/tile_grid.h"
#include "visibility/svgpu.h"

namespace tilevis::vis {
namespace {

using geom::ConvexPolygon;
using geom::Point;
using geom::Rect;

// A front-facing setup triangle with what the tile stage needs of it.
struct TileTriangle : svgpu::Triangle {
  const SetupTriangle* t = nullptr;
};

using Edge = svgpu::Edge;

}  // namespace

// The tile stage of the golden pipeline; GoldenTiler exposes its binning and per-tile work.
class GoldenTiler::Impl {
 public:
  Impl(const Setup& s, const GoldenConfig& cfg, GoldenResult& r) : m_s(s), m_cfg(cfg), m_r(r) {
    prepare();
    const size_t n_samples = size_t(m_s.width) * m_s.height * m_s.samples.size();
    m_r.ids.assign(n_samples, -1);
    m_r.visible_area.assign(m_s.triangle_draw.size(), 0.0);
    std::vector<std::string> columns = golden_tile_columns();
    if (m_cfg.hybrid) columns.insert(columns.end(), hybrid_tile_columns().begin(), hybrid_tile_columns().end());
    m_r.tiles.resize(m_cfg.tile_w, m_cfg.tile_h, m_s.width, m_s.height, columns);
    setup_occlusion_bins();
  }

  void prepare() {
    for (const SetupTriangle& t : m_s.triangles) {
      if (!t.front) continue;
      TileTriangle tt;
      static_cast<svgpu::Triangle&>(tt) = svgpu::Triangle::from(t.v[0], t.v[1], t.v[2]);
      tt.t = &t;
      m_tris.push_back(tt);
    }
    for (const SilhouetteEdge& se : m_s.silhouettes) m_edges.push_back(svgpu::Edge::from(se.a, se.b));
    m_grid = geom::TileGrid::make(m_s.width, m_s.height, m_cfg.tile_w, m_cfg.tile_h, m_s.subpixel_bits);
  }

  // GoldenConfig::progress: the frame's estimated work, set after binning.
  void start_progress() {
    if (!m_cfg.progress) return;
    m_work_total = m_work_done = 0;
    for (size_t tile = 0; tile < m_tile_tris.size(); ++tile) {
      const uint64_t t = m_tile_tris[tile].size();
      m_work_total += 1 + t * (m_tile_edges[tile].size() + t);
    }
    m_cfg.progress(0, m_work_total);
  }

  void bin() {
    m_tile_tris.assign(m_grid.tile_count(), {});
    m_tile_edges.assign(m_tile_tris.size(), {});
    for (uint32_t i = 0; i < m_tris.size(); ++i) {
      const TileTriangle& tt = m_tris[i];
      m_grid.for_tiles(tt.bbox, [&](uint32_t tile, const Rect& r) {
        if (geom::triangle_overlaps_rect(tt.tri, r)) m_tile_tris[tile].push_back(i);
      });
    }
    for (uint32_t i = 0; i < m_edges.size(); ++i) {
      const Edge& e = m_edges[i];
      m_grid.for_tiles(e.bbox, [&](uint32_t tile, const Rect& r) {
        if (geom::segment_overlaps_rect(e.a.xy(), e.b.xy(), r)) m_tile_edges[tile].push_back(i);
      });
    }
    start_progress();
  }

  int process_tile(uint32_t tile, std::vector<TileTriangleWork>* per_triangle) {
    const auto& tris = m_tile_tris[tile];
    const auto& edge_ids = m_tile_edges[tile];
    auto& row = m_r.tiles.rows[tile];
    TileCounters c;
    c.triangles = int64_t(tris.size());
    c.edges = int64_t(edge_ids.size());
    m_r.max_tile_triangles = std::max<uint64_t>(m_r.max_tile_triangles, tris.size());
    m_r.max_tile_edges = std::max<uint64_t>(m_r.max_tile_edges, edge_ids.size());
    const int cause = tris.empty() ? 0 : resolve(tile, tris, edge_ids, c, row, per_triangle);
    c.add_to(row.data());
    return cause;
  }

  int resolve(uint32_t tile, const std::vector<uint32_t>& tris, const std::vector<uint32_t>& edge_ids, TileCounters& c,
              std::vector<int64_t>& row, std::vector<TileTriangleWork>* per_triangle) {
    const uint32_t tx = m_grid.tile_x(tile), ty = m_grid.tile_y(tile);
    const Rect rect = m_grid.rect(tx, ty);

    // Edges by nearest depth: a triangle whose farthest point is nearer than an edge's
    // nearest (test 6) can skip that edge and every later one.
    m_sorted_edges.assign(edge_ids.begin(), edge_ids.end());
    std::stable_sort(m_sorted_edges.begin(), m_sorted_edges.end(),
                     [&](uint32_t a, uint32_t b) { return m_edges[a].z_min < m_edges[b].z_min; });
    // Occluders: opaque triangles of the tile, nearest first (the first hit ends the search).
    m_occluders.clear();
    for (uint32_t i : tris)
      if (m_tris[i].t->opaque) m_occluders.push_back(i);
    std::stable_sort(m_occluders.begin(), m_occluders.end(),
                     [&](uint32_t a, uint32_t b) { return m_tris[a].z_min < m_tris[b].z_min; });
    bin_occluders(rect);

    if (m_cfg.hybrid)
      if (const int cause = fallback_cause(tris, edge_ids.size(), rect)) {
        resolve_per_pixel(tris, tx, ty, c, per_triangle);
        row[TileCounters::kCount] = 1;  // hybrid_tile_columns()
        row[TileCounters::kCount + 1] = cause;
        ++m_r.fallback_tiles;
        (cause == 1 ? m_r.fallback_interpenetration : cause == 2 ? m_r.fallback_non_opaque : m_r.fallback_budget) += 1;
        return cause;
      }

    const uint64_t step = edge_ids.size() + tris.size();
    for (uint32_t i : tris) {
      const TileCounters before = c;
      process_triangle(m_tris[i], rect, tx, ty, c);
      if (per_triangle) per_triangle->push_back({setup_index(i), c - before});
      if (m_cfg.progress && !per_triangle) m_cfg.progress(m_work_done += step, m_work_total);
    }
    if (m_cfg.progress && !per_triangle) m_cfg.progress(m_work_done += 1, m_work_total);
    return 0;
  }

  uint32_t setup_index(uint32_t front) const { return uint32_t(m_tris[front].t - m_s.triangles.data()); }

  void process_triangle(const TileTriangle& tt, const Rect& rect, uint32_t tx, uint32_t ty, TileCounters& c) {
    ConvexPolygon poly = geom::clip_to_rect(ConvexPolygon::from_triangle(tt.tri), rect);
    if (poly.empty()) return;
    // Candidate edges (tests 1–6 against the triangle's tile polygon), in ascending id.
    m_candidates.clear();
    for (uint32_t ei : m_sorted_edges) {
      const Edge& e = m_edges[ei];
      if (svgpu::edge_behind(e, tt)) break;  // test 6: and so is every later edge
      ++c.pair_tests;
      if (svgpu::boxes_apart(e, tt) || svgpu::shares_edge(e, tt.tri)) continue;  // tests 2 (boxes) and 4
      if (svgpu::survives(poly, tt, e)) m_candidates.push_back(ei);
    }
    std::sort(m_candidates.begin(), m_candidates.end());
    c.candidate_pairs += int64_t(m_candidates.size());

    // Clipping (SVGPU §3.2.2): every piece re-checked against every candidate edge.
    m_pieces.clear();
    m_pieces.push_back(std::move(poly));
    for (uint32_t ei : m_candidates) {
      const Edge& e = m_edges[ei];
      const size_t n = m_pieces.size();
      for (size_t k = 0; k < n; ++k) {
        if (!svgpu::survives(m_pieces[k], tt, e)) continue;
        geom::SplitResult sr = svgpu::split(m_pieces[k], e);
        ++c.clip_polygons;
        m_pieces[k] = std::move(sr.inside);
        if (!sr.outside.empty()) m_pieces.push_back(std::move(sr.outside));
      }
    }
    // Canonical order of pieces: a split puts the inside part in place of its parent and
    // appends the outside part (the order the CUDA reference reproduces).
    c.pieces += int64_t(m_pieces.size());
    m_r.max_tile_pieces = std::max<uint64_t>(m_r.max_tile_pieces, m_pieces.size());

    const int32_t sb = int32_t(m_s.subpixel_bits);
    const uint32_t n_samples = uint32_t(m_s.samples.size());
    for (const ConvexPolygon& piece : m_pieces) {
      if (piece.empty()) continue;
      const bool visible = !occluded(piece, tt, c);
      // Samples of the piece: a pixel's samples lie in [px·2^sb, (px+1)·2^sb).
      const Rect b = geom::bounding_box(piece);
      const int64_t px0 = std::max<int64_t>(int64_t(tx) * m_cfg.tile_w, (int64_t(b.x0) >> sb));
      const int64_t px1 = std::min<int64_t>(int64_t(tx + 1) * m_cfg.tile_w - 1, int64_t(b.x1) >> sb);
      const int64_t py0 = std::max<int64_t>(int64_t(ty) * m_cfg.tile_h, (int64_t(b.y0) >> sb));
      const int64_t py1 = std::min<int64_t>(int64_t(ty + 1) * m_cfg.tile_h - 1, int64_t(b.y1) >> sb);
      int64_t covered = 0;
      for (int64_t py = py0; py <= py1 && py < m_s.height; ++py)
        for (int64_t px = px0; px <= px1 && px < m_s.width; ++px)
          for (uint32_t k = 0; k < n_samples; ++k) {
            const Point p{int32_t((px << sb) + m_s.samples[k].x), int32_t((py << sb) + m_s.samples[k].y)};
            if (!geom::covers(piece, p)) continue;
            ++covered;
            if (visible) m_r.ids[(size_t(py) * m_s.width + size_t(px)) * n_samples + k] = int32_t(tt.t->id);
          }
      c.fragments_generated += covered;
      if (!visible) continue;
      ++c.visible_pieces;
      c.samples_covered += covered;
      m_r.visible_triangles += piece.size() - 2;
      m_r.visible_area[tt.t->id] += geom::doubled_area(piece) / (2.0 * double(1 << sb) * double(1 << sb));
      if (m_cfg.keep_pieces) keep(piece, tt);
    }
  }

  // Hybrid: why the tile must go per pixel (0: it need not). 1: two opaque triangles whose
  // planes cross inside their overlap in the tile; 2: a non-opaque or per-pixel-only triangle;
  // 3: estimated pair tests over the budget.
  int fallback_cause(const std::vector<uint32_t>& tris, size_t n_edges, const Rect& rect) const {
    for (uint32_t i : tris)
      if (!m_tris[i].t->opaque) return 2;
    if (m_cfg.hybrid_pair_budget && uint64_t(tris.size()) * n_edges > m_cfg.hybrid_pair_budget) return 3;
    for (uint32_t i : tris)
      if (crosses_an_occluder(m_tris[i], rect)) return 1;
    return 0;
  }

  // Is there an opaque triangle u of the tile (another trace triangle) whose plane crosses
  // tt's strictly inside their overlap within the tile? Depth is affine over the overlap, a
  // convex polygon, so it crosses exactly when the sign of z_u - z_tt at its vertices is
  // positive at one and negative at another (exact: depth_order at implicit points). There
  // the analytic method, which judges a piece by one interior point, can be wrong; where every
  // overlap keeps one order, silhouette splitting makes it exact (SVGPU §4.3's assumption).
  bool crosses_an_occluder(const TileTriangle& tt, const Rect& rect) const {
    const ConvexPolygon poly = geom::clip_to_rect(ConvexPolygon::from_triangle(tt.tri), rect);
    if (poly.empty()) return false;
    for (uint32_t oi : m_occluders) {
      const TileTriangle& u = m_tris[oi];
      if (u.z_min >= tt.z_max) break;  // u at or behind tt everywhere: so are all later occluders
      if (u.t->id != tt.t->id && svgpu::planes_cross(poly, tt, u)) return true;
    }
    return false;
  }

  // The tile per pixel: every binned triangle in submission order, an exact less-than depth
  // test, opaque triangles taking the samples they win (the z-buffer truth's rule). Visible
  // areas of these tiles are sample counts times the sample's share of a pixel.
  void resolve_per_pixel(const std::vector<uint32_t>& tris, uint32_t tx, uint32_t ty, TileCounters& c,
                         std::vector<TileTriangleWork>* per_triangle) {
    const size_t first_record = per_triangle ? per_triangle->size() : 0;
    const int32_t sb = int32_t(m_s.subpixel_bits);
    const uint32_t ns = uint32_t(m_s.samples.size());
    const uint32_t x0 = tx * m_cfg.tile_w, y0 = ty * m_cfg.tile_h;
    const uint32_t x1 = std::min(x0 + m_cfg.tile_w, m_s.width), y1 = std::min(y0 + m_cfg.tile_h, m_s.height);
    const uint32_t w = x1 - x0;
    m_owner.assign(size_t(w) * (y1 - y0) * ns, -1);
    int64_t generated = 0;
    for (size_t n = 0; n < tris.size(); ++n) {
      const uint32_t i = tris[n];
      const TileTriangle& t = m_tris[i];
      const int64_t generated_before = generated;
      const int64_t px0 = std::max<int64_t>(x0, t.bbox.x0 >> sb), px1 = std::min<int64_t>(x1 - 1, t.bbox.x1 >> sb);
      const int64_t py0 = std::max<int64_t>(y0, t.bbox.y0 >> sb), py1 = std::min<int64_t>(y1 - 1, t.bbox.y1 >> sb);
      for (int64_t py = py0; py <= py1; ++py)
        for (int64_t px = px0; px <= px1; ++px)
          for (uint32_t k = 0; k < ns; ++k) {
            const Point p{int32_t((px << sb) + m_s.samples[k].x), int32_t((py << sb) + m_s.samples[k].y)};
            if (!t.edges.covers(p)) continue;
            ++generated;
            int32_t& o = m_owner[(size_t(py - y0) * w + size_t(px - x0)) * ns + k];
            if (t.t->opaque && (o < 0 || geom::depth_order(t.plane, m_tris[size_t(o)].plane, p) < 0)) o = int32_t(i);
          }
      if (per_triangle) {
        TileTriangleWork record;
        record.triangle = setup_index(i);
        record.counters.fragments_generated = generated - generated_before;
        per_triangle->push_back(record);
        m_record_of[i] = uint32_t(n);
      }
    }
    int64_t covered = 0;
    const double sample_area = 1.0 / double(ns);
    for (uint32_t py = y0; py < y1; ++py)
      for (uint32_t px = x0; px < x1; ++px)
        for (uint32_t k = 0; k < ns; ++k) {
          const int32_t o = m_owner[(size_t(py - y0) * w + (px - x0)) * ns + k];
          if (o < 0) continue;
          const uint32_t id = m_tris[size_t(o)].t->id;
          m_r.ids[(size_t(py) * m_s.width + px) * ns + k] = int32_t(id);
          m_r.visible_area[id] += sample_area;
          ++covered;
          if (per_triangle) ++(*per_triangle)[first_record + m_record_of[uint32_t(o)]].counters.samples_covered;
        }
    c.samples_covered += covered;
    c.fragments_generated += generated;
    m_r.fallback_samples += uint64_t(covered);
  }

  // SVGPU §3.3: the piece is hidden if an original opaque triangle nearer at its interior
  // point contains that point. Equal depth: the earlier-submitted triangle stays in front,
  // as under a less-than depth test.
  bool occluded(const ConvexPolygon& piece, const TileTriangle& tt, TileCounters& c) {
    const geom::RationalPoint q = geom::interior_point(piece);
    const double qx = q.fx / q.fw, qy = q.fy / q.fw;
    for (uint32_t oi : occluders_at(qx, qy)) {
      const TileTriangle& u = m_tris[oi];
      if (u.z_min > tt.z_max) break;  // u is behind everywhere: so are all later occluders
      if (u.t->id == tt.t->id) continue;
      // The bounding box rejects with a margin far above the error of qx, qy.
      if (qx < u.bbox.x0 - 1.0 || qx > u.bbox.x1 + 1.0 || qy < u.bbox.y0 - 1.0 || qy > u.bbox.y1 + 1.0) continue;
      ++c.occlusion_tests;
      if (svgpu::occludes(u, u.t->id, tt, tt.t->id, q)) return true;
    }
    return false;
  }

  // SVGPU §4.1's finer occlusion bins. Bin (bx, by) of the tile covers [x_b, x_{b+1}) x
  // [y_b, y_{b+1}) in sub-pixel units, the first and last bins of a row or column open
  // towards the outside. An occluder joins every bin its bounding-box test (qx within
  // [x0 - 1, x1 + 1], same for y) can pass in, in tile order, so for any point q the bin of q
  // lists exactly the tile's occluders that can pass the test at q, in the same order.
  // The bin grid is the same for every tile: set once, here.
  void setup_occlusion_bins() {
    const uint32_t bw = m_cfg.occlusion_bin_w ? std::min(m_cfg.occlusion_bin_w, m_cfg.tile_w) : m_cfg.tile_w;
    const uint32_t bh = m_cfg.occlusion_bin_h ? std::min(m_cfg.occlusion_bin_h, m_cfg.tile_h) : m_cfg.tile_h;
    m_bins_x = (m_cfg.tile_w + bw - 1) / bw;
    m_bins_y = (m_cfg.tile_h + bh - 1) / bh;
    m_bin_step_x = int64_t(bw) << m_s.subpixel_bits;
    m_bin_step_y = int64_t(bh) << m_s.subpixel_bits;
    m_bin_occ.resize(size_t(m_bins_x) * m_bins_y);
  }

  bool binned() const { return m_bin_occ.size() > 1; }

  // The bin whose span holds v: floor((v - origin) / step), clamped to [0, n - 1]. Integer
  // and double arguments give the same bin for the same value, and both are monotone in v.
  static uint32_t bin_index(int64_t v, int64_t origin, int64_t step, uint32_t n) {
    const int64_t k = v < origin ? 0 : (v - origin) / step;
    return uint32_t(std::min<int64_t>(k, int64_t(n) - 1));
  }
  static uint32_t bin_index(double v, int64_t origin, int64_t step, uint32_t n) {
    const double k = std::floor((v - double(origin)) / double(step));
    return uint32_t(std::clamp<double>(k, 0.0, double(n - 1)));
  }

  void bin_occluders(const Rect& rect) {
    if (!binned()) return;
    m_bin_x0 = rect.x0;
    m_bin_y0 = rect.y0;
    for (auto& b : m_bin_occ) b.clear();
    for (uint32_t oi : m_occluders) {
      const Rect& b = m_tris[oi].bbox;
      const uint32_t bx0 = bin_index(int64_t(b.x0) - 1, m_bin_x0, m_bin_step_x, m_bins_x);
      const uint32_t bx1 = bin_index(int64_t(b.x1) + 1, m_bin_x0, m_bin_step_x, m_bins_x);
      const uint32_t by0 = bin_index(int64_t(b.y0) - 1, m_bin_y0, m_bin_step_y, m_bins_y);
      const uint32_t by1 = bin_index(int64_t(b.y1) + 1, m_bin_y0, m_bin_step_y, m_bins_y);
      for (uint32_t by = by0; by <= by1; ++by)
        for (uint32_t bx = bx0; bx <= bx1; ++bx) m_bin_occ[size_t(by) * m_bins_x + bx].push_back(oi);
    }
  }

  // The occluders a piece with interior point (qx, qy) scans: its bin's, or the tile's.
  const std::vector<uint32_t>& occluders_at(double qx, double qy) const {
    if (!binned()) return m_occluders;
    return m_bin_occ[size_t(bin_index(qy, m_bin_y0, m_bin_step_y, m_bins_y)) * m_bins_x +
                     bin_index(qx, m_bin_x0, m_bin_step_x, m_bins_x)];
  }

  void keep(const ConvexPolygon& piece, const TileTriangle& tt) {
    PlanarPiece pp;
    pp.id = tt.t->id;
    pp.draw = tt.t->draw;
    const double scale = 1.0 / double(1u << m_s.subpixel_bits);
    // Shade by the plane's depth gradient: a cheap, stable stand-in for lighting.
    const double g = std::hypot(double(tt.plane.alpha), double(tt.plane.beta)) / double(tt.plane.area);
    pp.shade = float(1.0 / (1.0 + g * 1e-3));
    for (const auto& e : piece.edges()) {
      pp.xy.push_back(double(e.start.x) / double(e.start.w) * scale);
      pp.xy.push_back(double(e.start.y) / double(e.start.w) * scale);
    }
    m_r.pieces.push_back(std::move(pp));
  }

  const Setup& m_s;
  const GoldenConfig& m_cfg;
  GoldenResult& m_r;
  std::vector<TileTriangle> m_tris;
  std::vector<Edge> m_edges;
  geom::TileGrid m_grid;
  std::vector<std::vector<uint32_t>> m_tile_tris, m_tile_edges;
  std::vector<uint32_t> m_sorted_edges, m_occluders, m_candidates;
  std::vector<std::vector<uint32_t>> m_bin_occ;  // finer occlusion bins of the current tile (one: off)
  uint32_t m_bins_x = 1, m_bins_y = 1;
  int64_t m_bin_x0 = 0, m_bin_y0 = 0, m_bin_step_x = 1, m_bin_step_y = 1;
  std::vector<ConvexPolygon> m_pieces;
  std::vector<int32_t> m_owner;  // hybrid: the per-pixel tile's sample owners (index into m_tris)
  std::unordered_map<uint32_t, uint32_t> m_record_of;  // hybrid: per-triangle record of a tile triangle
  uint64_t m_work_done = 0, m_work_total = 0;  // GoldenConfig::progress
};

GoldenTiler::GoldenTiler(const Setup& setup, const GoldenConfig& config, GoldenResult& result)
    : m_impl(std::make_unique<Impl>(setup, config, result)) {}
GoldenTiler::~GoldenTiler() = default;
void GoldenTiler::bin() { m_impl->bin(); }
uint32_t GoldenTiler::tiles_x() const { return m_impl->m_grid.tiles_x(); }
uint32_t GoldenTiler::tiles_y() const { return m_impl->m_grid.tiles_y(); }
std::vector<uint32_t> GoldenTiler::tile_triangles(uint32_t tile) const {
  std::vector<uint32_t> out;
  out.reserve(m_impl->m_tile_tris[tile].size());
  for (uint32_t i : m_impl->m_tile_tris[tile]) out.push_back(m_impl->setup_index(i));
  return out;
}
size_t GoldenTiler::tile_triangle_count(uint32_t tile) const { return m_impl->m_tile_tris[tile].size(); }
const std::vector<uint32_t>& GoldenTiler::tile_edges(uint32_t tile) const { return m_impl->m_tile_edges[tile]; }
int GoldenTiler::process_tile(uint32_t tile, std::vector<TileTriangleWork>* per_triangle) {
  return m_impl->process_tile(tile, per_triangle);
}

GoldenResult golden_visibility(const Setup& s, const GoldenConfig& cfg) {
  GoldenResult r;
  r.width = s.width;
  r.height = s.height;
  r.samples = uint32_t(s.samples.size());
  GoldenTiler tiler(s, cfg, r);
  tiler.bin();
  for (uint32_t tile = 0; tile < tiler.tile_count(); ++tile) tiler.process_tile(tile);
  sum_golden_totals(r);
  return r;
}

void sum_golden_totals(GoldenResult& r) {
  TileCounters sum;
  for (const auto& row : r.tiles.rows) {
    sum = sum + TileCounters::from(row.data());
  }
  r.pair_tests = uint64_t(sum.pair_tests);
  r.candidate_pairs = uint64_t(sum.candidate_pairs);
  r.clip_polygons = uint64_t(sum.clip_polygons);
  r.pieces_total = uint64_t(sum.pieces);
  r.visible_pieces = uint64_t(sum.visible_pieces);
  r.occlusion_tests = uint64_t(sum.occlusion_tests);
  r.samples_covered = uint64_t(sum.samples_covered);
  r.fragments_generated = uint64_t(sum.fragments_generated);
}

}  // namespace tilevis::vis
