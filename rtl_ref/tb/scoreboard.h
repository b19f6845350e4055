// The scoreboard's side of the RTL testbenches: what each unit must decide, from the public
// functions of model/visibility (svgpu.h) and model/geom, and the constrained-random source
// shared by the units' testbenches.
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "geom/clip.h"
#include "geom/polygon.h"
#include "visibility/svgpu.h"

namespace tilevis::rtl {

// PairReject's decision codes (rtl_ref/units/pair_reject.sv).
enum PairCode : int { kDepth = 0, kBehind = 1, kBoxes = 2, kShared = 3, kOneSide = 4, kMisses = 5 };
inline const char* pair_code_name(int c) {
  static const char* n[] = {"depth(test 3 decides)", "behind(6)", "boxes(2)", "shared(4)", "one_side(1)", "misses(2)"};
  return c >= 0 && c <= 5 ? n[c] : "?";
}

// The tests in the order the analytic resolver applies them (analytic_resolver.cpp).
inline int expected_pair_code(const geom::ConvexPolygon& poly, const vis::svgpu::Triangle& t,
                              const vis::svgpu::Edge& e) {
  if (vis::svgpu::edge_behind(e, t)) return kBehind;
  if (vis::svgpu::boxes_apart(e, t)) return kBoxes;
  if (vis::svgpu::shares_edge(e, t.tri)) return kShared;
  if (geom::classify(poly, e.line) != geom::LineRelation::crosses) return kOneSide;
  if (!geom::segment_overlaps(poly, e.a.xy(), e.b.xy())) return kMisses;
  return kDepth;
}

struct PairVector {
  vis::svgpu::Triangle t;
  vis::svgpu::Edge e;
  geom::ConvexPolygon poly;  // the triangle clipped to its tile (or any piece of it)
};

// Coverage of the corner cases a vector exercises (counted by the testbench).
struct PairCoverage {
  uint64_t vectors = 0, codes[6] = {};
  uint64_t vertex_on_line = 0;     // a polygon vertex exactly on the edge's line (tie)
  uint64_t collinear = 0;          // the edge lies on a triangle edge's line without being that edge
  uint64_t shared_vertex = 0;      // an edge endpoint is a triangle vertex
  uint64_t degenerate_edge = 0;    // a == b
  uint64_t depth_tie = 0;          // edge z_min == triangle z_max
  uint64_t implicit_vertices = 0;  // the polygon has a vertex that is not a snapped point (w > 1)
  uint64_t max_vertices = 0;
  void add(const PairVector& v, int code);
  std::string report() const;
};

// Constrained-random pairs: coordinates from a small lattice (ties everywhere), a tile-sized
// range or the whole guard band; the edge is random, a triangle edge, collinear with one,
// anchored at a triangle vertex or degenerate; depths with deliberate equalities.
class PairSource {
 public:
  explicit PairSource(uint64_t seed) : m_rng(seed) {}
  PairVector next();

 private:
  int32_t coord(int scale);
  uint32_t depth();
  std::mt19937_64 m_rng;
  int m_scale = 0;
};

}  // namespace tilevis::rtl

namespace tilevis::rtl {

// A tile job replayed through the public functions in the analytic resolver's order
// (analytic_resolver.cpp): per triangle its tile polygon, its candidate edges (tests 1-6),
// and its pieces after clipping with re-checks. `on_split` sees every split performed.
struct ReplayedTriangle {
  vis::svgpu::Triangle t;
  uint32_t id = 0;
  bool opaque = true;
  std::vector<uint32_t> candidates;
  std::vector<geom::ConvexPolygon> pieces;
  int64_t clips = 0;  // splits performed on its pieces
};
struct ReplayedJob {
  std::vector<vis::svgpu::Edge> edges;
  std::vector<ReplayedTriangle> triangles;
  int64_t clips = 0;
};
// A testbench's command line: --random N --seed S (N constrained-random vectors from seed S),
// --jobs FILE (again for more files) [--job-stride K: every K-th tile job], and where the
// testbench takes them (`extra`, kTb* bits) --csv FILE and --max-jobs M. Anything else, or an
// option without its value, prints the usage and exits with status 2.
enum TbExtra : unsigned { kTbCsv = 1, kTbMaxJobs = 2 };
struct TbOptions {
  uint64_t random = 0, seed = 1, job_stride = 1, max_jobs = ~uint64_t{0};
  std::vector<std::string> jobs;
  std::string csv;
};
TbOptions parse_tb_options(int argc, char** argv, unsigned extra);

}  // namespace tilevis::rtl

#include <functional>

#include "visibility/evu_jobs.h"

namespace tilevis::rtl {
ReplayedJob replay_job(const vis::EvuJob& job,
                       const std::function<void(const geom::ConvexPolygon&, const vis::svgpu::Edge&)>& on_split = {});
}  // namespace tilevis::rtl
