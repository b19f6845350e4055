// The analytic mode: SVGPU §3.2-3.3 on one tile. Per triangle (ascending index): candidate
// silhouette edges by tests 1-6 against its tile polygon, clipping with both sides kept and
// every piece re-checked against every candidate, then each piece's occlusion test at its
// interior point against the tile's opaque triangles; visible opaque pieces take their samples.
#include <algorithm>
#include <cmath>

#include "geom/clip.h"
#include "geom/polygon.h"
#include "visibility/tile_resolver.h"

namespace tilevis::vis {
namespace {

using geom::ConvexPolygon;
using geom::Rect;

class AnalyticResolver final : public TileResolver {
  // The scans read compact per-tile copies: FrontTriangle and Edge are wide, and a triangle's
  // id sits behind a pointer (the occlusion scan was bound by those loads).
  // A silhouette edge as the pair tests' scan reads it (tests 6 and 2), 24 bytes.
  struct PairEdge {
    uint32_t z_min, index;  // index into TileFrame::edges()
    geom::Rect bbox;
  };
  // An occluder as the occlusion test's scan reads it, 48 bytes.
  struct Occluder {
    uint32_t z_min, id, index;  // index into TileFrame::triangles()
    double x0, x1, y0, y1;      // the bounding box widened by the test's margin (int -+ 1: exact)
  };

 public:
  explicit AnalyticResolver(const ResolverOptions& o) : m_opt(o) {}

  TileVerdict resolve(const TileFrame& f, uint32_t tile, TileOutput& out, TileCounters& c,
                      std::vector<TileTriangleWork>* per_triangle) override {
    const auto& tris = f.tile_triangles(tile);
    if (tris.empty()) return {};
    const geom::TileGrid& g = f.grid();
    const Rect rect = g.rect(tile);
    setup_occlusion_bins(f);
    // Edges by nearest depth: a triangle whose farthest point is nearer than an edge's
    // nearest (test 6) can skip that edge and every later one.
    const auto& edge_ids = f.tile_edges(tile);
    m_sorted_edges.clear();
    for (uint32_t ei : edge_ids) m_sorted_edges.push_back({f.edges()[ei].z_min, ei, f.edges()[ei].bbox});
    std::stable_sort(m_sorted_edges.begin(), m_sorted_edges.end(),
                     [](const PairEdge& a, const PairEdge& b) { return a.z_min < b.z_min; });
    // Occluders: nearest first (the first hit ends the search).
    f.occluders(tile, m_occluders);
    bin_occluders(f, rect);
    const uint64_t step = edge_ids.size() + tris.size();
    m_stamp.assign(size_t(g.tile_w) * g.tile_h, 0);
    for (uint32_t i : tris) {
      const TileCounters before = c;
      m_shape = {};
      const uint64_t shaded = process_triangle(f, f.triangles()[i], tile, rect, out, c);
      out.shader_invocations += shaded;
      if (per_triangle) per_triangle->push_back({f.triangles()[i].setup_index, c - before, shaded, m_shape});
      if (m_opt.work_done) m_opt.work_done(step);
    }
    return {};
  }

 private:
  // Returns the triangle's shader invocations in the tile: pixels where a visible piece covers
  // a sample (pieces of one triangle may share a pixel: counted once, by a stamp per pixel).
  uint64_t process_triangle(const TileFrame& f, const FrontTriangle& tt, uint32_t tile, const Rect& rect,
                            TileOutput& out, TileCounters& c) {
    ConvexPolygon poly = geom::clip_to_rect(ConvexPolygon::from_triangle(tt.tri), rect);
    if (poly.empty()) return 0;
    ++m_serial;
    uint64_t shaded = 0;
    // Candidate edges (tests 1–6 against the triangle's tile polygon), in ascending id.
    m_candidates.clear();
    // Test 6 on edges by nearest depth: the first edge behind the triangle ends the pairs (so
    // is every later one), found by a binary search; the pairs before it are tested.
    const auto pairs_end = std::upper_bound(m_sorted_edges.begin(), m_sorted_edges.end(), tt,
                                            [](const FrontTriangle& t, const PairEdge& pe) { return svgpu::edge_behind(pe.z_min, t); });
    if (pairs_end != m_sorted_edges.end()) m_shape.test6_stop = 1;
    c.pair_tests += pairs_end - m_sorted_edges.begin();
    const geom::Rect tb = tt.bbox;
    for (auto pe = m_sorted_edges.begin(); pe != pairs_end; ++pe) {
      if (svgpu::boxes_apart(pe->bbox, tb)) continue;  // test 2 (boxes)
      const svgpu::Edge& e = f.edges()[pe->index];
      if (svgpu::shares_edge(e, tt.tri)) continue;  // test 4
      if (svgpu::survives(poly, tt, e)) m_candidates.push_back(pe->index);
    }
    std::sort(m_candidates.begin(), m_candidates.end());
    c.candidate_pairs += int64_t(m_candidates.size());

    // Clipping (SVGPU §3.2.2): every piece re-checked against every candidate edge.
    m_pieces.clear();
    m_pieces.push_back(std::move(poly));
    m_walk.start();
    for (size_t ci = 0; ci < m_candidates.size(); ++ci) {
      const svgpu::Edge& e = f.edges()[m_candidates[ci]];
      const size_t n = m_pieces.size();
      for (size_t k = 0; k < n; ++k) {
        ++m_shape.piece_checks;
        if (!svgpu::survives(m_pieces[k], tt, e)) continue;
        const uint64_t parent_edges = m_pieces[k].size();
        geom::SplitResult sr = svgpu::split(m_pieces[k], e);
        ++c.clip_polygons;
        m_shape.split_edges += parent_edges;
        if (!sr.inside.empty() && !sr.outside.empty()) m_shape.crossing_edges += parent_edges;
        m_pieces[k] = std::move(sr.inside);
        m_walk.split(k, ci, !sr.outside.empty());
        if (!sr.outside.empty()) m_pieces.push_back(std::move(sr.outside));
      }
    }
    const uint64_t walk = m_walk.longest(m_candidates.size());
    if (walk > out.longest_walk.steps)
      out.longest_walk = {walk,
                          m_walk.work(m_candidates.size()),
                          m_candidates.size(),
                          m_pieces.size(),
                          m_walk.longest_splits(m_candidates.size()),
                          m_walk.splits(),
                          tile,
                          tt.setup_index};
    // Canonical order of pieces: a split puts the inside part in place of its parent and
    // appends the outside part (the order the CUDA reference reproduces).
    c.pieces += int64_t(m_pieces.size());
    out.max_tile_pieces = std::max<uint64_t>(out.max_tile_pieces, m_pieces.size());

    const Setup& s = f.setup();
    const geom::TileGrid& g = f.grid();
    const int32_t sb = int32_t(s.subpixel_bits);
    const uint32_t n_samples = uint32_t(s.samples.size());
    const int64_t tx = g.tile_x(tile), ty = g.tile_y(tile);
    for (const ConvexPolygon& piece : m_pieces) {
      if (piece.empty()) continue;
      const int64_t tests_before = c.occlusion_tests;
      const bool visible = !occluded(f, piece, tt, c);
      m_shape.pieces_tested += c.occlusion_tests != tests_before;
      // A visible piece is shaded; only an opaque one owns its samples (ids: the nearest opaque
      // surface, the truth's definition; non-opaque content is blended over it).
      const bool owns = visible && tt.t->opaque;
      // Samples of the piece: a pixel's samples lie in [px·2^sb, (px+1)·2^sb).
      const Rect b = geom::bounding_box(piece);
      const int64_t px0 = std::max<int64_t>(tx * g.tile_w, (int64_t(b.x0) >> sb));
      const int64_t px1 = std::min<int64_t>((tx + 1) * g.tile_w - 1, int64_t(b.x1) >> sb);
      const int64_t py0 = std::max<int64_t>(ty * g.tile_h, (int64_t(b.y0) >> sb));
      const int64_t py1 = std::min<int64_t>((ty + 1) * g.tile_h - 1, int64_t(b.y1) >> sb);
      int64_t covered = 0;
      const int64_t px_end = std::min<int64_t>(px1, int64_t(s.width) - 1);
      for (int64_t py = py0; py <= py1 && py < s.height; ++py)
        for (uint32_t k = 0; k < n_samples; ++k) {
          // The row's covered samples of sample position k, one span (geom::covered_span: the
          // same samples as geom::covers, without a test each).
          const geom::PixelSpan span =
              geom::covered_span(piece, s.samples[k].x, int32_t((py << sb) + s.samples[k].y), sb, px0, px_end);
          if (span.lo > span.hi) continue;
          covered += span.hi - span.lo + 1;
          if (!visible) continue;  // a hidden piece's samples are counted, nothing else
          for (int64_t px = span.lo; px <= span.hi; ++px) {
            if (owns) out.ids[(size_t(py) * s.width + size_t(px)) * n_samples + k] = int32_t(tt.t->id);
            uint64_t& stamp = m_stamp[size_t(py - ty * g.tile_h) * g.tile_w + size_t(px - tx * g.tile_w)];
            shaded += stamp != m_serial || tt.t->sample_rate;  // sample rate: every sample
            stamp = m_serial;
          }
        }
      c.fragments_generated += covered;
      if (!visible) continue;
      ++c.visible_pieces;
      c.samples_covered += covered;
      out.visible_triangles += piece.size() - 2;
      out.areas.emplace_back(tt.t->id, geom::doubled_area(piece) / (2.0 * double(1 << sb) * double(1 << sb)));
      if (m_opt.keep_pieces) keep(s, piece, tt, out);
    }
    return shaded;
  }

  // SVGPU §3.3: the piece is hidden if an original opaque triangle nearer at its interior
  // point contains that point. Equal depth: the earlier-submitted triangle stays in front,
  // as under a less-than depth test.
  bool occluded(const TileFrame& f, const ConvexPolygon& piece, const FrontTriangle& tt, TileCounters& c) const {
    const geom::RationalPoint q = geom::interior_point(piece);
    const double qx = q.fx / q.fw, qy = q.fy / q.fw;
    const uint32_t id = tt.t->id;
    for (const Occluder& o : occluders_at(qx, qy)) {
      if (o.z_min > tt.z_max) break;  // behind everywhere: so are all later occluders
      if (o.id == id) continue;
      // The bounding box rejects with a margin far above the error of qx, qy.
      if (qx < o.x0 || qx > o.x1 || qy < o.y0 || qy > o.y1) continue;
      ++c.occlusion_tests;
      if (svgpu::occludes(f.triangles()[o.index], o.id, tt, id, q)) return true;
    }
    return false;
  }

  // SVGPU §4.1's finer occlusion bins. Bin (bx, by) of the tile covers [x_b, x_{b+1}) x
  // [y_b, y_{b+1}) in sub-pixel units, the first and last bins of a row or column open
  // towards the outside. An occluder joins every bin its bounding-box test (qx within
  // [x0 - 1, x1 + 1], same for y) can pass in, in tile order, so for any point q the bin of q
  // lists exactly the tile's occluders that can pass the test at q, in the same order.
  // The bin grid is the same for every tile of a grid.
  void setup_occlusion_bins(const TileFrame& f) {
    const geom::TileGrid& g = f.grid();
    if (m_bins_for.tile_w == g.tile_w && m_bins_for.tile_h == g.tile_h &&
        m_bins_for.subpixel_bits == g.subpixel_bits && !m_bin_occ.empty())
      return;
    m_bins_for = g;
    const uint32_t bw = m_opt.occlusion_bin_w ? std::min(m_opt.occlusion_bin_w, g.tile_w) : g.tile_w;
    const uint32_t bh = m_opt.occlusion_bin_h ? std::min(m_opt.occlusion_bin_h, g.tile_h) : g.tile_h;
    m_bins_x = (g.tile_w + bw - 1) / bw;
    m_bins_y = (g.tile_h + bh - 1) / bh;
    m_bin_step_x = int64_t(bw) << g.subpixel_bits;
    m_bin_step_y = int64_t(bh) << g.subpixel_bits;
    m_bin_occ.assign(size_t(m_bins_x) * m_bins_y, {});
  }

  bool binned() const { return m_bin_occ.size() > 1; }

  // The bin whose span holds v: floor((v - origin) / step), clamped to [0, n - 1]; monotone
  // in v, and exact for an integer v (a quotient short of an integer by at least 1 / step,
  // step < 2^17, does not round up to it).
  static uint32_t bin_index(double v, int64_t origin, int64_t step, uint32_t n) {
    const double k = std::floor((v - double(origin)) / double(step));
    return uint32_t(std::clamp<double>(k, 0.0, double(n - 1)));
  }

  // The tile's occluders as compact records, nearest first, and in each finer bin.
  void bin_occluders(const TileFrame& f, const Rect& rect) {
    m_occ.clear();
    for (uint32_t oi : m_occluders) {
      const FrontTriangle& u = f.triangles()[oi];
      m_occ.push_back({u.z_min, u.t->id, oi, u.bbox.x0 - 1.0, u.bbox.x1 + 1.0, u.bbox.y0 - 1.0, u.bbox.y1 + 1.0});
    }
    if (!binned()) return;
    m_bin_x0 = rect.x0;
    m_bin_y0 = rect.y0;
    for (auto& b : m_bin_occ) b.clear();
    for (const Occluder& o : m_occ) {  // the widened box: integers, so the double bins are exact
      const uint32_t bx0 = bin_index(o.x0, m_bin_x0, m_bin_step_x, m_bins_x);
      const uint32_t bx1 = bin_index(o.x1, m_bin_x0, m_bin_step_x, m_bins_x);
      const uint32_t by0 = bin_index(o.y0, m_bin_y0, m_bin_step_y, m_bins_y);
      const uint32_t by1 = bin_index(o.y1, m_bin_y0, m_bin_step_y, m_bins_y);
      for (uint32_t by = by0; by <= by1; ++by)
        for (uint32_t bx = bx0; bx <= bx1; ++bx) m_bin_occ[size_t(by) * m_bins_x + bx].push_back(o);
    }
  }

  // The occluders a piece with interior point (qx, qy) scans: its bin's, or the tile's.
  const std::vector<Occluder>& occluders_at(double qx, double qy) const {
    if (!binned()) return m_occ;
    return m_bin_occ[size_t(bin_index(qy, m_bin_y0, m_bin_step_y, m_bins_y)) * m_bins_x +
                     bin_index(qx, m_bin_x0, m_bin_step_x, m_bins_x)];
  }

  void keep(const Setup& s, const ConvexPolygon& piece, const FrontTriangle& tt, TileOutput& out) const {
    PlanarPiece pp;
    pp.id = tt.t->id;
    pp.draw = tt.t->draw;
    const double scale = 1.0 / double(1u << s.subpixel_bits);
    // Shade by the plane's depth gradient: a cheap, stable stand-in for lighting.
    const double g = std::hypot(double(tt.plane.alpha), double(tt.plane.beta)) / double(tt.plane.area);
    pp.shade = float(1.0 / (1.0 + g * 1e-3));
    for (const auto& e : piece.edges()) {
      pp.xy.push_back(double(e.start.x) / double(e.start.w) * scale);
      pp.xy.push_back(double(e.start.y) / double(e.start.w) * scale);
    }
    out.pieces.push_back(std::move(pp));
  }

  ResolverOptions m_opt;
  std::vector<PairEdge> m_sorted_edges;  // the tile's edges, nearest z_min first
  std::vector<uint32_t> m_occluders, m_candidates;
  std::vector<Occluder> m_occ;
  std::vector<ConvexPolygon> m_pieces;
  svgpu::WalkChain m_walk;  // the clip's chain of dependent steps as cuda_ref's tree walks it
  EvuShape m_shape;  // of the triangle in process
  std::vector<uint64_t> m_stamp;  // per pixel of the tile: the last triangle serial that shaded it
  uint64_t m_serial = 0;
  geom::TileGrid m_bins_for{};
  std::vector<std::vector<Occluder>> m_bin_occ;  // finer occlusion bins of the current tile (one: off)
  uint32_t m_bins_x = 1, m_bins_y = 1;
  int64_t m_bin_x0 = 0, m_bin_y0 = 0, m_bin_step_x = 1, m_bin_step_y = 1;
};

}  // namespace

std::unique_ptr<TileResolver> make_analytic_resolver(const ResolverOptions& o) {
  return std::make_unique<AnalyticResolver>(o);
}

}  // namespace tilevis::vis
