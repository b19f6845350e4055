// The sampled render's estimator (units/tile_scheduler/tile_sampler.h), pure arithmetic:
// the normal quantile, rounds without replacement, an exact fit where the occupancy is a
// linear function of the auxiliaries, the interval's coverage on a noisy population (fixed
// seeds: deterministic), and the sample size the budget asks for.
#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "units/tile_scheduler/tile_sampler.h"

using namespace tilevis::sim;

namespace {

SamplingConfig config(uint32_t cluster, uint64_t seed) {
  SamplingConfig c;
  c.cluster_tiles = cluster;
  c.seed = seed;
  return c;
}

// One core, every tile after the first observed: feeds `sampler` the clusters of one round.
void observe_round(TileSampler& s, const std::vector<uint64_t>& round, const std::vector<double>& occupancy,
                   const std::vector<double>& triangles, bool& first) {
  for (uint64_t c : round) {
    double y = 0, x = 0;
    uint64_t m = 0;
    for (uint64_t p = s.cluster_begin(c); p < s.cluster_end(c); ++p) {
      if (first) {
        s.observe_fill(occupancy[p]);
        first = false;
        continue;
      }
      y += occupancy[p], x += triangles[p], ++m;
    }
    s.observe_cluster(c, y, double(m), x);
  }
}

// n tiles of 0 to 199 triangles each, occupancy 150 + 7 a triangle (exactly linear).
void linear_population(uint64_t seed, size_t n, std::vector<double>& tris, std::vector<double>& occ) {
  std::mt19937_64 rng(seed);
  tris.resize(n);
  occ.resize(n);
  for (size_t i = 0; i < n; ++i) {
    tris[i] = double(rng() % 200);
    occ[i] = 150.0 + 7.0 * tris[i];
  }
}

}  // namespace

TEST(Sampler, NormalQuantile) {
  EXPECT_NEAR(normal_quantile(0.95), 1.959963985, 1e-8);
  EXPECT_NEAR(normal_quantile(0.99), 2.575829304, 1e-8);
  EXPECT_NEAR(normal_quantile(0.6826894921), 1.0, 1e-8);
  EXPECT_THROW(normal_quantile(1.0), std::invalid_argument);
  // Tables: t(0.975; 1) = 12.706, t(0.975; 12) = 2.179, t(0.995; 30) = 2.750; large dof -> z.
  EXPECT_NEAR(student_quantile(0.95, 1), 12.7062, 1e-3);
  EXPECT_NEAR(student_quantile(0.95, 12), 2.1788, 1e-3);
  EXPECT_NEAR(student_quantile(0.99, 30), 2.7500, 1e-3);
  EXPECT_NEAR(student_quantile(0.95, 1e6), normal_quantile(0.95), 1e-4);
}

TEST(Sampler, RoundsDrawEveryClusterOnceAscendingAndTheSeedFixesThem) {
  const std::vector<double> tris(103, 1.0);
  TileSampler a(tris, config(4, 7), 0), b(tris, config(4, 7), 0), c(tris, config(4, 8), 0);
  EXPECT_EQ(a.clusters(), 26u);
  EXPECT_EQ(a.cluster_end(25), 103u);
  std::set<uint64_t> seen;
  std::vector<uint64_t> all_a, all_c;
  for (uint64_t want : {5, 9, 100}) {
    const auto r = a.next_round(want), rb = b.next_round(want), rc = c.next_round(want);
    EXPECT_EQ(r, rb);
    EXPECT_TRUE(std::is_sorted(r.begin(), r.end()));
    for (uint64_t x : r) EXPECT_TRUE(seen.insert(x).second) << "cluster " << x << " drawn twice";
    all_a.insert(all_a.end(), r.begin(), r.end());
    all_c.insert(all_c.end(), rc.begin(), rc.end());
  }
  EXPECT_EQ(seen.size(), 26u);
  EXPECT_TRUE(a.next_round(3).empty());
  EXPECT_NE(all_a, all_c);  // another seed, another sample
}

TEST(Sampler, AnExactLinearPopulationIsEstimatedExactlyWithZeroWidth) {
  const size_t n = 400;
  std::vector<double> tris, occ;
  linear_population(3, n, tris, occ);
  TileSampler s(tris, config(4, 1), 0);
  bool first = true;
  const std::vector<uint64_t> round = s.next_round(12);
  observe_round(s, round, occ, tris, first);
  const RenderEstimate e = s.estimate(1);
  // The fill is the round's first tile; Y = a M + b X over all tiles but one (one core).
  double sum_tris = 0;
  for (size_t i = 0; i < n; ++i) sum_tris += tris[i];
  const double fill = occ[s.cluster_begin(round.front())];
  const double expect = fill + 150.0 * double(n - 1) + 7.0 * sum_tris * double(n - 1) / double(n);
  EXPECT_NEAR(e.cycles, expect, 1e-9 * expect);
  EXPECT_NEAR(e.half_width, 0.0, 1e-6 * e.cycles);
  EXPECT_FALSE(e.complete);
  EXPECT_EQ(e.clusters_observed, 12u);
  EXPECT_EQ(e.tiles_observed, 48u);
}

TEST(Sampler, TakeAllClustersAreTheHeavyOnesAndTheClustersBeforeEachRun) {
  // Clusters of 4: a unit of 1000 (mean 94.7; over 4x) in clusters 2 and 3, and in cluster 6.
  std::vector<double> aux(32, 1.0);
  aux[9] = aux[14] = aux[25] = 1000.0;
  const std::vector<bool> c = take_all_clusters({aux}, 4, 4.0);
  EXPECT_EQ(take_all_clusters({aux}, 4, 16.0), std::vector<bool>(8, false));  // 1000 < 16 x 94.7
  EXPECT_EQ(c, (std::vector<bool>{false, true, true, true, false, true, true, false}));
  EXPECT_EQ(take_all_clusters({std::vector<double>(32, 5.0)}, 4, 16.0), std::vector<bool>(8, false));
  // Two clusters before each run: cluster 0 too.
  EXPECT_EQ(take_all_clusters({aux}, 4, 4.0, 2), (std::vector<bool>{true, true, true, true, true, true, true, false}));
  // Any auxiliary may make a unit heavy: a second one with a peak in cluster 7.
  std::vector<double> pairs(32, 2.0);
  pairs[30] = 500.0;
  EXPECT_EQ(take_all_clusters({aux, pairs}, 4, 4.0),
            (std::vector<bool>{false, true, true, true, false, true, true, true}));
  // A run at the start has no cluster before it; a cut last cluster counts.
  std::vector<double> tail(10, 1.0);
  tail[0] = tail[9] = 1000.0;
  EXPECT_EQ(take_all_clusters({tail}, 4, 2.0), (std::vector<bool>{true, true, true}));
  EXPECT_THROW(take_all_clusters({tail}, 0, 2.0), std::invalid_argument);
  EXPECT_THROW(take_all_clusters({tail, aux}, 4, 2.0), std::invalid_argument);
}

// Take-all clusters come in the first round beside the stratified draw, are in no stratum, and
// are added as they are: where the rest is an exact linear population, the estimate is exact
// however far from it the take-all clusters' occupancies lie, and the interval has no width.
TEST(Sampler, TakeAllClustersAreAddedAsTheyAre) {
  std::mt19937_64 rng(11);
  const size_t n = 400;
  std::vector<double> tris, occ;
  linear_population(11, n, tris, occ);
  std::vector<bool> certain(n / 4, false);
  for (uint64_t c : {0, 17, 18, 60}) {
    certain[c] = true;
    for (size_t p = 4 * c; p < 4 * c + 4; ++p) occ[p] = 50000.0 + double(rng() % 9000);  // not linear
  }
  TileSampler s(tris, config(4, 1), 0, {}, {}, certain);
  EXPECT_EQ(s.clusters(), 100u);
  EXPECT_EQ(s.take_all(), 4u);
  EXPECT_THROW(TileSampler(tris, config(4, 1), 0, {}, {}, std::vector<bool>(99, false)), std::invalid_argument);
  const std::vector<uint64_t> round = s.next_round(12);
  ASSERT_EQ(round.size(), 16u);
  for (uint64_t c : {0, 17, 18, 60}) EXPECT_TRUE(std::binary_search(round.begin(), round.end(), c));
  EXPECT_EQ(s.clusters_taken(), 16u);
  bool first = true;
  observe_round(s, round, occ, tris, first);
  const RenderEstimate e = s.estimate(1);
  // The fill is cluster 0's first tile (a take-all one); the take-all clusters' other tiles
  // are summed; the regression's population is the other 384 tiles, less one average tile.
  double exact = 0, sum_tris = 0;
  for (size_t i = 1; i < n; ++i)
    if (certain[i / 4]) exact += occ[i];
  for (size_t i = 0; i < n; ++i)
    if (!certain[i / 4]) sum_tris += tris[i];
  const double m = 384;
  const double expect = occ[0] + exact + (150.0 * m + 7.0 * sum_tris) * (m - 1) / m;
  EXPECT_NEAR(e.cycles, expect, 1e-9 * expect);
  EXPECT_NEAR(e.half_width, 0.0, 1e-6 * e.cycles);
  EXPECT_EQ(e.clusters_observed, 16u);
  EXPECT_EQ(e.tiles_observed, 64u);
  // Later rounds draw the stratified clusters only, and all of them complete the sample.
  for (uint64_t c : s.next_round(1000)) EXPECT_FALSE(s.is_take_all(c));
  EXPECT_EQ(s.clusters_taken(), 100u);
}

// Tiles cut by the screen's bottom edge (a quarter of their rows gone) cost their share of a
// full tile's fixed cost: with each tile's size as the regressor the estimate is exact from a
// sample of full tiles alone; counting tiles, it would be a full tile's cost too high for each
// cut tile (decals at 1080p: +1.09 % inside a zero-width interval).
TEST(Sampler, TilesCutByTheScreenEdgeCountTheirShare) {
  const size_t n = 400, row = 40;  // 10 rows of 40 tiles; the last row 24 of 32 pixel rows
  std::vector<double> tris(n), size(n, 1.0), occ(n);
  std::mt19937_64 rng(5);
  for (size_t i = 0; i < n; ++i) {
    if (i >= n - row) size[i] = 0.75;
    tris[i] = double(rng() % 50);
    occ[i] = 264.0 * size[i] + 3.0 * tris[i];
  }
  TileSampler s(tris, config(8, 3), 0, size);
  // A round of clusters that holds none of the last row's.
  std::vector<uint64_t> round;
  while (round.size() < 6) {
    for (uint64_t c : s.next_round(1))
      if (s.cluster_end(c) <= n - row) round.push_back(c);
  }
  std::sort(round.begin(), round.end());
  bool first = true;
  for (uint64_t c : round) {
    double y = 0, m = 0, x = 0;
    for (uint64_t p = s.cluster_begin(c); p < s.cluster_end(c); ++p) {
      if (first) {
        s.observe_fill(occ[p]);
        first = false;
        continue;
      }
      y += occ[p], m += size[p], x += tris[p];
    }
    s.observe_cluster(c, y, m, x);
  }
  double sum_tris = 0, sum_size = 0;
  for (size_t i = 0; i < n; ++i) sum_tris += tris[i], sum_size += size[i];
  const double fill = occ[s.cluster_begin(round.front())];
  const double share = double(n - 1) / double(n);  // all but the core's first tile, on average
  const double expect = fill + (264.0 * sum_size + 3.0 * sum_tris) * share;
  EXPECT_NEAR(s.estimate(1).cycles, expect, 1e-9 * expect);
  EXPECT_THROW(TileSampler(tris, config(8, 3), 0, std::vector<double>(n - 1, 1.0)), std::invalid_argument);
}

TEST(Sampler, TheIntervalCoversTheTruthAtItsConfidence) {
  // A population with clustered noise: occupancy = 300 + 4 x + cluster effect + tile noise.
  std::mt19937_64 rng(11);
  std::normal_distribution<double> cluster_effect(0.0, 120.0), noise(0.0, 80.0);
  const size_t n = 2000;
  std::vector<double> tris(n), occ(n);
  double effect = 0;
  for (size_t i = 0; i < n; ++i) {
    if (i % 4 == 0) effect = cluster_effect(rng);
    tris[i] = double(rng() % 300);
    occ[i] = std::max(0.0, 300.0 + 4.0 * tris[i] + effect + noise(rng));
  }
  int covered = 0, runs = 200;
  for (int seed = 1; seed <= runs; ++seed) {
    TileSampler s(tris, config(4, uint64_t(seed)), 0);
    bool first = true;
    observe_round(s, s.next_round(40), occ, tris, first);
    const RenderEstimate e = s.estimate(1);
    // The truth on the estimator's terms: this run's fill tile, then every other tile.
    double fill = 0, rest = 0;
    bool seen_first = false;
    const uint64_t first_cluster = [&] {
      TileSampler t(tris, config(4, uint64_t(seed)), 0);
      return t.next_round(40).front();
    }();
    for (size_t i = 0; i < n; ++i) {
      if (!seen_first && i == s.cluster_begin(first_cluster)) {
        fill = occ[i];
        seen_first = true;
        continue;
      }
      rest += occ[i];
    }
    const double truth = fill + rest;
    covered += std::abs(e.cycles - truth) <= e.half_width;
  }
  // 95 % nominal; the regression estimator's variance is approximate: 88 % or more.
  EXPECT_GE(covered, int(0.88 * runs)) << covered << " of " << runs;
  EXPECT_LE(covered, runs);
}

TEST(Sampler, ATighterBudgetNeedsMoreClustersAndAllTakenIsComplete) {
  std::mt19937_64 rng(5);
  const size_t n = 800;
  std::vector<double> tris(n), occ(n);
  for (size_t i = 0; i < n; ++i) {
    tris[i] = double(rng() % 100);
    occ[i] = 200.0 + 3.0 * tris[i] + double(rng() % 400);
  }
  TileSampler s(tris, config(4, 2), 0);
  bool first = true;
  observe_round(s, s.next_round(16), occ, tris, first);
  const RenderEstimate e = s.estimate(1);
  ASSERT_GT(e.half_width, 0.0);
  const uint64_t loose = s.clusters_needed(e.half_width * 2, 1), tight = s.clusters_needed(e.half_width / 4, 1);
  EXPECT_GT(tight, loose);
  EXPECT_GT(tight, 16u);
  EXPECT_LE(tight, s.clusters());
  observe_round(s, s.next_round(s.clusters()), occ, tris, first);
  const RenderEstimate all = s.estimate(1);
  EXPECT_TRUE(all.complete);
  EXPECT_EQ(all.half_width, 0.0);
  EXPECT_EQ(all.tiles_observed, n);
  EXPECT_EQ(s.clusters_needed(1.0, 1), s.clusters());
}

TEST(Sampler, StrataByTrianglesKeepTheHeavyClustersInEverySampleAndTheIntervalHonest) {
  // A skewed population as real scenes have it: 90 % of tiles cost a constant 264 cycles
  // (a fixed per-tile floor), the rest grow with their triangles. With strata of equal
  // cluster counts, 28 of these 200 seeds drew only light clusters of the top stratum and
  // claimed a zero-width interval (79 % coverage).
  std::mt19937_64 rng(21);
  const size_t n = 1600;
  std::vector<double> tris(n), occ(n);
  for (size_t i = 0; i < n; ++i) {
    const bool heavy = (i / 40) % 10 == 3;  // runs of heavy tiles, as an object covers them
    tris[i] = heavy ? double(20 + rng() % 40) : double(rng() % 4);
    occ[i] = heavy ? 264.0 + 55.0 * tris[i] + double(rng() % 300) : 264.0;
  }
  int covered = 0, runs = 200;
  for (int seed = 1; seed <= runs; ++seed) {
    TileSampler s(tris, config(8, uint64_t(seed)), 0);
    ASSERT_EQ(s.strata(), 4u);
    bool first = true;
    const std::vector<uint64_t> round = s.next_round(16);
    std::vector<int> per_stratum(s.strata(), 0);
    for (uint64_t c : round) ++per_stratum[s.stratum_of(c)];
    for (int k : per_stratum) EXPECT_GE(k, 2) << "seed " << seed;
    observe_round(s, round, occ, tris, first);
    const RenderEstimate e = s.estimate(1);
    double truth = 0;
    for (size_t i = 0; i < n; ++i) truth += occ[i];
    covered += std::abs(e.cycles - truth) <= e.half_width;
    EXPECT_GT(e.half_width, 0.0) << "seed " << seed;
  }
  EXPECT_GE(covered, int(0.88 * runs)) << covered << " of " << runs;
}

TEST(Sampler, TwoAlikeClustersInAStratumDoNotClaimItHasNoVariance) {
  // Most tiles alike (a scene's empty background: 264 cycles, one triangle), some a little
  // busier and noisy (an object's silhouette), a few runs heavy. The lightest stratum holds
  // both the empty clusters and the busier ones: where its two draws were both empty, their
  // residuals were equal and the stratum claimed no variance at all, so the interval left out
  // its unseen busier clusters.
  std::mt19937_64 rng(33);
  const size_t n = 1600;
  std::vector<double> tris(n), occ(n);
  for (size_t i = 0; i < n; ++i) {
    const size_t cluster = i / 8;
    const bool heavy = (i / 40) % 10 == 3;
    const bool busy = !heavy && cluster % 7 == 2;
    tris[i] = heavy ? double(20 + rng() % 40) : busy ? double(1 + rng() % 3) : 1.0;
    occ[i] = heavy ? 264.0 + 55.0 * tris[i] + double(rng() % 300)
             : busy ? 264.0 + 40.0 * tris[i] + double(rng() % 400)
                    : 264.0;
  }
  double truth = 0;
  for (size_t i = 0; i < n; ++i) truth += occ[i];
  int covered = 0, runs = 200;
  for (int seed = 1; seed <= runs; ++seed) {
    TileSampler s(tris, config(8, uint64_t(seed)), 0);
    bool first = true;
    observe_round(s, s.next_round(12), occ, tris, first);
    const RenderEstimate e = s.estimate(1);
    covered += std::abs(e.cycles - truth) <= e.half_width;
  }
  EXPECT_GE(covered, int(0.88 * runs)) << covered << " of " << runs;
}

namespace {

SampledPart part(double a, double b, double cost, uint64_t taken, uint64_t clusters) {
  SampledPart p;
  p.curve.a = a;
  p.curve.b = b;
  p.curve.known = true;
  p.cost = cost;
  p.taken = taken;
  p.clusters = clusters;
  return p;
}

double variance_at(const SampledPart& p, uint64_t n) {
  return n >= p.clusters ? 0.0 : std::max(0.0, p.curve.a / double(n) - p.curve.b);
}

}  // namespace

TEST(Allocate, TwoPartsFitTheTargetAtTheLeastCost) {
  // Geometry: many cheap clusters with a wide spread; render: few dear ones.
  const SampledPart g = part(4e10, 1e8, 300, 16, 273), r = part(4e9, 5e7, 1500, 16, 72);
  const double target = 15800;
  const std::vector<uint64_t> n = allocate({g, r}, target);
  ASSERT_EQ(n.size(), 2u);
  EXPECT_LE(variance_at(g, n[0]) + variance_at(r, n[1]), target * target);
  const double cost = g.cost * double(n[0]) + r.cost * double(n[1]);
  // Every other split that fits costs at least as much (up to the rounding of one cluster each).
  double best = 1e300;
  for (uint64_t i = g.taken; i <= g.clusters; ++i)
    for (uint64_t j = r.taken; j <= r.clusters; ++j)
      if (variance_at(g, i) + variance_at(r, j) <= target * target) best = std::min(best, g.cost * double(i) + r.cost * double(j));
  EXPECT_LE(cost, best + g.cost + r.cost);
  EXPECT_GE(cost, best);
  // A dearer render shifts the sample towards the geometry.
  SampledPart dear = r;
  dear.cost *= 4;
  const std::vector<uint64_t> m = allocate({g, dear}, target);
  EXPECT_GT(m[0], n[0]);
  EXPECT_LT(m[1], n[1]);
}

TEST(Allocate, APartPastItsShareStaysAndTheOtherTakesTheRest) {
  const double target = 1000;
  // The geometry already holds 200 of 273 clusters, far below its share of the variance.
  const SampledPart g = part(1e7, 0, 1, 200, 273), r = part(1e9, 0, 1, 16, 5000);
  const std::vector<uint64_t> n = allocate({g, r}, target);
  EXPECT_EQ(n[0], 200u);  // its share alone: 110 clusters
  // The render alone: a / n <= target^2 - the geometry's variance.
  const double left = target * target - variance_at(g, 200);
  EXPECT_EQ(n[1], uint64_t(std::ceil(r.curve.a / left)));
}

TEST(Allocate, ACompletePartLeavesTheWholeTargetToTheOther) {
  const SampledPart g = part(1e10, 0, 1, 273, 273), r = part(1e9, 0, 1, 16, 2000);
  const std::vector<uint64_t> n = allocate({g, r}, 1000);
  EXPECT_EQ(n[0], 273u);
  EXPECT_NEAR(double(n[1]), 1000.0, 1.0);  // 1e9 / 1e6
}

TEST(Allocate, NothingGrowsWhereTheTakenFitAndAnUnknownPartGrowsAnyway) {
  const SampledPart g = part(1e6, 0, 1, 16, 273), r = part(1e6, 0, 1, 16, 72);
  const std::vector<uint64_t> n = allocate({g, r}, 1000);  // 62,500 x 2 <= 1e6
  EXPECT_EQ(n[0], 16u);
  EXPECT_EQ(n[1], 16u);
  SampledPart unknown = r;
  unknown.curve.known = false;
  EXPECT_EQ(allocate({g, unknown}, 1000)[1], 32u);  // twice its taken
}

TEST(Allocate, ATargetBeyondReachTakesEverything) {
  // b > 0: even a complete sample of neither part reaches a zero target.
  const SampledPart g = part(1e8, 1e5, 1, 16, 273), r = part(1e8, 1e5, 3, 16, 72);
  const std::vector<uint64_t> n = allocate({g, r}, 0.0);
  EXPECT_EQ(n[0], 273u);
  EXPECT_EQ(n[1], 72u);
}

// Extra regressors (the render's triangles and pair rows): where the occupancy is a linear
// function of size, auxiliary and an extra regressor, a sample of clusters gives the exact
// total; a regressor the others span (here the auxiliary again) is left out of the fit and
// changes nothing; a wrong number of sums is refused.
TEST(Sampler, ExtraRegressorsFitExactlyAndASpannedOneIsLeftOut) {
  const size_t n = 640;
  std::vector<double> work(n), pairs(n), occ(n);
  std::mt19937_64 rng(21);
  for (size_t i = 0; i < n; ++i) {
    work[i] = double(rng() % 60);
    pairs[i] = double(rng() % 900);
    occ[i] = 200.0 + 2.0 * work[i] + 0.75 * pairs[i];
  }
  double sum_work = 0, sum_pairs = 0;
  for (size_t i = 0; i < n; ++i) sum_work += work[i], sum_pairs += pairs[i];
  const double share = double(n - 1) / double(n);
  for (const bool spanned : {false, true}) {
    std::vector<std::vector<double>> extra = {pairs};
    if (spanned) extra.push_back(work);
    TileSampler s(work, config(8, 4), 0, {}, extra);
    bool first = true;
    double fill = 0;
    for (uint64_t c : s.next_round(12)) {
      double y = 0, m = 0, x = 0;
      std::vector<double> z(extra.size(), 0.0);
      for (uint64_t p = s.cluster_begin(c); p < s.cluster_end(c); ++p) {
        if (first) {
          s.observe_fill(fill = occ[p]);
          first = false;
          continue;
        }
        y += occ[p], m += 1.0, x += work[p];
        for (size_t k = 0; k < extra.size(); ++k) z[k] += extra[k][p];
      }
      s.observe_cluster(c, y, m, x, z);
    }
    const double expect = fill + (200.0 * double(n) + 2.0 * sum_work + 0.75 * sum_pairs) * share;
    const RenderEstimate e = s.estimate(1);
    EXPECT_NEAR(e.cycles, expect, 1e-7 * expect) << "spanned " << spanned;
    EXPECT_LT(e.half_width, 1e-6 * expect) << "spanned " << spanned;
    EXPECT_THROW(s.observe_cluster(0, 1.0, 1.0, 1.0, {}), std::invalid_argument);
  }
  EXPECT_THROW(TileSampler(work, config(8, 4), 0, {}, {std::vector<double>(n - 1, 0.0)}), std::invalid_argument);
}
