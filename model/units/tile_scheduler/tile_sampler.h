// Sampled simulation of a segment's render (fidelity auto), in the manner of SMARTS
// (Wunderlich et al., ISCA 2003): simulate a random sample of the work in detail and
// estimate the whole with a confidence interval, growing the sample until the interval
// fits the error budget.
//
// The sampling unit is a cluster of consecutive tiles in the scheduler's order (tiles that
// share primitives stay together, so parameter-cache and DRAM-row locality inside a cluster
// are the full frame's). Rounds of randomly chosen clusters are dispatched in the
// scheduler's order; each round starts on empty cores, so every core's first tile of a
// round pays the pipeline fill.
//
// What is measured per tile is its occupancy of its core: the cycles from the previous
// tile's end on the same core (in the same round) to its own end. A core's render is then
// its first tile's fill plus the occupancies of the others, so a segment's render on C
// cores is estimated as
//     R = mean fill + Y / C,   Y = the occupancies of all but the C first tiles,
// Y by a regression estimator over clusters with auxiliaries known for every tile before any
// is simulated: the tiles' size (in full tiles: a tile cut by the screen's right or bottom
// edge counts its share of pixels, and its fixed per-pixel work, clear and write-back, with
// it; with the tile count instead, a sample without bottom-row tiles, whose 24 of 32 rows cost
// 200 cycles against 264, put decals +1.09 % off inside a zero-width interval), their binned work (tile_work: triangles, weighted by the EVU's all-pairs rows where a
// tile has many silhouette edges), and any further regressors the caller gives (the render:
// its binned triangles and the EVU's exact reject rows, TileFrame::pair_tests),
//     y_j = a m_j + b x_j + sum_k c_k z_jk + e_j   (cluster j: occupancy sum y, size m, work x),
//     Y = a M + b X + sum_k c_k Z_k,
// with M, X and Z_k the population's totals less C average tiles. Work alone leaves a tile's
// triangles and its pairs confounded: with both beside it the residuals' spread fell by 12 to
// 49 % (million, bunny, dragon_bunnies, elephant, glass, armadillo; one core, 32x32 tiles).
// A regressor that the others already span (per-pixel modes: work = triangles, no pairs) is
// left out of the fit. The clusters are stratified by
// their work (equal-sized strata of the sorted clusters) and drawn within each stratum
// at random, at least two per stratum, then in Neyman allocation (K_h s_h): a skewed scene's
// heavier clusters are always represented, and a sample of light clusters alone can no longer
// claim a zero-width interval. The fit is weighted by the design weights K_h / n_h (the
// combined regression estimator: Cochran, Sampling Techniques, ch. 7) and
//     Var(Y) = sum_h K_h^2 (1 - n_h/K_h) s_eh^2 / n_h   (K_h clusters, n_h observed),
// s_eh^2 the residuals' variance within stratum h, and no less than the pooled one (over all
// strata) while h has clusters unobserved: two or three draws alike (empty tiles) would claim
// none. Pure arithmetic: no SystemC.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

namespace tilevis::sim {

struct SamplingConfig {
  double error_budget = 0.02;  // interval half-width / frame cycles to reach
  double confidence = 0.95;    // two-sided confidence of the interval
  uint32_t cluster_tiles = 8;  // tiles per sampling unit (4 left a locality bias at 8x8 tiles)
  uint32_t first_clusters = 16;  // the first round's clusters
  uint32_t strata = 4;           // strata of clusters by their work (at most; two clusters each at least)
  // Tiles with more than this many times the segment's mean work (tile_work below) are
  // simulated, all of them, in the first round (a take-all stratum): a skewed scene's few
  // heavy tiles would otherwise be missed by a small sample, and its interval be falsely
  // narrow (hot_tile at 1080p without it: -22 % inside a +/-0.35 % interval). The work grows
  // with the square of a tile's density where its edges grow with its triangles, so 16 here
  // is 4x in triangles; 4x in work took 184 of the bunny's 623 tiles whole. Tiles with this
  // many times the mean pairs through test 6 are taken too (clip-bound tiles: slivers' rare
  // ones hid from a first round of 16 clusters inside a +/-0.01 % interval, -7.7 %), and in the
  // sampled geometry, triangles with this many times the mean bytes.
  double certainty_ratio = 16.0;
  // Clusters before each run of take-all tiles, taken whole with it (take_all_clusters): the
  // light tiles before a heavy run drain what the run's predecessors left in the memory queues
  // and let the units upstream run ahead as in the frame. With one, hot_tile's take-all tiles
  // cost 11 % more than in the frame (render +2.3 % with every tile simulated; teapot_stadium
  // +0.4 %); with 8, over seeds 1-8 on the 15 built-in scenes (take-all by work or pairs), the
  // interval held the full frame in 96 of 120 runs against 87, mean error 0.56 % against 0.66 %,
  // in 2 % less host time in all (the bunny 13 % more).
  uint32_t take_all_lead = 8;
  // Detailed warming: a cluster whose preceding tile is not in the same round starts with
  // this many tiles per core simulated but not observed, so that the measured tiles follow
  // a tile as they do in the full frame (a core's overlap of consecutive tiles and its
  // caches depend on the tile before). Interpenetrating at 1080p, every cluster simulated, no
  // take-all tiles: +1.06 % without, +0.13 % with one; two gave +1.84 % (the warm-up tiles
  // themselves are estimated by the regression, and the tiles' occupancies depend on a longer
  // history than a few tiles: the memory model's queue).
  uint32_t warm_tiles = 1;
  uint64_t seed = 1;
  // Geometry (one-segment frames): clusters of this many consecutive trace triangles, the
  // first `geometry_warm` of a cluster that follows an unsimulated one simulated but not
  // measured (the queues between the geometry units hold 16 items each by default).
  uint32_t geometry_cluster = 256;
  uint32_t geometry_warm = 64;
  // The geometry's first round, before the render (later rounds come from the shared budget).
  // Its clusters' times are skewed (a few triangles spanning many tiles, write drains): with 16,
  // slivers' geometry came out 13 to 22 % low on four seeds inside intervals of 4 to 17 %; with
  // 32, -1 to -9 %, and fidelity auto held the primitive level on 22 of 33 runs over 11 scenes
  // against 20, in the same host time.
  uint32_t geometry_first = 32;
  // The tiles' work known before any is simulated, the auxiliary x of the estimator, the
  // strata and the take-all rule: a tile's binned triangles, each counted as the rows of
  // `reject_lanes` silhouette edges the EVU's reject stage reads for it at most,
  // triangles x max(1, edges / reject_lanes) (0: triangles alone, as in the per-pixel modes).
  // Where a tile's edges are many, the EVU's all-pairs work, not its triangles, sets its time.
  uint32_t reject_lanes = 0;
  // The host time of simulating one of a tile's binned triangles at fidelity primitive, in
  // units of a geometry triangle's, by which a frame's budget is shared between its sampled
  // geometry and its render (allocate()). Measured on a 2-core host with the resolve on the
  // simulating thread: 2.4 on the bunny (3.25 against 1.37 us), 3.0 on million (4.2 against
  // 1.42 us, its tiles' all-pairs work). With tiles resolved ahead on the second core, 1.0,
  // 1.5 and 2.5 gave the same host time within 6 % (bunny, million, slivers; 4 seeds each).
  double tile_triangle_cost = 2.5;
};

// A tile's auxiliary (SamplingConfig::reject_lanes).
inline double tile_work(uint32_t triangles, uint32_t edges, uint32_t reject_lanes) {
  const double rows = reject_lanes ? double(edges) / double(reject_lanes) : 1.0;
  return double(triangles) * (rows > 1.0 ? rows : 1.0);
}

// Take-all clusters of units in clusters of `cluster` consecutive units, `aux` one or more
// auxiliaries (each one value per unit): every cluster holding a unit with more than `ratio`
// times the mean of any auxiliary, and the `lead` clusters before each run of them, where the
// run's cold start then falls (a heavy tile after an unsimulated one was 35 % dearer on
// armadillo_box).
std::vector<bool> take_all_clusters(const std::vector<std::vector<double>>& aux, uint32_t cluster, double ratio,
                                    uint32_t lead = 1);

// Two-sided standard-normal quantile: P(|Z| <= z) = confidence.
double normal_quantile(double confidence);
// Two-sided Student's t quantile with `dof` degrees of freedom: P(|T| <= t) = confidence.
double student_quantile(double confidence, double dof);

struct RenderEstimate {
  double cycles = 0;       // estimated render cycles of the whole segment
  double half_width = 0;   // of the confidence interval, cycles
  uint64_t tiles = 0, tiles_observed = 0;
  uint64_t clusters = 0, clusters_observed = 0;
  bool complete = false;   // every tile was simulated (no estimate: zero width)
};

// A sample's half-width squared at n clusters (taken in Neyman allocation within its
// strata), on its estimate's scale: hw(n)^2 = a / n - b.
struct VarianceCurve {
  double a = 0, b = 0;
  bool known = false;  // every open stratum has a variance (else nothing bounds the sample)
};

// One sampled part of a frame (its geometry, its render) for allocate(): its curve, the host
// cost of one more cluster (any unit, the same for every part), the clusters taken and in all.
struct SampledPart {
  VarianceCurve curve;
  double cost = 1;
  uint64_t taken = 0, clusters = 0;
};

// The cheapest sample that fits parts whose half-widths add in quadrature into a half-width
// `target`: per part, the clusters in all that minimise sum cost n subject to
// sum (a / n - b) <= target^2, each between its taken and its population. Lagrange gives
// n_i = sqrt(a_i / cost_i) (sum_j sqrt(a_j cost_j)) / (target^2 + sum_j b_j); a part that
// would fall below its taken, or above its population, is held there and the others solved
// again. A part whose variance is unknown grows as clusters_needed() grows it (at least three
// more, or twice its taken). While the parts taken do not fit, at least one part grows.
std::vector<uint64_t> allocate(const std::vector<SampledPart>& parts, double target);

class TileSampler {
 public:
  // `aux`: per unit (tile, or trace triangle) in order, the auxiliary known before any is
  // simulated (tile_work; a geometry's bytes). `size`: per unit, its size regressor (a tile's
  // pixels over a full tile's); empty: 1 each.
  // `extra`: further regressors, each one value per unit (none: size and aux alone).
  // `certain`: per cluster, taken whole in the first round (take_all_clusters; empty: none).
  // Such a cluster is added as it is, not estimated: it is in no stratum, and the regression's
  // population is the other clusters' units. It is measured from its first unit on (it has no
  // warm-up: a measured cold start costs less than an estimated heavy one).
  TileSampler(std::vector<double> aux, const SamplingConfig& config, uint64_t stream,
              const std::vector<double>& size = {}, const std::vector<std::vector<double>>& extra = {},
              std::vector<bool> certain = {});

  uint64_t tiles() const { return m_tiles; }
  // Clusters in all and taken, the take-all ones included.
  uint64_t clusters() const { return m_all_clusters; }
  uint64_t clusters_taken() const { return m_taken + (m_certain_pending.empty() ? m_certain_count : 0); }
  uint64_t take_all() const { return m_certain_count; }
  bool is_take_all(uint64_t c) const { return m_certain[c]; }
  // Tile positions [begin, end) of cluster c in the scheduler's order.
  uint64_t cluster_begin(uint64_t c) const { return c * m_cfg.cluster_tiles; }
  uint64_t cluster_end(uint64_t c) const;

  uint64_t strata() const { return m_strata.size(); }
  uint64_t stratum_of(uint64_t c) const { return m_stratum_of[c]; }

  // The next round: `count` more clusters drawn at random within strata (without
  // replacement; two per stratum first, then Neyman allocation), and in the first round every
  // take-all cluster besides, ascending.
  std::vector<uint64_t> next_round(uint64_t count);

  // Observations: the occupancies of cluster c's tiles that were measured (not their core's
  // first in their round, not warm-up; their sum, and their size summed); each core's first
  // tile of a round as a fill. `aux` and `extra` (one per extra regressor): the auxiliary and
  // the extra regressors summed over the same tiles.
  // A take-all cluster's occupancies are added as they are (its regressors are not used).
  void observe_cluster(uint64_t c, double occupancy_sum, double size, double aux, const std::vector<double>& extra = {});
  void observe_fill(double cycles);

  RenderEstimate estimate(uint32_t cores) const;
  // Clusters needed in all (taken included) for a half-width of `target` cycles, from the
  // observed variance; at least one more than taken while any remain.
  uint64_t clusters_needed(double target, uint32_t cores) const;
  // The half-width's curve over the clusters taken, from the observed variance.
  VarianceCurve variance_curve(uint32_t cores) const;

 private:
  uint64_t m_tiles;
  uint64_t m_units = 0;     // the units of the clusters not taken whole
  double m_aux_total = 0;   // their auxiliary total
  double m_size_total = 0;  // and their size total
  SamplingConfig m_cfg;
  double m_z;
  struct Stratum {
    std::vector<uint64_t> order;  // its clusters in a random permutation
    uint64_t taken = 0;
  };
  std::vector<Stratum> m_strata;
  static constexpr uint32_t kTakeAll = ~uint32_t{0};
  std::vector<uint32_t> m_stratum_of;  // per cluster (kTakeAll: in none)
  std::vector<bool> m_certain;         // per cluster: taken whole
  std::vector<uint64_t> m_certain_pending;  // take-all clusters not yet drawn
  uint64_t m_all_clusters = 0, m_certain_count = 0;
  uint64_t m_clusters = 0, m_taken = 0;  // the stratified clusters: in all, taken
  std::vector<double> m_extra_total;  // per extra regressor: the population's total
  std::vector<double> m_y;             // per observed cluster: occupancy sum
  std::vector<std::vector<double>> m_reg;  // per observed cluster: size, auxiliary, extra regressors
  std::vector<uint32_t> m_h;          // per observed cluster: its stratum
  double m_fill_sum = 0, m_exact_sum = 0;
  uint64_t m_fills = 0;

  struct Fit {
    std::vector<double> coef; // y = coef . (m, x, z...) (m: size); 0 for a regressor left out
    size_t fitted = 0;        // regressors in the fit
    std::vector<double> s2;   // per stratum: the residuals' variance per cluster
    std::vector<uint64_t> n;  // per stratum: clusters observed
    bool variance_known = true;  // every stratum not fully observed has a variance
    double total = 0;         // Y = a M + b X
  };
  Fit fit(uint32_t cores) const;
  // sum_h K_h^2 (1 - n_h/K_h) s_h^2 / n_h for the fit's strata.
  double variance(const Fit& f) const;
};

}  // namespace tilevis::sim
