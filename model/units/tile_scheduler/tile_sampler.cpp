#include "units/tile_scheduler/tile_sampler.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace tilevis::sim {

double normal_quantile(double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0)) throw std::invalid_argument("confidence must lie in (0, 1)");
  // P(|Z| <= z) = erf(z / sqrt 2): bisection on a monotone function, to double precision.
  double lo = 0.0, hi = 40.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::erf(mid / std::sqrt(2.0)) < confidence ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

TileSampler::TileSampler(std::vector<double> triangles, const SamplingConfig& config, uint64_t stream)
    : m_tiles(triangles.size()), m_cfg(config), m_z(normal_quantile(config.confidence)) {
  if (config.cluster_tiles == 0) throw std::invalid_argument("sampling: cluster_tiles must be at least 1");
  for (double t : triangles) m_triangles += t;
  const uint64_t k = (m_tiles + config.cluster_tiles - 1) / config.cluster_tiles;
  m_order.resize(k);
  for (uint64_t i = 0; i < k; ++i) m_order[i] = i;
  // Fisher-Yates with the generator's raw output: the same permutation on every platform
  // (std::shuffle's and the distributions' algorithms are the library's choice).
  std::mt19937_64 rng(config.seed * 0x9e3779b97f4a7c15ull + stream);
  for (uint64_t i = k; i > 1; --i) std::swap(m_order[i - 1], m_order[rng() % i]);
}

uint64_t TileSampler::cluster_end(uint64_t c) const {
  return std::min<uint64_t>(m_tiles, (c + 1) * m_cfg.cluster_tiles);
}

std::vector<uint64_t> TileSampler::next_round(uint64_t count) {
  count = std::min<uint64_t>(count, m_order.size() - m_taken);
  std::vector<uint64_t> r(m_order.begin() + int64_t(m_taken), m_order.begin() + int64_t(m_taken + count));
  m_taken += count;
  std::sort(r.begin(), r.end());
  return r;
}

void TileSampler::observe_cluster(double occupancy_sum, uint64_t tiles_observed, double triangles) {
  m_y.push_back(occupancy_sum);
  m_m.push_back(double(tiles_observed));
  m_x.push_back(triangles);
}

void TileSampler::observe_exact(double cycles) { m_exact_sum += cycles; }

void TileSampler::observe_fill(double cycles) {
  m_fill_sum += cycles;
  ++m_fills;
}

TileSampler::Fit TileSampler::fit(uint32_t cores) const {
  Fit f;
  const size_t n = m_y.size();
  double mm = 0, mx = 0, xx = 0, my = 0, xy = 0;
  for (size_t j = 0; j < n; ++j) {
    mm += m_m[j] * m_m[j];
    mx += m_m[j] * m_x[j];
    xx += m_x[j] * m_x[j];
    my += m_m[j] * m_y[j];
    xy += m_x[j] * m_y[j];
  }
  const double det = mm * xx - mx * mx;
  size_t params = 2;
  if (n >= 3 && det > 1e-9 * mm * xx) {
    f.a = (my * xx - xy * mx) / det;
    f.b = (xy * mm - my * mx) / det;
  } else {  // the auxiliaries are proportional (or too few clusters): a ratio to the tile count
    f.a = mm > 0 ? my / mm : 0.0;
    params = 1;
  }
  double e2 = 0;
  for (size_t j = 0; j < n; ++j) {
    const double e = m_y[j] - f.a * m_m[j] - f.b * m_x[j];
    e2 += e * e;
  }
  f.s2 = n > params ? e2 / double(n - params) : 0.0;
  // The population's tiles and triangles less the cores' first tiles (their cost is the fill).
  const double c = std::min<double>(std::max<uint32_t>(cores, 1), double(m_tiles));
  const double tiles = double(m_tiles) - c;
  const double triangles = m_tiles ? m_triangles * tiles / double(m_tiles) : 0.0;
  f.total = f.a * tiles + f.b * triangles;
  return f;
}

RenderEstimate TileSampler::estimate(uint32_t cores) const {
  RenderEstimate e;
  e.tiles = m_tiles;
  e.clusters = m_order.size();
  e.clusters_observed = m_taken;
  for (uint64_t i = 0; i < m_taken; ++i) {
    const uint64_t c = m_order[i];
    e.tiles_observed += cluster_end(c) - cluster_begin(c);
  }
  e.complete = m_taken == m_order.size();
  const Fit f = fit(cores);
  const double fill = m_fills ? m_fill_sum / double(m_fills) : 0.0;
  const double per_core = 1.0 / double(std::max<uint32_t>(cores, 1));
  e.cycles = fill + (std::max(0.0, f.total) + m_exact_sum) * per_core;
  const size_t n = m_y.size();
  const double k = double(m_order.size());
  if (!e.complete && n >= 3) {
    const double fpc = 1.0 - double(n) / k;
    e.half_width = m_z * per_core * k * std::sqrt(std::max(0.0, fpc * f.s2 / double(n)));
  } else if (!e.complete) {
    e.half_width = e.cycles;  // too few observations to bound anything
  }
  return e;
}

uint64_t TileSampler::clusters_needed(double target, uint32_t cores) const {
  const uint64_t k = m_order.size();
  if (m_taken >= k) return k;
  const size_t n = m_y.size();
  if (n < 3) return std::min<uint64_t>(k, std::max<uint64_t>(m_taken + 3, 2 * m_taken));
  const double s2 = fit(cores).s2;
  const double a = m_z * double(k) / double(std::max<uint32_t>(cores, 1));
  if (s2 <= 0) return std::min<uint64_t>(k, m_taken + 1);
  // (1/n - 1/K) * a^2 * s2 <= target^2  <=>  n >= 1 / (target^2 / (a^2 s2) + 1/K)
  const double need = target > 0 ? 1.0 / (target * target / (a * a * s2) + 1.0 / double(k)) : double(k);
  const uint64_t n_need = uint64_t(std::ceil(need));
  return std::min<uint64_t>(k, std::max<uint64_t>(n_need, m_taken + 1));
}

}  // namespace tilevis::sim
