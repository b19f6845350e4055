#include "units/tile_scheduler/tile_sampler.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>

namespace tilevis::sim {

double normal_quantile(double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0)) throw std::invalid_argument("confidence must lie in (0, 1)");
  // P(|Z| <= z) = confidence: the upper (1 - confidence) / 2 quantile.
  return boost::math::quantile(boost::math::complement(boost::math::normal(), (1.0 - confidence) / 2));
}

double student_quantile(double confidence, double dof) {
  if (!(confidence > 0.0 && confidence < 1.0)) throw std::invalid_argument("confidence must lie in (0, 1)");
  if (!(dof >= 1.0)) throw std::invalid_argument("degrees of freedom must be at least 1");
  return boost::math::quantile(boost::math::complement(boost::math::students_t(dof), (1.0 - confidence) / 2));
}

std::vector<bool> take_all_clusters(const std::vector<std::vector<double>>& aux, uint32_t cluster, double ratio,
                                    uint32_t lead) {
  if (cluster == 0) throw std::invalid_argument("sampling: cluster_tiles must be at least 1");
  const size_t units = aux.empty() ? 0 : aux.front().size();
  const size_t n = (units + cluster - 1) / cluster;
  std::vector<bool> heavy(n, false);
  for (const std::vector<double>& a : aux) {
    if (a.size() != units) throw std::invalid_argument("sampling: one value of each auxiliary per unit");
    double mean = 0;
    for (double v : a) mean += v;
    mean /= double(std::max<size_t>(units, 1));
    for (size_t i = 0; i < units; ++i)
      if (a[i] > ratio * mean) heavy[i / cluster] = true;
  }
  std::vector<bool> certain = heavy;
  for (size_t c = 1; c < n; ++c)
    if (heavy[c] && !heavy[c - 1])
      for (size_t k = 1; k <= lead && k <= c; ++k) certain[c - k] = true;
  return certain;
}

TileSampler::TileSampler(std::vector<double> aux, const SamplingConfig& config, uint64_t stream,
                         const std::vector<double>& size, const std::vector<std::vector<double>>& extra,
                         std::vector<bool> certain)
    : m_tiles(aux.size()), m_cfg(config), m_z(normal_quantile(config.confidence)), m_certain(std::move(certain)) {
  if (config.cluster_tiles == 0) throw std::invalid_argument("sampling: cluster_tiles must be at least 1");
  if (!size.empty() && size.size() != aux.size()) throw std::invalid_argument("sampling: one size per unit");
  for (const std::vector<double>& z : extra)
    if (z.size() != aux.size()) throw std::invalid_argument("sampling: one value of each extra regressor per unit");
  m_all_clusters = (m_tiles + config.cluster_tiles - 1) / config.cluster_tiles;
  if (m_certain.empty()) m_certain.assign(m_all_clusters, false);
  if (m_certain.size() != m_all_clusters) throw std::invalid_argument("sampling: one take-all flag per cluster");
  // The population the regression estimates: the units of the clusters not taken whole.
  m_extra_total.assign(extra.size(), 0.0);
  for (uint64_t c = 0; c < m_all_clusters; ++c) {
    if (m_certain[c]) {
      m_certain_pending.push_back(c);
      continue;
    }
    for (uint64_t p = cluster_begin(c); p < cluster_end(c); ++p) {
      ++m_units;
      m_aux_total += aux[p];
      m_size_total += size.empty() ? 1.0 : size[p];
      for (size_t k = 0; k < extra.size(); ++k) m_extra_total[k] += extra[k][p];
    }
  }
  m_certain_count = m_certain_pending.size();
  m_clusters = m_all_clusters - m_certain_count;
  // Strata: the clusters sorted by their auxiliary (ties by position), cut where the running
  // total of (auxiliary + tiles) passes each equal share, at least two clusters a stratum:
  // a few heavy clusters get strata of their own instead of hiding among light ones.
  std::vector<double> x(m_all_clusters, 0.0);
  std::vector<uint64_t> by_x;
  for (uint64_t c = 0; c < m_all_clusters; ++c) {
    if (m_certain[c]) continue;
    for (uint64_t p = cluster_begin(c); p < cluster_end(c); ++p) x[c] += aux[p];
    by_x.push_back(c);
  }
  std::stable_sort(by_x.begin(), by_x.end(), [&](uint64_t a, uint64_t b) { return x[a] < x[b]; });
  const uint64_t h_count = std::max<uint64_t>(1, std::min<uint64_t>(std::max<uint32_t>(1, config.strata), m_clusters / 2));
  m_strata.resize(m_clusters ? h_count : 0);
  m_stratum_of.assign(m_all_clusters, kTakeAll);
  double total = 0;
  for (uint64_t c : by_x) total += x[c] + double(cluster_end(c) - cluster_begin(c));
  double running = 0;
  uint32_t h = 0;
  for (uint64_t i = 0; i < m_clusters; ++i) {
    const uint64_t c = by_x[i];
    // Close stratum h when it has its share and two clusters, and enough remain for the rest.
    const uint64_t in_h = m_strata[h].order.size(), left = m_clusters - i;
    if (h + 1 < h_count && in_h >= 2 && running >= total * double(h + 1) / double(h_count) &&
        left >= 2 * (h_count - h - 1))
      ++h;
    m_stratum_of[c] = h;
    m_strata[h].order.push_back(c);
    running += x[c] + double(cluster_end(c) - cluster_begin(c));
  }
  while (!m_strata.empty() && m_strata.back().order.empty()) m_strata.pop_back();
  // Fisher-Yates with the generator's raw output: the same permutation on every platform
  // (std::shuffle's and the distributions' algorithms are the library's choice).
  std::mt19937_64 rng(config.seed * 0x9e3779b97f4a7c15ull + stream);
  for (Stratum& st : m_strata) {
    std::sort(st.order.begin(), st.order.end());
    for (uint64_t i = st.order.size(); i > 1; --i) std::swap(st.order[i - 1], st.order[rng() % i]);
  }
}

uint64_t TileSampler::cluster_end(uint64_t c) const {
  return std::min<uint64_t>(m_tiles, (c + 1) * m_cfg.cluster_tiles);
}

std::vector<uint64_t> TileSampler::next_round(uint64_t count) {
  count = std::min<uint64_t>(count, m_clusters - m_taken);
  // Allocation weights: K_h s_h once every stratum has a variance, else K_h (proportional).
  const Fit f = fit(1);
  std::vector<double> w(m_strata.size());
  bool neyman = f.variance_known;
  for (size_t h = 0; h < m_strata.size(); ++h) {
    neyman = neyman && f.n[h] >= 2;
    w[h] = double(m_strata[h].order.size());
  }
  double sw = 0;
  if (neyman) {
    for (size_t h = 0; h < m_strata.size(); ++h) sw += w[h] * std::sqrt(f.s2[h]);
    if (sw > 0)
      for (size_t h = 0; h < m_strata.size(); ++h) w[h] *= std::sqrt(f.s2[h]);
  }
  // Greedy: each next cluster to the open stratum with fewer than two, else the largest
  // weight per cluster taken (w_h / (n_h + 1)); ties to the lower stratum.
  std::vector<uint64_t> take(m_strata.size(), 0);
  for (uint64_t k = 0; k < count; ++k) {
    size_t best = m_strata.size();
    double best_score = -1;
    for (size_t h = 0; h < m_strata.size(); ++h) {
      const uint64_t n = m_strata[h].taken + take[h];
      if (n >= m_strata[h].order.size()) continue;
      const double score = n < 2 ? 1e300 / double(n + 1) : w[h] / double(n + 1);
      if (score > best_score) best = h, best_score = score;
    }
    if (best == m_strata.size()) break;
    ++take[best];
  }
  std::vector<uint64_t> r = std::move(m_certain_pending);
  m_certain_pending.clear();
  for (size_t h = 0; h < m_strata.size(); ++h) {
    Stratum& st = m_strata[h];
    r.insert(r.end(), st.order.begin() + int64_t(st.taken), st.order.begin() + int64_t(st.taken + take[h]));
    st.taken += take[h];
    m_taken += take[h];
  }
  std::sort(r.begin(), r.end());
  return r;
}

void TileSampler::observe_cluster(uint64_t c, double occupancy_sum, double size, double aux,
                                  const std::vector<double>& extra) {
  if (extra.size() != m_extra_total.size()) throw std::invalid_argument("sampling: one sum per extra regressor");
  if (m_certain.at(c)) {
    m_exact_sum += occupancy_sum;
    return;
  }
  m_y.push_back(occupancy_sum);
  m_reg.push_back({size, aux});
  m_reg.back().insert(m_reg.back().end(), extra.begin(), extra.end());
  m_h.push_back(m_stratum_of.at(c));
}

void TileSampler::observe_fill(double cycles) {
  m_fill_sum += cycles;
  ++m_fills;
}

TileSampler::Fit TileSampler::fit(uint32_t cores) const {
  Fit f;
  const size_t n = m_y.size(), hn = m_strata.size();
  f.n.assign(hn, 0);
  f.s2.assign(hn, 0.0);
  for (uint32_t h : m_h) ++f.n[h];
  // Design weights K_h / n_h.
  std::vector<double> d(hn, 0.0);
  for (size_t h = 0; h < hn; ++h) d[h] = f.n[h] ? double(m_strata[h].order.size()) / double(f.n[h]) : 0.0;
  // Weighted least squares on the regressors in order (size, auxiliary, extras), at most one
  // fewer than the clusters observed; a regressor is left out where the ones before it span
  // it (its Cholesky pivot under 1e-9 of its own weight: proportional auxiliaries, per-pixel
  // modes' work = triangles, a column of zeros).
  const size_t p_all = 2 + m_extra_total.size();
  const size_t p = n >= 2 ? std::min(p_all, n - 1) : 1;
  std::vector<std::vector<double>> g(p, std::vector<double>(p, 0.0));
  std::vector<double> r(p, 0.0);
  for (size_t j = 0; j < n; ++j) {
    const double wj = d[m_h[j]];
    for (size_t k = 0; k < p; ++k) {
      r[k] += wj * m_reg[j][k] * m_y[j];
      for (size_t l = 0; l < p; ++l) g[k][l] += wj * m_reg[j][k] * m_reg[j][l];
    }
  }
  std::vector<size_t> used;
  std::vector<std::vector<double>> chol;  // lower-triangular rows over `used`
  for (size_t k = 0; k < p; ++k) {
    std::vector<double> row(used.size() + 1, 0.0);
    double pivot = g[k][k];
    for (size_t i = 0; i < used.size(); ++i) {
      double v = g[k][used[i]];
      for (size_t q = 0; q < i; ++q) v -= row[q] * chol[i][q];
      row[i] = v / chol[i][i];
      pivot -= row[i] * row[i];
    }
    if (!(g[k][k] > 0) || !(pivot > 1e-9 * g[k][k])) continue;
    row.back() = std::sqrt(pivot);
    chol.push_back(std::move(row));
    used.push_back(k);
  }
  std::vector<double> u(used.size());
  for (size_t i = 0; i < used.size(); ++i) {  // L u = r
    double v = r[used[i]];
    for (size_t q = 0; q < i; ++q) v -= chol[i][q] * u[q];
    u[i] = v / chol[i][i];
  }
  f.coef.assign(p_all, 0.0);
  for (size_t i = used.size(); i-- > 0;) {  // L^T beta = u
    double v = u[i];
    for (size_t q = i + 1; q < used.size(); ++q) v -= chol[q][i] * f.coef[used[q]];
    f.coef[used[i]] = v / chol[i][i];
  }
  f.fitted = used.size();
  auto residual = [&](size_t j) {
    double e = m_y[j];
    for (size_t k = 0; k < p_all; ++k) e -= f.coef[k] * m_reg[j][k];
    return e;
  };
  // Per stratum: the residuals' variance about their stratum mean.
  std::vector<double> sum(hn, 0.0), sum2(hn, 0.0);
  double pooled = 0;
  uint64_t pooled_dof = 0;
  for (size_t j = 0; j < n; ++j) {
    const double e = residual(j);
    sum[m_h[j]] += e;
    sum2[m_h[j]] += e * e;
  }
  // Each regressor fitted beyond size and auxiliary takes a degree of freedom from the
  // residuals: their variances are scaled by (n - 2) / (n - fitted).
  const double inflate = f.fitted > 2 && n > f.fitted ? double(n - 2) / double(n - f.fitted) : 1.0;
  for (size_t h = 0; h < hn; ++h)
    if (f.n[h] >= 2) {
      const double ss = std::max(0.0, sum2[h] - sum[h] * sum[h] / double(f.n[h])) * inflate;
      f.s2[h] = ss / double(f.n[h] - 1);
      pooled += ss;
      pooled_dof += f.n[h] - 1;
    }
  // Two or three clusters a stratum estimate its variance loosely, and two alike (a scene's
  // empty tiles) claim none at all though the stratum's unseen clusters differ: an open
  // stratum's variance is at least the pooled one (collapsed strata: Cochran, Sampling
  // Techniques, 5A.12). Over seeds 1-8 on the 15 built-in scenes the interval held the
  // primitive level in 78 of 120 runs without this floor, 91 with it. A stratum with one
  // cluster observed (of more) takes the pooled variance; with none, nothing bounds it.
  const double pooled_s2 = pooled_dof > 0 ? pooled / double(pooled_dof) : 0.0;
  for (size_t h = 0; h < hn; ++h) {
    if (f.n[h] >= m_strata[h].order.size()) continue;
    if (f.n[h] >= 2) f.s2[h] = std::max(f.s2[h], pooled_s2);
    else if (f.n[h] == 1 && pooled_dof > 0) f.s2[h] = pooled_s2;
    else f.variance_known = false;
  }
  // The population's size and auxiliary less the cores' first tiles' (average tiles: their
  // cost is the fill).
  const double c = std::min<double>(std::max<uint32_t>(cores, 1), double(m_units));
  const double share = m_units ? (double(m_units) - c) / double(m_units) : 0.0;
  std::vector<double> totals = {m_size_total, m_aux_total};
  totals.insert(totals.end(), m_extra_total.begin(), m_extra_total.end());
  // The generalised regression estimator: the fit's prediction plus the residuals expanded
  // by their design weights (zero where the model holds; it corrects a misspecified model).
  double residual_total = 0;
  for (size_t j = 0; j < n; ++j) residual_total += d[m_h[j]] * residual(j);
  f.total = residual_total;
  for (size_t k = 0; k < p_all; ++k) f.total += f.coef[k] * totals[k] * share;
  return f;
}

double TileSampler::variance(const Fit& f) const {
  double v = 0;
  for (size_t h = 0; h < m_strata.size(); ++h) {
    const double k = double(m_strata[h].order.size()), n = double(f.n[h]);
    if (n > 0 && n < k) v += k * k * (1.0 - n / k) * f.s2[h] / n;
  }
  return v;
}

RenderEstimate TileSampler::estimate(uint32_t cores) const {
  RenderEstimate e;
  e.tiles = m_tiles;
  e.clusters = m_all_clusters;
  e.clusters_observed = clusters_taken();
  for (const Stratum& st : m_strata)
    for (uint64_t i = 0; i < st.taken; ++i) e.tiles_observed += cluster_end(st.order[i]) - cluster_begin(st.order[i]);
  if (m_certain_pending.empty())
    for (uint64_t c = 0; c < m_all_clusters; ++c)
      if (m_certain[c]) e.tiles_observed += cluster_end(c) - cluster_begin(c);
  e.complete = clusters_taken() == m_all_clusters;
  const Fit f = fit(cores);
  const double fill = m_fills ? m_fill_sum / double(m_fills) : 0.0;
  const double per_core = 1.0 / double(std::max<uint32_t>(cores, 1));
  e.cycles = fill + (std::max(0.0, f.total) + m_exact_sum) * per_core;
  if (!e.complete && m_y.size() >= 3 && f.variance_known) {
    // Student's t on the residuals' degrees of freedom: two to four clusters a stratum
    // estimate its variance loosely (the normal quantile covered 85 % at 95 % nominal).
    const double dof = std::max(1.0, double(m_y.size()) - double(m_strata.size()) - double(f.fitted > 2 ? f.fitted - 2 : 0));
    e.half_width = student_quantile(m_cfg.confidence, dof) * per_core * std::sqrt(variance(f));
  } else if (!e.complete) {
    e.half_width = e.cycles;  // too few observations to bound anything
  }
  return e;
}

VarianceCurve TileSampler::variance_curve(uint32_t cores) const {
  VarianceCurve v;
  const Fit f = fit(cores);
  v.known = m_y.size() >= 3 && f.variance_known;
  if (!v.known) return v;
  // Neyman allocation: V(n) = (sum K_h s_h)^2 / n - sum K_h s_h^2, on the estimate's scale
  // (the normal quantile: Student's t at today's few degrees of freedom would ask for far
  // more than the next round needs; the rounds grow until the t interval fits).
  const double scale = m_z / double(std::max<uint32_t>(cores, 1));
  for (size_t h = 0; h < m_strata.size(); ++h) {
    const double kh = double(m_strata[h].order.size()), sh = std::sqrt(f.s2[h]);
    v.a += kh * sh;
    v.b += kh * sh * sh;
  }
  v.a *= v.a * scale * scale;
  v.b *= scale * scale;
  return v;
}

uint64_t TileSampler::clusters_needed(double target, uint32_t cores) const {
  SampledPart p;
  p.curve = variance_curve(cores);
  p.taken = m_taken;
  p.clusters = m_clusters;
  if (m_taken >= m_clusters) return m_all_clusters;
  return m_certain_count + std::max<uint64_t>(allocate({p}, target).front(), m_taken + 1);
}

std::vector<uint64_t> allocate(const std::vector<SampledPart>& parts, double target) {
  const size_t n = parts.size();
  std::vector<double> at(n);
  std::vector<bool> held(n, false);
  for (size_t i = 0; i < n; ++i) {
    const SampledPart& p = parts[i];
    at[i] = double(p.taken);
    if (p.taken >= p.clusters) {
      held[i] = true;
    } else if (!p.curve.known) {
      at[i] = double(std::min<uint64_t>(p.clusters, std::max<uint64_t>(p.taken + 3, 2 * p.taken)));
      held[i] = true;
    } else if (p.curve.a <= 0) {
      held[i] = true;  // no variance left to remove
    }
  }
  // The variance of a held part at its clusters (none once it is complete or unbounded).
  auto var = [&](size_t i, double k) {
    const SampledPart& p = parts[i];
    return k >= double(p.clusters) || !p.curve.known ? 0.0 : std::max(0.0, p.curve.a / k - p.curve.b);
  };
  const double v = target > 0 ? target * target : 0.0;
  for (bool again = true; again;) {
    again = false;
    double budget = v, sum = 0;
    for (size_t i = 0; i < n; ++i) {
      if (held[i]) {
        budget -= var(i, at[i]);
      } else {
        budget += parts[i].curve.b;
        sum += std::sqrt(parts[i].curve.a * std::max(parts[i].cost, 1e-12));
      }
    }
    for (size_t i = 0; i < n; ++i) {
      if (held[i]) continue;
      const SampledPart& p = parts[i];
      const double want = budget > 0 ? std::sqrt(p.curve.a / std::max(p.cost, 1e-12)) * sum / budget : double(p.clusters);
      if (want <= double(p.taken) || want >= double(p.clusters)) {
        at[i] = want <= double(p.taken) ? double(p.taken) : double(p.clusters);
        held[i] = again = true;
        break;  // solve the others again without it
      }
      at[i] = want;
    }
  }
  std::vector<uint64_t> r(n);
  double total = 0;
  bool grows = false;
  for (size_t i = 0; i < n; ++i) {
    r[i] = std::min<uint64_t>(parts[i].clusters, uint64_t(std::ceil(at[i] - 1e-9)));
    grows = grows || r[i] > parts[i].taken;
    total += var(i, double(parts[i].taken));
  }
  if (!grows && total > v) {
    // Rounding left the parts where they are: one more cluster where it removes the most
    // variance for its cost.
    size_t best = n;
    double best_gain = -1;
    for (size_t i = 0; i < n; ++i) {
      const SampledPart& p = parts[i];
      if (p.taken >= p.clusters) continue;
      const double k = double(p.taken);
      const double gain = (k > 0 && p.curve.known ? var(i, k) - var(i, k + 1) : 1e300) / std::max(p.cost, 1e-12);
      if (gain > best_gain) best = i, best_gain = gain;
    }
    if (best < n) ++r[best];
  }
  return r;
}

}  // namespace tilevis::sim
