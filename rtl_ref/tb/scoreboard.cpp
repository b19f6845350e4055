#include "scoreboard.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace tilevis::rtl {

TbOptions parse_tb_options(int argc, char** argv, unsigned extra) {
  TbOptions o;
  auto usage = [&] {
    std::fprintf(stderr, "usage: %s [--random N --seed S] [--jobs FILE [--job-stride K]%s]...%s\n", argv[0],
                 extra & kTbMaxJobs ? " [--max-jobs M]" : "", extra & kTbCsv ? " [--csv FILE]" : "");
    std::exit(2);
  };
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto val = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--random")
      o.random = std::stoull(val());
    else if (a == "--seed")
      o.seed = std::stoull(val());
    else if (a == "--jobs")
      o.jobs.push_back(val());
    else if (a == "--job-stride")
      o.job_stride = std::max<uint64_t>(1, std::stoull(val()));
    else if (a == "--csv" && (extra & kTbCsv))
      o.csv = val();
    else if (a == "--max-jobs" && (extra & kTbMaxJobs))
      o.max_jobs = std::stoull(val());
    else
      usage();
  }
  return o;
}

using geom::Point;
using geom::Vertex;

void PairCoverage::add(const PairVector& v, int code) {
  ++vectors;
  ++codes[code];
  bool on = false, implicit = false;
  for (size_t i = 0; i < v.poly.size(); ++i) {
    on |= geom::side(v.e.line, v.poly.vertex(i)) == 0;
    implicit |= v.poly.vertex(i).w != 1;
  }
  vertex_on_line += on;
  implicit_vertices += implicit;
  max_vertices = std::max<uint64_t>(max_vertices, v.poly.size());
  bool col = false, sv = false;
  for (int i = 0; i < 3; ++i) {
    const Point p = v.t.tri.v[i].xy(), q = v.t.tri.v[(i + 1) % 3].xy();
    col |= geom::orient2d(p, q, v.e.a.xy()) == 0 && geom::orient2d(p, q, v.e.b.xy()) == 0;
    sv |= v.t.tri.v[i] == v.e.a || v.t.tri.v[i] == v.e.b;
  }
  collinear += col && !vis::svgpu::shares_edge(v.e, v.t.tri) && !(v.e.a == v.e.b);
  shared_vertex += sv;
  degenerate_edge += v.e.a.xy() == v.e.b.xy();
  depth_tie += v.e.z_min == v.t.z_max;
}

std::string PairCoverage::report() const {
  std::ostringstream o;
  o << vectors << " vectors; decisions:";
  for (int c = 0; c < 6; ++c) o << ' ' << pair_code_name(c) << '=' << codes[c];
  o << "; corner cases: vertex on line " << vertex_on_line << ", collinear edge " << collinear << ", shared vertex "
    << shared_vertex << ", degenerate edge " << degenerate_edge << ", depth tie " << depth_tie
    << ", implicit polygon vertices " << implicit_vertices << ", most polygon vertices " << max_vertices;
  return o.str();
}

int32_t PairSource::coord(int scale) {
  switch (scale) {
    case 0:
      return int32_t(m_rng() % 9) * 16;  // lattice: ties everywhere
    case 1:
      return int32_t(m_rng() % 4096);  // a few tiles
    default:
      return int32_t(int64_t(m_rng() % ((1u << 24) - 1)) - ((1 << 23) - 1));  // the guard band
  }
}

uint32_t PairSource::depth() {
  switch (m_rng() % 3) {
    case 0:
      return uint32_t(m_rng() % 4) * 1000;  // equalities
    case 1:
      return uint32_t(m_rng() % (1u << 24));
    default:
      return uint32_t(m_rng());  // 32-bit depth
  }
}

PairVector PairSource::next() {
  for (;;) {
    const int scale = int(m_rng() % 3);
    Vertex v[3];
    for (auto& p : v) p = {coord(scale), coord(scale), depth()};
    if (geom::orient2d(v[0].xy(), v[1].xy(), v[2].xy()) == 0) continue;  // front triangles have area
    // A tile: around the triangle or cutting it.
    int32_t x0 = std::min({v[0].x, v[1].x, v[2].x}), x1 = std::max({v[0].x, v[1].x, v[2].x});
    int32_t y0 = std::min({v[0].y, v[1].y, v[2].y}), y1 = std::max({v[0].y, v[1].y, v[2].y});
    geom::Rect r{x0, y0, x1, y1};
    if (m_rng() % 4 != 0) {
      auto inner = [&](int32_t a, int32_t b) { return a + int32_t(int64_t(m_rng() % (uint64_t(int64_t(b) - a) + 1))); };
      const int32_t ax = inner(x0, x1), bx = inner(x0, x1), ay = inner(y0, y1), by = inner(y0, y1);
      r = {std::min(ax, bx), std::min(ay, by), std::max(ax, bx), std::max(ay, by)};
      if (r.x0 == r.x1 || r.y0 == r.y1) r = {x0, y0, x1, y1};
    }
    PairVector pv;
    pv.t = vis::svgpu::Triangle::from(v[0], v[1], v[2]);
    pv.poly = geom::triangle_in_rect(pv.t.tri, r);
    if (pv.poly.empty()) continue;
    // A piece of it now and then: split by a random line through two lattice/tile points.
    if (m_rng() % 4 == 0) {
      const Point p{coord(scale), coord(scale)}, q{coord(scale), coord(scale)};
      if (!(p == q)) {
        geom::SplitResult sr = geom::split(pv.poly, geom::Line::through(p, q));
        if (!sr.inside.empty() && sr.inside.size() <= 8) pv.poly = sr.inside;
      }
    }
    Vertex a{coord(scale), coord(scale), depth()}, b{coord(scale), coord(scale), depth()};
    const int i = int(m_rng() % 3);
    switch (m_rng() % 8) {
      case 0:
        a = v[i];
        b = v[(i + 1) % 3];
        if (m_rng() & 1) std::swap(a, b);
        break;   // a triangle edge
      case 1: {  // collinear with a triangle edge, beyond or inside it
        const int64_t dx = int64_t(v[(i + 1) % 3].x) - v[i].x, dy = int64_t(v[(i + 1) % 3].y) - v[i].y;
        const int64_t k0 = int64_t(m_rng() % 5) - 2, k1 = int64_t(m_rng() % 5) - 1;
        const int64_t ax = v[i].x + k0 * dx, ay = v[i].y + k0 * dy, bx = v[i].x + k1 * dx, by = v[i].y + k1 * dy;
        const int64_t lim = (1 << 23) - 1;
        if (std::max({std::abs(ax), std::abs(ay), std::abs(bx), std::abs(by)}) > lim) break;
        a = {int32_t(ax), int32_t(ay), depth()};
        b = {int32_t(bx), int32_t(by), depth()};
        break;
      }
      case 2:
        a = v[i];
        break;  // anchored at a vertex
      case 3:
        a = v[i];
        b.x = a.x;
        b.y = a.y;
        break;  // degenerate
      case 4:
        a = {r.x0, r.y0, depth()};
        b = {r.x1, r.y1, depth()};
        break;  // the tile's diagonal
      case 5:
        a.z = b.z = pv.t.z_max;
        break;  // depth tie with the triangle's farthest point
      default:
        break;
    }
    pv.e = vis::svgpu::Edge::from(a, b);
    return pv;
  }
}

}  // namespace tilevis::rtl

namespace tilevis::rtl {

ReplayedJob replay_job(const vis::EvuJob& j,
                       const std::function<void(const geom::ConvexPolygon&, const vis::svgpu::Edge&)>& on_split) {
  ReplayedJob r;
  for (size_t k = 0; k < j.edges.size(); k += 2) r.edges.push_back(vis::svgpu::Edge::from(j.edges[k], j.edges[k + 1]));
  std::vector<uint32_t> order(r.edges.size());
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t c) { return r.edges[a].z_min < r.edges[c].z_min; });
  for (const auto& jt : j.triangles) {
    ReplayedTriangle rt;
    rt.t = vis::svgpu::Triangle::from(jt.v[0], jt.v[1], jt.v[2]);
    rt.id = jt.id;
    rt.opaque = jt.opaque;
    geom::ConvexPolygon poly = geom::triangle_in_rect(rt.t.tri, j.rect);
    if (!poly.empty()) {
      for (uint32_t ei : order) {
        const auto& e = r.edges[ei];
        if (vis::svgpu::edge_behind(e, rt.t)) break;
        if (vis::svgpu::boxes_apart(e, rt.t) || vis::svgpu::shares_edge(e, rt.t.tri)) continue;
        if (vis::svgpu::survives(poly, rt.t, e)) rt.candidates.push_back(ei);
      }
      std::sort(rt.candidates.begin(), rt.candidates.end());
      rt.pieces.push_back(std::move(poly));
      for (uint32_t ei : rt.candidates) {
        const size_t n = rt.pieces.size();
        for (size_t k = 0; k < n; ++k) {
          if (!vis::svgpu::survives(rt.pieces[k], rt.t, r.edges[ei])) continue;
          if (on_split) on_split(rt.pieces[k], r.edges[ei]);
          geom::SplitResult sr = vis::svgpu::split(rt.pieces[k], r.edges[ei]);
          ++r.clips;
          ++rt.clips;
          rt.pieces[k] = std::move(sr.inside);
          if (!sr.outside.empty()) rt.pieces.push_back(std::move(sr.outside));
        }
      }
    }
    r.triangles.push_back(std::move(rt));
  }
  return r;
}

}  // namespace tilevis::rtl
