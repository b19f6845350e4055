#include "visibility/evu_jobs.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "visibility/tile_resolver.h"

namespace tilevis::vis {
namespace {

constexpr const char* kMagic = "tilevis-evu-jobs";
constexpr int kVersion = 1;

void put_vertex(std::ostream& o, const geom::Vertex& v) { o << ' ' << v.x << ' ' << v.y << ' ' << v.z; }

}  // namespace

EvuJob make_evu_job(const TileFrame& f, uint32_t tile, const TileCounters* golden) {
  EvuJob j;
  j.tile = tile;
  j.rect = f.grid().rect(tile);
  const auto& tris = f.tile_triangles(tile);
  const auto& edges = f.tile_edges(tile);
  j.triangles.reserve(tris.size());
  for (uint32_t i : tris) {
    const FrontTriangle& t = f.triangles()[i];
    EvuJobTriangle jt;
    jt.id = t.t->id;
    for (int k = 0; k < 3; ++k) jt.v[k] = t.tri.v[k];
    jt.opaque = t.t->opaque;
    j.triangles.push_back(jt);
  }
  j.edges.reserve(2 * edges.size());
  for (uint32_t i : edges) {
    const svgpu::Edge& e = f.edges()[i];
    j.edges.push_back(e.a);
    j.edges.push_back(e.b);
  }
  if (golden) j.golden = *golden;
  j.golden.triangles = int64_t(tris.size());
  j.golden.edges = int64_t(edges.size());
  return j;
}

EvuJobSource::EvuJobSource(const TileFrame& f)
    : m_f(f),
      m_resolver(make_tile_resolver("analytic", {})),
      m_ids(size_t(f.setup().width) * f.setup().height * f.setup().samples.size(), -1) {}

EvuJobSource::~EvuJobSource() = default;

EvuJob EvuJobSource::job(uint32_t tile) {
  TileCounters c;
  TileOutput out;
  out.ids = m_ids.data();
  if (!m_f.tile_triangles(tile).empty()) m_resolver->resolve(m_f, tile, out, c, nullptr);
  return make_evu_job(m_f, tile, &c);
}

uint64_t write_evu_jobs(const Setup& setup, uint32_t tile_w, uint32_t tile_h, uint32_t frame, const std::string& path) {
  const geom::TileGrid grid = geom::TileGrid::make(setup.width, setup.height, tile_w, tile_h, setup.subpixel_bits);
  TileFrame f(setup, grid);
  f.bin();
  std::ofstream o(path);
  if (!o) throw std::runtime_error(path + ": cannot open for writing");
  o << kMagic << ' ' << kVersion << '\n';
  o << "frame " << frame << ' ' << setup.width << ' ' << setup.height << ' ' << setup.subpixel_bits << ' ' << tile_w
    << ' ' << tile_h << '\n';
  EvuJobSource source(f);
  uint64_t jobs = 0;
  for (uint32_t tile = 0; tile < grid.tile_count(); ++tile) {
    if (f.tile_triangles(tile).empty()) continue;
    const EvuJob j = source.job(tile);
    const TileCounters& c = j.golden;
    const geom::Rect& r = j.rect;
    o << "tile " << tile << ' ' << r.x0 << ' ' << r.y0 << ' ' << r.x1 << ' ' << r.y1 << ' ' << j.triangles.size() << ' '
      << j.edges.size() / 2 << ' ' << c.pair_tests << ' ' << c.candidate_pairs << ' ' << c.clip_polygons << ' '
      << c.pieces << ' ' << c.visible_pieces << ' ' << c.occlusion_tests << '\n';
    for (const EvuJobTriangle& t : j.triangles) {
      o << 't' << ' ' << t.id;
      for (const auto& v : t.v) put_vertex(o, v);
      o << ' ' << (t.opaque ? 1 : 0) << '\n';
    }
    for (size_t k = 0; k < j.edges.size(); k += 2) {
      o << 'e';
      put_vertex(o, j.edges[k]);
      put_vertex(o, j.edges[k + 1]);
      o << '\n';
    }
    ++jobs;
  }
  if (!o) throw std::runtime_error(path + ": write failed");
  return jobs;
}

EvuJobsHeader read_evu_jobs(const std::string& path, const std::function<void(const EvuJob&)>& job) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::string line;
  uint64_t n = 0;
  auto fail = [&](const std::string& what) {
    throw std::runtime_error(path + ": line " + std::to_string(n) + ": expected " + what);
  };
  auto next = [&](const char* what) {
    if (!std::getline(in, line)) fail(what);
    ++n;
  };
  next("the header");
  {
    std::istringstream s(line);
    std::string magic;
    int version = 0;
    if (!(s >> magic >> version) || magic != kMagic || version != kVersion)
      fail(std::string(kMagic) + " " + std::to_string(kVersion));
  }
  EvuJobsHeader h;
  next("the frame line");
  {
    std::istringstream s(line);
    std::string tag;
    if (!(s >> tag >> h.frame >> h.width >> h.height >> h.subpixel_bits >> h.tile_w >> h.tile_h) || tag != "frame")
      fail("'frame K W H SUBPIXEL_BITS TILE_W TILE_H'");
  }
  EvuJob j;
  while (std::getline(in, line)) {
    ++n;
    std::istringstream s(line);
    std::string tag;
    size_t nt = 0, ne = 0;
    TileCounters& c = j.golden;
    if (!(s >> tag >> j.tile >> j.rect.x0 >> j.rect.y0 >> j.rect.x1 >> j.rect.y1 >> nt >> ne >> c.pair_tests >>
          c.candidate_pairs >> c.clip_polygons >> c.pieces >> c.visible_pieces >> c.occlusion_tests) ||
        tag != "tile")
      fail("'tile INDEX X0 Y0 X1 Y1 TRIANGLES EDGES PAIR_TESTS CANDIDATES CLIPS PIECES VISIBLE OCCLUSION_TESTS'");
    c.triangles = int64_t(nt);
    c.edges = int64_t(ne);
    j.triangles.resize(nt);
    j.edges.resize(2 * ne);
    for (auto& t : j.triangles) {
      next("a triangle line");
      std::istringstream ts(line);
      int opaque = 0;
      if (!(ts >> tag >> t.id) || tag != "t") fail("'t ID X0 Y0 Z0 X1 Y1 Z1 X2 Y2 Z2 OPAQUE'");
      for (auto& v : t.v)
        if (!(ts >> v.x >> v.y >> v.z)) fail("'t ID X0 Y0 Z0 X1 Y1 Z1 X2 Y2 Z2 OPAQUE'");
      if (!(ts >> opaque)) fail("'t ID X0 Y0 Z0 X1 Y1 Z1 X2 Y2 Z2 OPAQUE'");
      t.opaque = opaque != 0;
    }
    for (size_t k = 0; k < ne; ++k) {
      next("an edge line");
      std::istringstream es(line);
      geom::Vertex& a = j.edges[2 * k];
      geom::Vertex& b = j.edges[2 * k + 1];
      if (!(es >> tag >> a.x >> a.y >> a.z >> b.x >> b.y >> b.z) || tag != "e") fail("'e AX AY AZ BX BY BZ'");
    }
    job(j);
  }
  return h;
}

}  // namespace tilevis::vis
