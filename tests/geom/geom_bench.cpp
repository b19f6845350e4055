// ns per call of the hot geometry predicates (Google Benchmark; not a CTest test).
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "geom/clip.h"
#include "geom/depth.h"
#include "geom/overlap.h"
#include "geom/polygon.h"
#include "geom/predicates.h"

namespace tilevis::geom {
namespace {

constexpr std::size_t kN = 4096;  // inputs cycled per benchmark, fits in L1/L2

Point rnd_point(std::mt19937_64& rng, int32_t lo, int32_t hi) {
  std::uniform_int_distribution<int32_t> d(lo, hi);
  const int32_t x = d(rng);
  return {x, d(rng)};
}

Line rnd_line(std::mt19937_64& rng, int32_t lim) {
  for (;;) {
    const Point p = rnd_point(rng, -lim, lim), q = rnd_point(rng, -lim, lim);
    if (!(p == q)) return Line::through(p, q);
  }
}

Triangle rnd_triangle(std::mt19937_64& rng, int32_t lo, int32_t hi) {
  for (;;) {
    Triangle t;
    for (auto& v : t.v) {
      const Point p = rnd_point(rng, lo, hi);
      v = {p.x, p.y, static_cast<uint32_t>(rng() & 0xffffff)};
    }
    if (doubled_area(t) != 0) return t;
  }
}

void BM_Orient2d(benchmark::State& state) {
  std::mt19937_64 rng(1);
  std::vector<Point> p(kN + 2);
  for (auto& q : p) q = rnd_point(rng, -kCoordLimit, kCoordLimit);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(orient2d(p[i], p[i + 1], p[i + 2]));
    i = (i + 1) % kN;
  }
}
BENCHMARK(BM_Orient2d);

void BM_SampleCoverage(benchmark::State& state) {
  std::mt19937_64 rng(2);
  std::vector<TriangleEdges> t(kN);
  std::vector<Point> s(kN);
  for (std::size_t k = 0; k < kN; ++k) {
    const Triangle tri = rnd_triangle(rng, 0, 8192);
    t[k] = TriangleEdges::from(tri);
    s[k] = rnd_point(rng, 0, 8192);
  }
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(t[i].covers(s[i]));
    i = (i + 1) % kN;
  }
}
BENCHMARK(BM_SampleCoverage);

void BM_ImplicitSide(benchmark::State& state) {
  std::mt19937_64 rng(3);
  std::vector<ImplicitPoint> p;
  std::vector<Line> l;
  while (p.size() < kN) {
    const ImplicitPoint q = intersect(rnd_line(rng, kCoordLimit), rnd_line(rng, kCoordLimit));
    if (q.valid()) {
      p.push_back(q);
      l.push_back(rnd_line(rng, kCoordLimit));
    }
  }
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(side(l[i], p[i]));
    i = (i + 1) % kN;
  }
}
BENCHMARK(BM_ImplicitSide);

void BM_Intersect(benchmark::State& state) {
  std::mt19937_64 rng(4);
  std::vector<Line> l(kN + 1);
  for (auto& q : l) q = rnd_line(rng, kCoordLimit);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(intersect(l[i], l[i + 1]));
    i = (i + 1) % kN;
  }
}
BENCHMARK(BM_Intersect);

void BM_RationalSide(benchmark::State& state) {
  std::mt19937_64 rng(5);
  std::vector<RationalPoint> p;
  std::vector<Line> l;
  while (p.size() < kN) {
    ImplicitPoint q[3];
    bool ok = true;
    for (auto& v : q) {
      v = intersect(rnd_line(rng, 1 << 16), rnd_line(rng, 1 << 16));
      ok = ok && v.valid();
    }
    if (!ok) continue;
    p.push_back(centroid(q[0], q[1], q[2]));
    l.push_back(rnd_line(rng, 1 << 16));
  }
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(side(l[i], p[i]));
    i = (i + 1) % kN;
  }
}
BENCHMARK(BM_RationalSide);

void BM_Split(benchmark::State& state) {
  std::mt19937_64 rng(6);
  std::vector<ConvexPolygon> polys;
  std::vector<Line> lines;
  while (polys.size() < kN) {
    // Triangle clipped to a 32x32-pixel tile, then a line that crosses it.
    const Triangle t = rnd_triangle(rng, -2000, 10192);
    ConvexPolygon p = triangle_in_rect(t, {0, 0, 8192, 8192});
    if (p.empty()) continue;
    const Line l = rnd_line(rng, 8192);
    if (classify(p, l) != LineRelation::crosses) continue;
    polys.push_back(std::move(p));
    lines.push_back(l);
  }
  ConvexPolygon in, out;
  std::size_t i = 0;
  for (auto _ : state) {
    split(polys[i], lines[i], in, out);
    benchmark::DoNotOptimize(in.size() + out.size());
    i = (i + 1) % kN;
  }
}
BENCHMARK(BM_Split);

void BM_TriangleInTile(benchmark::State& state) {
  std::mt19937_64 rng(7);
  std::vector<Triangle> t(kN);
  for (auto& q : t) q = rnd_triangle(rng, -2000, 10192);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(triangle_in_rect(t[i], {0, 0, 8192, 8192}).size());
    i = (i + 1) % kN;
  }
}
BENCHMARK(BM_TriangleInTile);

void BM_TriangleOverlapsTile(benchmark::State& state) {
  std::mt19937_64 rng(8);
  std::vector<Triangle> t(kN);
  for (auto& q : t) q = rnd_triangle(rng, -2000, 10192);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(triangle_overlaps_rect(t[i], {0, 0, 8192, 8192}));
    i = (i + 1) % kN;
  }
}
BENCHMARK(BM_TriangleOverlapsTile);

void BM_InteriorPoint(benchmark::State& state) {
  std::mt19937_64 rng(9);
  std::vector<ConvexPolygon> polys;
  while (polys.size() < kN) {
    ConvexPolygon p = triangle_in_rect(rnd_triangle(rng, -2000, 10192), {0, 0, 8192, 8192});
    if (!p.empty()) polys.push_back(std::move(p));
  }
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(interior_point(polys[i]));
    i = (i + 1) % kN;
  }
}
BENCHMARK(BM_InteriorPoint);

struct DepthInputs {
  std::vector<DepthPlane> p, q;
  std::vector<Point> s;
  std::vector<ImplicitPoint> v;
  std::vector<RationalPoint> r;
  std::vector<Triangle> t;
};

const DepthInputs& depth_inputs() {
  static const DepthInputs in = [] {
    DepthInputs d;
    std::mt19937_64 rng(10);
    while (d.p.size() < kN) {
      const Triangle a = rnd_triangle(rng, 0, 1 << 18), b = rnd_triangle(rng, 0, 1 << 18);
      ImplicitPoint q[3];
      bool ok = true;
      for (auto& v : q) {
        v = intersect(rnd_line(rng, 1 << 18), rnd_line(rng, 1 << 18));
        ok = ok && v.valid();
      }
      if (!ok) continue;
      d.p.push_back(DepthPlane::from(a));
      d.q.push_back(DepthPlane::from(b));
      d.t.push_back(a);
      d.s.push_back(rnd_point(rng, 0, 1 << 18));
      d.v.push_back(q[0]);
      d.r.push_back(centroid(q[0], q[1], q[2]));
    }
    return d;
  }();
  return in;
}

void BM_DepthOrderSample(benchmark::State& state) {
  const auto& d = depth_inputs();
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(depth_order(d.p[i], d.q[i], d.s[i]));
    i = (i + 1) % kN;
  }
}
BENCHMARK(BM_DepthOrderSample);

void BM_DepthOrderImplicit(benchmark::State& state) {
  const auto& d = depth_inputs();
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(depth_order(d.p[i], d.q[i], d.v[i]));
    i = (i + 1) % kN;
  }
}
BENCHMARK(BM_DepthOrderImplicit);

void BM_DepthOrderRational(benchmark::State& state) {
  const auto& d = depth_inputs();
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(depth_order(d.p[i], d.q[i], d.r[i]));
    i = (i + 1) % kN;
  }
}
BENCHMARK(BM_DepthOrderRational);

// Exact fallback cost: a tie (plane against itself) always reaches the wide path.
void BM_DepthOrderRationalExactTie(benchmark::State& state) {
  const auto& d = depth_inputs();
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(depth_order(d.p[i], d.p[i], d.r[i]));
    i = (i + 1) % kN;
  }
}
BENCHMARK(BM_DepthOrderRationalExactTie);

void BM_DepthOrderEdge(benchmark::State& state) {
  const auto& d = depth_inputs();
  std::vector<ImplicitPoint> on(kN);
  std::mt19937_64 rng(11);
  for (std::size_t k = 0; k < kN; ++k) {
    const Triangle& t = d.t[(k + 1) % kN];
    do on[k] = intersect(Line::through(t.v[0].xy(), t.v[1].xy()), rnd_line(rng, 1 << 18));
    while (!on[k].valid());
  }
  std::size_t i = 0;
  for (auto _ : state) {
    const Triangle& t = d.t[(i + 1) % kN];
    benchmark::DoNotOptimize(depth_order_edge(d.p[i], t.v[0], t.v[1], on[i]));
    i = (i + 1) % kN;
  }
}
BENCHMARK(BM_DepthOrderEdge);

}  // namespace
}  // namespace tilevis::geom

BENCHMARK_MAIN();
