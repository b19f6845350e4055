#include "units/tile_scheduler/tile_scheduler.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include "visibility/zbuffer.h"

namespace tilevis::sim {
namespace {

uint64_t morton(uint32_t x, uint32_t y) {
  uint64_t m = 0;
  for (int b = 0; b < 32; ++b) m |= (uint64_t((x >> b) & 1) << (2 * b)) | (uint64_t((y >> b) & 1) << (2 * b + 1));
  return m;
}

}  // namespace

const char* to_string(Schedule s) {
  switch (s) {
    case Schedule::row_major: return "row_major";
    case Schedule::morton: return "morton";
    case Schedule::dynamic: return "dynamic";
  }
  return "?";
}

TileScheduler::TileScheduler(const sc_core::sc_module_name& name, const UnitEnv& env, const TileSchedulerConfig& config)
    : UnitBase(name, env, "tile scheduler: a segment's tiles to the tile cores, in order or to the first free core"),
      ready("ready"),
      to_core("to_core", config.cores),
      done("done", config.cores),
      released("released"),
      m_cfg(config) {
  for (uint32_t c = 0; c < config.cores; ++c)
    m_core_tiles.push_back(&m_stats.add("core" + std::to_string(c) + "_tiles", "tiles", "tiles given to core " + std::to_string(c)));
  SC_THREAD(dispatch);
  SC_THREAD(join);
}

std::vector<uint32_t> TileScheduler::order(const std::vector<uint32_t>& row_major) const {
  std::vector<uint32_t> v = row_major;
  if (m_cfg.policy != Schedule::row_major) {
    const geom::TileGrid& g = m_work.grid();
    std::stable_sort(v.begin(), v.end(), [&](uint32_t a, uint32_t b) {
      return morton(g.tile_x(a), g.tile_y(a)) < morton(g.tile_x(b), g.tile_y(b));
    });
  }
  return v;
}

void TileScheduler::count(uint32_t core) {
  m_core_tiles[core]->value += 1;
  m_items.value += 1;
}

uint32_t TileScheduler::free_core() {
  for (;;) {
    for (uint32_t c = 0; c < m_cfg.cores; ++c)
      if (to_core[c]->num_free() > 0) return c;
    sc_core::sc_event_or_list any;
    for (uint32_t c = 0; c < m_cfg.cores; ++c) any |= to_core[c]->data_read_event();
    const sc_core::sc_time t0 = sc_core::sc_time_stamp();
    sc_core::wait(any);
    m_stall.value += double(cycles(sc_core::sc_time_stamp() - t0));
  }
}

uint32_t TileScheduler::send(uint32_t segment, uint32_t tile, size_t i) {
  const uint32_t core = m_cfg.policy == Schedule::dynamic ? free_core() : static_core(i);
  Item it;
  it.segment = segment;
  it.tile = m_work.open_tile(tile);
  count(core);
  push(to_core[core], it);
  return core;
}

void TileScheduler::dispatch() {
  for (;;) {
    const uint32_t k = ready.read();
    m_work.prepare_segment(k);
    const std::vector<uint32_t> tiles = order(m_work.segment_tiles());
    if (m_cfg.sampled) {
      dispatch_sampled(k, tiles);
    } else {
      m_work.resolve_ahead(tiles);
      for (size_t i = 0; i < tiles.size(); ++i) send(k, tiles[i], i);
    }
    Item end;
    end.kind = Item::Kind::segment_end;
    end.segment = k;
    for (uint32_t c = 0; c < m_cfg.cores; ++c) push(to_core[c], end);
  }
}

void TileScheduler::dispatch_sampled(uint32_t segment, const std::vector<uint32_t>& tiles) {
  // The take-all stratum: heavy tiles (tile_sampler.h); the others are sampled in clusters.
  std::vector<double> work(tiles.size());
  for (size_t i = 0; i < tiles.size(); ++i)
    work[i] = tile_work(m_work.tile_triangle_count(tiles[i]), m_work.tile_edge_count(tiles[i]), m_cfg.sampling.reject_lanes);
  const size_t ct = m_cfg.sampling.cluster_tiles;
  // A tile's size: its pixels over a full tile's (the screen's right and bottom edges cut tiles).
  const geom::TileGrid& grid = m_work.grid();
  std::vector<double> size(tiles.size());
  for (size_t i = 0; i < tiles.size(); ++i) {
    const vis::zbuffer::PixelRect r = vis::zbuffer::tile_pixels(grid, tiles[i]);
    size[i] = double(r.x1 - r.x0) * double(r.y1 - r.y0) / (double(grid.tile_w) * double(grid.tile_h));
  }
  // The regressors beside size and work (tile_sampler.h): the binned triangles and the pairs
  // test 6 lets through.
  std::vector<std::vector<double>> extra(2, std::vector<double>(tiles.size()));
  for (size_t i = 0; i < tiles.size(); ++i) {
    extra[0][i] = double(m_work.tile_triangle_count(tiles[i]));
    extra[1][i] = double(m_work.tile_pair_tests(tiles[i]));
  }
  // Take-all: tiles whose work or whose pairs are more than sample_certainty times the mean (a
  // clip-bound tile of slivers, 242 triangles and 480 edges, has 12x the mean work and 33x the
  // mean pairs, and costs 120,240 cycles, as much as tiles of 200x the work).
  const std::vector<bool> certain_cluster = take_all_clusters(
      {work, extra[1]}, m_cfg.sampling.cluster_tiles, m_cfg.sampling.certainty_ratio, m_cfg.sampling.take_all_lead);
  TileSampler sampler(work, m_cfg.sampling, segment, size, extra, certain_cluster);
  SegmentSample rec;
  rec.segment = segment;
  for (size_t i = 0; i < tiles.size(); ++i) rec.certain_tiles += certain_cluster[i / ct];
  rec.start_cycle = cycles(sc_core::sc_time_stamp());
  const uint64_t warm = uint64_t(m_cfg.sampling.warm_tiles) * m_cfg.cores;
  // A segment of at most twice the first round's clusters is simulated whole, in one round:
  // the rounds' fills and warm-ups that a sample of it would leave to the estimate cost more
  // accuracy than the few tiles saved (elephant, 245 tiles in 8 rounds: -2.9 %).
  const uint64_t first = std::max<uint32_t>(1, m_cfg.sampling.first_clusters);
  const uint64_t stratified = sampler.clusters() - sampler.take_all();
  uint64_t want = stratified <= 2 * first ? stratified : first;
  bool first_round = true;
  const uint64_t geometry_before = m_geometry ? m_geometry->geometry_estimate().simulated : 0;
  for (;;) {
    if (want > 0 || first_round) {
      const std::vector<uint64_t> round = sampler.next_round(want);
      const uint64_t round_start = cycles(sc_core::sc_time_stamp());
      struct Sent {
        size_t pos;        // in the scheduler's order
        uint64_t cluster;
        bool warmup;       // simulated, not measured (detailed warming)
        uint32_t tile = 0, core = 0;
      };
      // This round's tiles in the scheduler's order (in the first round, every take-all cluster
      // too): the round's clusters come ascending.
      std::vector<Sent> sent;
      std::vector<bool> in_round(tiles.size(), false);
      for (uint64_t c : round)
        for (uint64_t q = sampler.cluster_begin(c); q < sampler.cluster_end(c); ++q) in_round[q] = true;
      for (uint64_t c : round) {
        // A sampled cluster that does not follow a tile of the round begins with its warm-up tiles.
        const uint64_t b = sampler.cluster_begin(c);
        const bool cold = !sampler.is_take_all(c) && b > 0 && !in_round[b - 1];
        for (uint64_t q = b; q < sampler.cluster_end(c); ++q) sent.push_back({q, c, cold && q - b < warm});
      }
      first_round = false;
      std::vector<uint32_t> ahead(sent.size());
      for (size_t i = 0; i < sent.size(); ++i) ahead[i] = tiles[sent[i].pos];
      m_work.resolve_ahead(ahead);
      for (size_t i = 0; i < sent.size(); ++i) {
        sent[i].tile = tiles[sent[i].pos];
        sent[i].core = send(segment, sent[i].tile, i);
        if (!sampler.is_take_all(sent[i].cluster))
          rec.cost += m_cfg.sampling.tile_triangle_cost * double(m_work.tile_triangle_count(sent[i].tile));
      }
      // The round ends when its last tile is written: every core empty again.
      for (const Sent& s : sent)
        while (!m_work.tile_closed(s.tile)) sc_core::wait(m_tile_closed);
      rec.simulated_render += cycles(sc_core::sc_time_stamp()) - round_start;
      ++rec.rounds;
      // Occupancies: a core's tiles end in the order it got them.
      std::vector<uint64_t> last(m_cfg.cores, round_start);
      std::vector<bool> started(m_cfg.cores, false);
      struct Sums {
        double y = 0, m = 0, x = 0;  // occupancy, size, work
        std::vector<double> z;       // the extra regressors
      };
      std::map<uint64_t, Sums> clusters;
      for (uint64_t c : round) clusters[c].z.assign(extra.size(), 0.0);
      for (const Sent& s : sent) {
        const uint64_t end = m_work.tile_end_cycle(s.tile);
        const double occupancy = double(end - last[s.core]);
        last[s.core] = end;
        if (!started[s.core]) {
          sampler.observe_fill(occupancy);
          started[s.core] = true;
        } else if (s.warmup) {
          ++rec.warmup_tiles;
        } else {
          Sums& v = clusters[s.cluster];
          v.y += occupancy;
          v.m += size[s.pos];
          v.x += work[s.pos];
          for (size_t k = 0; k < extra.size(); ++k) v.z[k] += extra[k][s.pos];
        }
      }
      for (const auto& [c, v] : clusters) sampler.observe_cluster(c, v.y, v.m, v.x, v.z);
      rec.estimate = sampler.estimate(m_cfg.cores);
    }
    // The whole segment in one round: simulated, not estimated.
    const bool whole = rec.estimate.complete && rec.rounds == 1;
    if (whole && !m_geometry) break;
    // The budget is a share of the frame: what is simulated before this segment, earlier
    // segments' corrections, this segment's render as estimated; the intervals already spent
    // (earlier segments) take their part of it, in quadrature.
    const double render = whole ? double(rec.simulated_render) : rec.estimate.cycles;
    const double frame_target = m_cfg.sampling.error_budget * frame_so_far(rec, geometry_before, render);
    double spent2 = 0;
    for (const SegmentSample& s : m_samples) spent2 += s.estimate.half_width * s.estimate.half_width;
    const double target = std::sqrt(std::max(frame_target * frame_target - spent2, 0.01 * frame_target * frame_target));
    const double render_half = whole ? 0.0 : rec.estimate.half_width;
    if (!m_geometry) {
      if (rec.estimate.complete || render_half <= target) break;
      want = sampler.clusters_needed(target, m_cfg.cores) - sampler.clusters_taken();
      continue;
    }
    // A sampled geometry shares the target with the render: the cheaper split of what remains.
    const double geometry_half = m_geometry->geometry_estimate().estimate.half_width;
    if (std::hypot(geometry_half, render_half) <= target) break;
    SampledPart r;
    r.curve = sampler.variance_curve(m_cfg.cores);
    r.taken = whole ? stratified : sampler.clusters_taken() - sampler.take_all();
    r.clusters = stratified;
    r.cost = r.taken ? rec.cost / double(r.taken) : 1.0;
    const SampledPart g = m_geometry->sampled_part();
    const std::vector<uint64_t> n = allocate({g, r}, target);
    want = n[1] - r.taken;
    // A geometry round between the render's, measured before the render goes on.
    auto grow_geometry = [&](uint64_t clusters) {
      m_geometry->grow(clusters);
      sc_core::wait(m_geometry->grown());
    };
    if (n[0] > g.taken) {
      grow_geometry(n[0] - g.taken);
    } else if (want == 0) {
      // Rounding kept both where they are: an eighth more of the wider one that can grow;
      // both complete: done.
      const bool geometry_first = g.taken < g.clusters && (geometry_half >= render_half || r.taken >= r.clusters);
      if (geometry_first) {
        grow_geometry(std::max<uint64_t>(1, g.taken / 8));
      } else if (r.taken < r.clusters) {
        want = std::max<uint64_t>(1, r.taken / 8);
      } else {
        break;
      }
    }
  }
  if (!(rec.estimate.complete && rec.rounds == 1)) m_correction += rec.estimate.cycles - double(rec.simulated_render);
  else rec.estimate.cycles = double(rec.simulated_render);
  m_samples.push_back(rec);
}

double TileScheduler::frame_so_far(const SegmentSample& rec, uint64_t geometry_simulated_before, double render) const {
  double before = double(rec.start_cycle) + m_correction;
  if (m_geometry) {
    const GeometryEstimate& g = m_geometry->geometry_estimate();
    before += g.estimate.cycles - double(geometry_simulated_before);
  }
  return before + render;
}

double TileScheduler::frame_estimate() const {
  double f = double(m_frame_end) + m_correction;
  if (m_geometry) f += m_geometry->geometry_estimate().estimate.cycles - double(m_geometry->geometry_estimate().simulated);
  return f;
}

double TileScheduler::frame_half_width() const {
  double v = 0;
  if (m_geometry) v += std::pow(m_geometry->geometry_estimate().estimate.half_width, 2);
  for (const SegmentSample& s : m_samples) v += s.estimate.half_width * s.estimate.half_width;
  return std::sqrt(v);
}

nlohmann::json TileScheduler::sampling_json() const {
  nlohmann::json segs = nlohmann::json::array();
  uint64_t tiles = 0, observed = 0;
  for (const SegmentSample& s : m_samples) {
    tiles += s.estimate.tiles;
    observed += s.estimate.tiles_observed;
    segs.push_back({{"segment", s.segment},
                    {"tiles", s.estimate.tiles},
                    {"tiles_simulated", s.estimate.tiles_observed},
                    {"tiles_taken_whole", s.certain_tiles},
                    {"tiles_warmup", s.warmup_tiles},
                    {"clusters", s.estimate.clusters},
                    {"clusters_simulated", s.estimate.clusters_observed},
                    {"rounds", s.rounds},
                    {"render_start_cycle", s.start_cycle},
                    {"render_simulated_cycles", s.simulated_render},
                    {"render_estimated_cycles", s.estimate.cycles},
                    {"half_width_cycles", s.estimate.half_width},
                    {"complete", s.estimate.complete}});
  }
  const double frame = frame_estimate(), half = frame_half_width();
  nlohmann::json geometry = nullptr;
  if (m_geometry) {
    const GeometryEstimate& g = m_geometry->geometry_estimate();
    const RenderEstimate& e = g.estimate;
    geometry = {{"triangles", e.tiles},
                {"triangles_simulated", e.tiles_observed},
                {"triangles_warmup", g.warmup},
                {"clusters", e.clusters},
                {"clusters_simulated", e.clusters_observed},
                {"rounds", g.rounds},
                {"rounds_before_render", g.rounds_before_render},
                {"simulated_cycles", g.simulated},
                {"estimated_cycles", e.cycles},
                {"half_width_cycles", e.half_width},
                {"complete", e.complete}};
  }
  return {{"help", "fidelity auto: each segment's render simulated on a random sample of clusters of consecutive tiles "
                   "(rounds grown until the interval fits the budget) and estimated; the geometry of a one-segment frame "
                   "likewise on clusters of consecutive trace triangles (\"geometry\"; null: simulated in full), the frame's "
                   "budget shared between the two where each cluster removes the most variance for its host cost"},
          {"geometry", geometry},
          {"tile_triangle_cost", m_cfg.sampling.tile_triangle_cost},
          {"error_budget", m_cfg.sampling.error_budget},
          {"confidence", m_cfg.sampling.confidence},
          {"cluster_tiles", m_cfg.sampling.cluster_tiles},
          {"warmup_tiles_per_core", m_cfg.sampling.warm_tiles},
          {"certainty_ratio", m_cfg.sampling.certainty_ratio},
          {"seed", m_cfg.sampling.seed},
          {"frame_cycles_simulated", m_frame_end},
          {"frame_cycles_estimated", frame},
          {"interval_cycles", {frame - half, frame + half}},
          {"relative_half_width", frame > 0 ? half / frame : 0.0},
          {"within_budget", frame <= 0 || half <= m_cfg.sampling.error_budget * frame},
          {"tiles", tiles},
          {"tiles_simulated", observed},
          {"segments", segs}};
}

void TileScheduler::join() {
  for (;;) {
    uint32_t k = 0;
    for (uint32_t c = 0; c < m_cfg.cores; ++c) k = done[c]->read();
    m_work.finish_segment();
    if (k + 1 == m_work.segment_count()) {
      m_frame_end = cycles(sc_core::sc_time_stamp());
      m_done = true;
    }
    released.write(k);
  }
}

}  // namespace tilevis::sim
