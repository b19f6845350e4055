#include "units/common/frame_work.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <future>
#include <numeric>
#include <span>
#include <stdexcept>
#include <string>

#include <systemc>

#include "units/early_visibility_unit/rtl_evu.h"
#include "visibility/parallel.h"
#include "visibility/evu_jobs.h"

namespace tilevis::sim {

const char* to_string(Mode m) {
  switch (m) {
    case Mode::analytic: return "analytic";
    case Mode::hybrid: return "hybrid";
    case Mode::hsr: return "hsr";
    case Mode::early_z: return "early_z";
    case Mode::none: return "none";
  }
  return "?";
}

const char* to_string(Fidelity f) {
  switch (f) {
    case Fidelity::analytic: return "analytic";
    case Fidelity::tile: return "tile";
    case Fidelity::primitive: return "primitive";
    case Fidelity::rtl: return "rtl";
    case Fidelity::automatic: return "auto";
  }
  return "?";
}

const char* column_name(TileUnit u) {
  switch (u) {
    case TileUnit::fetch: return "cycles_tile_fetch";
    case TileUnit::reject: return "cycles_evu_reject";
    case TileUnit::clip: return "cycles_evu_clip";
    case TileUnit::occlude: return "cycles_evu_occlude";
    case TileUnit::hsr: return "cycles_hsr";
    case TileUnit::fragment: return "cycles_fragment";
    case TileUnit::writer: return "cycles_tile_writer";
    case TileUnit::count: break;
  }
  return "?";
}

namespace {

bool unit_present(TileUnit u, Mode m) {
  switch (u) {
    case TileUnit::reject:
    case TileUnit::clip:
    case TileUnit::occlude: return uses_evu(m);
    case TileUnit::hsr: return uses_hsr(m);
    default: return true;
  }
}

struct EdgeKey {
  uint32_t draw;
  geom::Vertex a, b;  // a < b lexicographically
  bool operator==(const EdgeKey&) const = default;
};
struct EdgeKeyHash {
  size_t operator()(const EdgeKey& k) const {
    uint64_t h = k.draw * 0x9e3779b97f4a7c15ull;
    for (int32_t v : {k.a.x, k.a.y, int32_t(k.a.z), k.b.x, k.b.y, int32_t(k.b.z)})
      h = (h ^ uint32_t(v)) * 0x100000001b3ull;
    return size_t(h);
  }
};
EdgeKey edge_key(uint32_t draw, geom::Vertex a, geom::Vertex b) {
  auto less = [](const geom::Vertex& p, const geom::Vertex& q) {
    return p.x != q.x ? p.x < q.x : p.y != q.y ? p.y < q.y : p.z < q.z;
  };
  if (less(b, a)) std::swap(a, b);
  return {draw, a, b};
}

}  // namespace

// One segment's functional state. With one segment it borrows the frame's golden tiler.
struct FrameWork::Segment {
  uint32_t index = 0;
  uint32_t setup_first = 0, setup_end = 0;  // range of the frame's setup triangles
  std::unique_ptr<vis::Setup> setup;        // own setup (analytic, several segments)
  std::unique_ptr<vis::GoldenResult> result;
  std::unique_ptr<vis::GoldenTiler> tiler;
  const vis::Setup* s = nullptr;            // the setup the tile lists index
  vis::GoldenTiler* golden = nullptr;       // analytic mode
  std::vector<std::unique_ptr<TileWork>> open;
};

class FrameWork::HostTime {
 public:
  HostTime(double& total, int& depth) : m_total(total), m_depth(depth), m_outer(depth++ == 0) {
    if (m_outer) m_t0 = std::chrono::steady_clock::now();
  }
  ~HostTime() {
    --m_depth;
    if (m_outer) m_total += std::chrono::duration<double>(std::chrono::steady_clock::now() - m_t0).count();
  }
  HostTime(const HostTime&) = delete;
  HostTime& operator=(const HostTime&) = delete;

 private:
  double& m_total;
  int& m_depth;
  bool m_outer;
  std::chrono::steady_clock::time_point m_t0;
};

FrameWork::FrameWork(const trace::Frame& frame, const FrameWorkConfig& config,
                     std::unique_ptr<FunctionalRecord> replay)
    : m_frame(frame), m_cfg(config) {
  m_trace_triangles = uint32_t(frame.triangle_count());
  if (replay || config.record) {
    if (config.rtl)
      throw std::invalid_argument("sim.functional_record: fidelity rtl takes the EVU's clocks from the Verilated RTL, "
                                  "which needs the computed tiles; run it without a record");
    if (!config.key) throw std::logic_error("FrameWork: recording or replaying needs the record's key (FrameWorkConfig::key)");
    m_rec.key = *config.key;
  }
  if (replay) {
    const std::string differ = key_differences(replay->key, m_rec.key);
    if (!differ.empty()) throw std::runtime_error("the functional record is of another frame or configuration: " + differ);
    m_rec = std::move(*replay);
    m_replay = true;
  }
  m_gcfg.tile_w = config.tile_w;
  m_gcfg.tile_h = config.tile_h;
  m_gcfg.mode = uses_evu(config.mode) ? to_string(config.mode) : "per_pixel";
  m_gcfg.options.pair_budget = config.hybrid_pair_budget;
  m_gcfg.options.detection_bin = config.detection_bin;
  m_gcfg.options.list_triangles = config.evu_triangle_entries;
  m_gcfg.options.list_edges = config.evu_edge_entries;
  m_grid = geom::TileGrid::make(frame.width, frame.height, config.tile_w, config.tile_h, frame.subpixel_bits);
  if (uses_evu(m_cfg.mode)) {
    m_columns = vis::TileCounters::columns();
    for (const char* c : {"fragments_shaded", "depth_tests", "passes", "segments"}) m_columns.push_back(c);
    // The resolver's own columns (hybrid: per_pixel, per_pixel_cause, detection_tests).
    for (const std::string& c : vis::make_tile_resolver(m_gcfg.mode, {})->extra_columns()) m_columns.push_back(c);
  } else {
    m_columns = {"triangles", "fragments_generated", "samples_covered", "fragments_shaded", "depth_tests", "segments"};
  }
  m_cycles_col = m_columns.size();
  for (size_t u = 0; u < size_t(TileUnit::count); ++u)
    if (unit_present(TileUnit(u), m_cfg.mode)) m_columns.push_back(column_name(TileUnit(u)));
  m_columns.push_back("tile_cycles");
  if (m_cfg.sampled) {
    m_simulated_col = m_columns.size();
    m_columns.push_back("simulated");
  }
  m_tile_end.assign(m_grid.tile_count(), 0);
  m_closed_in.assign(m_grid.tile_count(), 0);
  m_rows.assign(m_grid.tile_count(), std::vector<int64_t>(m_columns.size(), 0));
  m_stored.assign(m_rows.size(), false);
}

FrameWork::~FrameWork() = default;

void FrameWork::run_setup() {
  const HostTime timed(m_functional_s, m_functional_depth);
  if (m_replay) {
    if (m_setup_begin.size() != size_t(m_trace_triangles) + 1 || m_setup.triangle_draw.size() != m_trace_triangles)
      throw std::runtime_error("the functional record's setup does not fit the frame's " +
                               std::to_string(m_trace_triangles) + " triangles");
    return;
  }
  m_setup = vis::primitive_setup(m_frame, {m_cfg.depth_bits});
  m_setup_begin.assign(size_t(m_trace_triangles) + 1, 0);
  for (const vis::SetupTriangle& t : m_setup.triangles) ++m_setup_begin[t.id + 1];
  for (size_t i = 1; i < m_setup_begin.size(); ++i) m_setup_begin[i] += m_setup_begin[i - 1];
}

void FrameWork::run_binning() {
  const HostTime timed(m_functional_s, m_functional_depth);
  m_full.width = m_setup.width;
  m_full.height = m_setup.height;
  m_full.samples = samples();
  if (m_replay) {
    // The outputs replayed tiles write, sized as golden's tiler sizes them.
    m_full.ids.assign(size_t(m_setup.width) * m_setup.height * m_setup.samples.size(), -1);
    m_full.visible_area.assign(m_setup.triangle_draw.size(), 0.0);
    if (m_tri_refs.size() != m_setup.triangles.size() || m_edge_refs.size() != m_setup.silhouettes.size() ||
        m_owned_begin.size() != size_t(m_trace_triangles) + 1)
      throw std::runtime_error("the functional record's binning does not fit its setup");
    return;
  }
  // Edge owners: the first front-facing triangle of the draw with the edge as one of its own.
  // They read the setup alone: on a host with a second core they are found beside the binning.
  auto find_owners = [this] {
    const size_t n_edges = m_setup.silhouettes.size();
    std::vector<uint32_t> owner(n_edges, kNone);
    if (uses_evu(m_cfg.mode) && n_edges > 0) {
      std::unordered_map<EdgeKey, uint32_t, EdgeKeyHash> by_key;
      by_key.reserve(n_edges * 2);
      // A bit per hash value (16 or more bits per edge): most triangle edges are no silhouette,
      // and one clear bit says so without a look-up in the map.
      const EdgeKeyHash hash;
      std::vector<uint64_t> maybe(std::bit_ceil(std::max<size_t>(n_edges / 4, 1)), 0);
      const size_t mask = maybe.size() * 64 - 1;
      for (uint32_t e = 0; e < n_edges; ++e) {
        const auto& se = m_setup.silhouettes[e];
        const EdgeKey key = edge_key(se.draw, se.a, se.b);
        const size_t h = hash(key) & mask;
        maybe[h / 64] |= uint64_t(1) << (h % 64);
        by_key.emplace(key, e);
      }
      for (const vis::SetupTriangle& t : m_setup.triangles) {
        if (!t.front) continue;
        for (int k = 0; k < 3; ++k) {
          const EdgeKey key = edge_key(t.draw, t.v[k], t.v[(k + 1) % 3]);
          const size_t h = hash(key) & mask;
          if (!(maybe[h / 64] >> (h % 64) & 1)) continue;
          auto it = by_key.find(key);
          if (it != by_key.end() && owner[it->second] == kNone) owner[it->second] = t.id;
        }
      }
      // An edge no front triangle claims (none expected: a silhouette has a front triangle)
      // rides with the last triangle of its draw.
      std::vector<uint32_t> draw_last(m_frame.draws.size(), 0);
      for (uint32_t id = 0; id < m_trace_triangles; ++id) draw_last[m_setup.triangle_draw[id]] = id;
      for (uint32_t e = 0; e < n_edges; ++e)
        if (owner[e] == kNone) owner[e] = draw_last[m_setup.silhouettes[e].draw];
    }
    return owner;
  };
  auto owners = std::async(vis::host_threads() > 1 ? std::launch::async : std::launch::deferred, find_owners);
  m_full_tiler = std::make_unique<vis::GoldenTiler>(m_setup, m_gcfg, m_full);
  m_full_tiler->bin();
  m_front_of.assign(m_setup.triangles.size(), kNone);
  const auto& front = m_full_tiler->frame().triangles();
  for (uint32_t i = 0; i < front.size(); ++i) m_front_of[front[i].setup_index] = i;
  const size_t n_tris = m_setup.triangles.size(), n_edges = m_setup.silhouettes.size();
  m_tri_refs.assign(n_tris, 0);
  m_tri_tests.assign(n_tris, 0);
  m_edge_refs.assign(n_edges, 0);
  m_edge_tests.assign(n_edges, 0);
  for (uint32_t tile = 0; tile < tile_count(); ++tile) {
    for (uint32_t s : m_full_tiler->tile_triangles(tile)) ++m_tri_refs[s];
    for (uint32_t e : m_full_tiler->frame().tile_edges(tile)) ++m_edge_refs[e];
  }
  for (size_t i = 0; i < n_tris; ++i) {
    const auto& v = m_setup.triangles[i].v;
    if (!m_setup.triangles[i].front) continue;  // culled before the tiling engine
    m_tri_tests[i] = m_grid
                         .range({std::min({v[0].x, v[1].x, v[2].x}), std::min({v[0].y, v[1].y, v[2].y}),
                                 std::max({v[0].x, v[1].x, v[2].x}), std::max({v[0].y, v[1].y, v[2].y})})
                         .count();
  }
  for (size_t i = 0; i < n_edges; ++i) {
    const auto& e = m_setup.silhouettes[i];
    m_edge_tests[i] =
        m_grid.range({std::min(e.a.x, e.b.x), std::min(e.a.y, e.b.y), std::max(e.a.x, e.b.x), std::max(e.a.y, e.b.y)})
            .count();
  }

  const std::vector<uint32_t> owner = owners.get();
  m_owned_begin.assign(size_t(m_trace_triangles) + 1, 0);
  for (uint32_t o : owner)
    if (o != kNone) ++m_owned_begin[o + 1];
  for (size_t i = 1; i < m_owned_begin.size(); ++i) m_owned_begin[i] += m_owned_begin[i - 1];
  m_owned.assign(m_owned_begin.back(), 0);
  std::vector<uint32_t> fill(m_owned_begin.begin(), m_owned_begin.end() - 1);
  for (uint32_t e = 0; e < n_edges; ++e)
    if (owner[e] != kNone) m_owned[fill[owner[e]]++] = e;
}

void FrameWork::set_segments(std::vector<uint32_t> first_ids) {
  if (first_ids.empty() || first_ids[0] != 0) throw std::logic_error("segment plan must start at triangle 0");
  for (size_t i = 1; i < first_ids.size(); ++i)
    if (first_ids[i] <= first_ids[i - 1] || first_ids[i] >= m_trace_triangles)
      throw std::logic_error("segment plan must be strictly ascending inside the frame");
  if (m_replay && first_ids != m_rec.segment_plan) {
    auto plan = [](const std::vector<uint32_t>& p) {
      std::string s = std::to_string(p.size()) + " segments, first triangles";
      for (size_t i = 0; i < p.size() && i < 8; ++i) s += " " + std::to_string(p[i]);
      return s + (p.size() > 8 ? " ..." : "");
    };
    throw std::runtime_error("the functional record's parameter-buffer segments differ from this run's (pb.* "
                             "parameters set the partial renders): the record has " +
                             plan(m_rec.segment_plan) + "; this run " + plan(first_ids));
  }
  if (!m_replay) {
    m_rec.segment_plan = first_ids;
    m_rec.segments.assign(first_ids.size(), {});
  }
  m_seg_first = std::move(first_ids);
  m_seg_front.assign(m_seg_first.size(), 0);
  if (segment_count() > 1 && m_owner.empty())
    m_owner.assign(size_t(m_frame.width) * m_frame.height * samples(), kNone);
  if (!uses_evu(m_cfg.mode) && m_owner.empty())
    m_owner.assign(size_t(m_frame.width) * m_frame.height * samples(), kNone);
}

// A segment's own setup: the frame's draws cut to the segment's triangles. Snapping and
// clipping are per triangle, so its triangles are the frame's, bit for bit (checked);
// silhouettes are the segment's own.
static std::unique_ptr<vis::Setup> segment_setup(const trace::Frame& f, const vis::Setup& full, uint32_t first,
                                                 uint32_t end, uint32_t depth_bits, uint32_t setup_first,
                                                 uint32_t setup_end) {
  trace::Frame sub;
  sub.width = f.width;
  sub.height = f.height;
  sub.depth_near = f.depth_near;
  sub.depth_far = f.depth_far;
  sub.subpixel_bits = f.subpixel_bits;
  sub.samples = f.samples;
  std::vector<uint32_t> draw_map;
  uint32_t id = 0;
  for (uint32_t d = 0; d < f.draws.size(); ++d) {
    const trace::Draw& draw = f.draws[d];
    const uint32_t n = uint32_t(draw.triangle_count());
    const uint32_t lo = std::max(first, id), hi = std::min(end, id + n);
    if (lo < hi) {
      trace::Draw c;
      c.name = draw.name;
      c.flags = draw.flags;
      c.shader_cycles_per_fragment = draw.shader_cycles_per_fragment;
      c.varying_bytes_per_vertex = draw.varying_bytes_per_vertex;
      c.texture_bytes_per_fragment = draw.texture_bytes_per_fragment;
      c.vertices = draw.vertices;
      c.indices.assign(draw.indices.begin() + 3 * size_t(lo - id), draw.indices.begin() + 3 * size_t(hi - id));
      sub.draws.push_back(std::move(c));
      draw_map.push_back(d);
    }
    id += n;
  }
  auto s = std::make_unique<vis::Setup>(vis::primitive_setup(sub, {depth_bits}));
  for (auto& t : s->triangles) {
    t.id += first;
    t.draw = draw_map[t.draw];
  }
  for (auto& e : s->silhouettes) e.draw = draw_map[e.draw];
  s->triangle_draw = full.triangle_draw;
  if (s->triangles.size() != setup_end - setup_first)
    throw std::logic_error("segment setup differs from the frame's in triangle count");
  for (size_t i = 0; i < s->triangles.size(); ++i) {
    const auto &a = s->triangles[i], &b = full.triangles[setup_first + i];
    if (a.id != b.id || a.front != b.front || !(a.v[0] == b.v[0]) || !(a.v[1] == b.v[1]) || !(a.v[2] == b.v[2]))
      throw std::logic_error("segment setup differs from the frame's at triangle " + std::to_string(b.id));
  }
  return s;
}

void FrameWork::prepare_segment(uint32_t k) {
  const HostTime timed(m_functional_s, m_functional_depth);
  if (m_seg) throw std::logic_error("prepare_segment: the previous segment is not finished");
  if (k >= segment_count()) throw std::logic_error("prepare_segment: no such segment");
  m_seg = std::make_unique<Segment>();
  Segment& sg = *m_seg;
  sg.index = k;
  sg.setup_first = m_setup_begin[segment_first(k)];
  sg.setup_end = m_setup_begin[segment_end(k)];
  sg.open.resize(tile_count());
  for (uint32_t i = sg.setup_first; i < sg.setup_end; ++i) m_seg_front[k] += m_setup.triangles[i].front;
  if (!m_replay) bin_segment(sg);

  const RecordedSegment& rs = m_rec.segments.at(k);
  const size_t n = rs.tiles.size();
  if (rs.triangle_count.size() != n || rs.pair_tests.size() != n || rs.list_begin.size() != n + 1 ||
      rs.list_begin.back() != rs.list.size() || rs.edge_count.size() != (uses_evu(m_cfg.mode) ? tile_count() : 0) ||
      rs.result_count() != rs.resolved.size())
    throw std::runtime_error("the functional record's segment " + std::to_string(k) + " is inconsistent");
  for (uint32_t s : rs.list)
    if (s >= m_setup.triangles.size()) throw std::runtime_error("the functional record's tile lists exceed its setup");
  m_seg_pos.assign(tile_count(), kNone);
  m_seg_tiles = rs.tiles;
  const size_t c_tri = 0,
               c_seg = size_t(std::find(m_columns.begin(), m_columns.end(), "segments") - m_columns.begin());
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t tile = rs.tiles[i];
    if (tile >= tile_count()) throw std::runtime_error("the functional record's tiles exceed the grid");
    m_seg_pos[tile] = i;
    m_rows[tile][c_tri] += int64_t(rs.triangle_count[i]);
    ++m_rows[tile][c_seg];
  }
  if (uses_evu(m_cfg.mode))
    for (uint32_t tile = 0; tile < tile_count(); ++tile) m_rows[tile][1] += int64_t(rs.edge_count[tile]);
  if (m_replay) {
    m_seg_result.assign(tile_count(), kNone);
    for (uint32_t i = 0; i < rs.resolved.size(); ++i) {
      if (rs.resolved[i] >= tile_count()) throw std::runtime_error("the functional record's tiles exceed the grid");
      m_seg_result[rs.resolved[i]] = i;
    }
    m_recorded_last.resize(tile_count(), kNone);
    m_replayed_last.resize(tile_count(), kNone);
    if (k > 0)
      for (uint32_t tile : m_rec.segments[k - 1].resolved) m_recorded_last[tile] = k - 1;
  }
  m_tiles_binned += n;
}

// The segment's binning, into its record.
void FrameWork::bin_segment(Segment& sg) {
  RecordedSegment& rs = m_rec.segments[sg.index];
  rs.list_begin.assign(1, 0);
  auto add_tile = [&](uint32_t tile, size_t triangles, uint64_t pair_tests) {
    rs.tiles.push_back(tile);
    rs.triangle_count.push_back(uint32_t(triangles));
    rs.pair_tests.push_back(pair_tests);
    rs.list_begin.push_back(uint32_t(rs.list.size()));
  };
  if (uses_evu(m_cfg.mode)) {
    uint32_t offset = 0;  // the segment's own setup indexes its triangles from the frame's setup_first
    if (segment_count() == 1) {
      sg.s = &m_setup;
      sg.golden = m_full_tiler.get();
    } else {
      sg.setup = segment_setup(m_frame, m_setup, segment_first(sg.index), segment_end(sg.index), m_cfg.depth_bits,
                               sg.setup_first, sg.setup_end);
      sg.result = std::make_unique<vis::GoldenResult>();
      sg.result->width = m_setup.width;
      sg.result->height = m_setup.height;
      sg.result->samples = samples();
      sg.tiler = std::make_unique<vis::GoldenTiler>(*sg.setup, m_gcfg, *sg.result);
      sg.tiler->bin();
      sg.s = sg.setup.get();
      sg.golden = sg.tiler.get();
      offset = sg.setup_first;
    }
    rs.edge_count.resize(tile_count());
    for (uint32_t tile = 0; tile < tile_count(); ++tile) {
      rs.edge_count[tile] = uint32_t(sg.golden->frame().tile_edges(tile).size());
      const size_t n = sg.golden->frame().tile_triangles(tile).size();
      if (!n) continue;
      for (uint32_t s : sg.golden->tile_triangles(tile)) rs.list.push_back(offset + s);
      add_tile(tile, n, sg.golden->frame().pair_tests(tile));
    }
  } else {
    sg.s = &m_setup;
    for (uint32_t tile = 0; tile < tile_count(); ++tile) {
      const size_t before = rs.list.size();
      for (uint32_t s : m_full_tiler->tile_triangles(tile))
        if (s >= sg.setup_first && s < sg.setup_end) rs.list.push_back(s);
      if (rs.list.size() > before) add_tile(tile, rs.list.size() - before, 0);
    }
  }
}

std::pair<const uint32_t*, const uint32_t*> FrameWork::tile_list(uint32_t tile) const {
  const RecordedSegment& rs = m_rec.segments[m_seg->index];
  const uint32_t i = m_seg_pos[tile];
  if (i == kNone) return {nullptr, nullptr};
  return {rs.list.data() + rs.list_begin[i], rs.list.data() + rs.list_begin[i + 1]};
}

uint32_t FrameWork::tile_triangle_count(uint32_t tile) const {
  const uint32_t i = m_seg_pos[tile];
  return i == kNone ? 0 : m_rec.segments[m_seg->index].triangle_count[i];
}

uint32_t FrameWork::tile_edge_count(uint32_t tile) const {
  return uses_evu(m_cfg.mode) ? m_rec.segments[m_seg->index].edge_count[tile] : 0;
}

uint64_t FrameWork::tile_pair_tests(uint32_t tile) const {
  const uint32_t i = m_seg_pos[tile];
  return i == kNone ? 0 : m_rec.segments[m_seg->index].pair_tests[i];
}

TileWork* FrameWork::open_tile(uint32_t tile) {
  const HostTime timed(m_functional_s, m_functional_depth);
  Segment& sg = *m_seg;
  auto w = std::make_unique<TileWork>();
  w->segment = sg.index;
  w->tile = tile;
  w->tx = m_grid.tile_x(tile);
  w->ty = m_grid.tile_y(tile);
  const uint32_t x0 = w->tx * m_cfg.tile_w, y0 = w->ty * m_cfg.tile_h;
  w->pixels = (std::min(m_frame.width, x0 + m_cfg.tile_w) - x0) * (std::min(m_frame.height, y0 + m_cfg.tile_h) - y0);
  const auto [b, e] = tile_list(tile);
  w->draws.reserve(size_t(e - b));
  w->ids.reserve(size_t(e - b));
  for (const uint32_t* s = b; s != e; ++s) {
    const vis::SetupTriangle& t = m_setup.triangles[*s];
    w->draws.push_back(t.draw);
    w->ids.push_back(t.id);
    w->opaque += t.opaque;
  }
  if (uses_evu(m_cfg.mode)) {
    w->edges = tile_edge_count(tile);
    // SVGPU needs a tile's whole edge list beside each triangle: a list over the on-chip
    // capacity is streamed in passes (triangles in chunks, edges and occluders re-read).
    const uint32_t tp = (w->triangles() + m_cfg.evu_triangle_entries - 1) / m_cfg.evu_triangle_entries;
    const uint32_t ep = (w->edges + m_cfg.evu_edge_entries - 1) / m_cfg.evu_edge_entries;
    w->passes = std::max<uint32_t>(1, std::max(tp, ep));
  }
  w->reload = m_stored[tile];
  w->store = sg.index + 1 < segment_count();
  m_stored[tile] = m_stored[tile] || w->store;
  sg.open[tile] = std::move(w);
  return sg.open[tile].get();
}

const vis::FrontTriangle& FrameWork::raster(uint32_t s) const {
  return m_full_tiler->frame().triangles()[m_front_of[s]];
}

uint32_t FrameWork::covering_fan(uint32_t id, geom::Point p) {
  for (uint32_t s = m_setup_begin[id]; s < m_setup_begin[id + 1]; ++s)
    if (m_setup.triangles[s].front && raster(s).edges.covers(p)) return s;
  throw std::logic_error("no setup triangle of triangle " + std::to_string(id) + " covers a sample it owns");
}

void FrameWork::resolve_ahead(const std::vector<uint32_t>& tiles) {
  const HostTime timed(m_functional_s, m_functional_depth);
  if (!m_seg) throw std::logic_error("resolve_ahead: no segment");
  if (uses_evu(m_cfg.mode) && !m_replay) m_seg->golden->resolve_ahead(tiles, true);
}

void FrameWork::resolve_tile(TileWork& w) {
  const HostTime timed(m_functional_s, m_functional_depth);
  if (w.resolved) return;
  if (m_replay) {
    replay_tile(w);
  } else {
    if (uses_evu(m_cfg.mode)) resolve_analytic(w);
    else resolve_pixels(w);
    if (m_cfg.record) record_tile(w);
  }
  w.resolved = true;
  if (m_cfg.progress) m_cfg.progress(++m_tiles_resolved, m_tiles_binned);
}

// Fidelity rtl: the tile's job through the Verilated EVU, which checks every decision against
// the job's golden counters (these per-triangle ones, summed) and returns its clocks.
// Called inside the simulation's threads: a failure stops the simulation and simulate() throws
// it (an exception must not cross the SystemC kernel).
void FrameWork::take_rtl_clocks(TileWork& w) {
  const HostTime timed(m_rtl_s, m_rtl_depth);
  try {
    take_rtl_clocks_or_throw(w);
  } catch (const std::exception& e) {
    if (m_failure.empty()) m_failure = e.what();
    sc_core::sc_stop();
  }
}

void FrameWork::take_rtl_clocks_or_throw(TileWork& w) {
  vis::TileCounters golden;
  for (const TriangleWork& t : w.tris) golden += t;
  const vis::EvuJob job = vis::make_evu_job(m_seg->golden->frame(), w.tile, &golden);
  const RtlTileClocks clocks = m_cfg.rtl->run(job);
  // The job's triangles are the resolver's, in its order (a fan of one clipped triangle shares
  // an id, so match by position and check the id).
  if (clocks.tris.size() != w.tris.size())
    throw std::logic_error("fidelity rtl: the RTL returned clocks for " + std::to_string(clocks.tris.size()) +
                           " triangles of tile " + std::to_string(w.tile) + ", which has " +
                           std::to_string(w.tris.size()));
  for (size_t i = 0; i < w.tris.size(); ++i) {
    TriangleWork& t = w.tris[i];
    const RtlTriangleClocks& r = clocks.tris[i];
    if (r.id != t.id)
      throw std::logic_error("fidelity rtl: tile " + std::to_string(w.tile) + ": the RTL's triangle " +
                             std::to_string(i) + " is " + std::to_string(r.id) + ", the model's " + std::to_string(t.id));
    t.rtl = true;
    t.rtl_reject = r.reject;
    t.rtl_clip = std::accumulate(r.splits.begin(), r.splits.end(), uint64_t(0));
    t.rtl_occlude = std::accumulate(r.pieces.begin(), r.pieces.end(), uint64_t(0));
  }
  w.rtl_reject_tile = clocks.reject_latency + clocks.list_load;
}

void FrameWork::resolve_analytic(TileWork& w) {
  Segment& sg = *m_seg;
  m_per_tri.clear();
  const bool keep = m_cfg.record && segment_count() == 1;  // the tile's visible areas go to m_full
  const vis::TileVerdict verdict = sg.golden->process_tile(w.tile, &m_per_tri, keep ? &m_tile_added : nullptr);
  w.per_pixel = uint8_t(verdict.per_pixel_cause);
  w.detection_screens = verdict.detection_screens;
  w.detection_tests = verdict.detection_tests;
  w.tris.resize(m_per_tri.size());
  for (size_t i = 0; i < m_per_tri.size(); ++i) {
    const auto& rec = m_per_tri[i];
    const vis::SetupTriangle& t = sg.s->triangles[rec.triangle];
    TriangleWork& tw = w.tris[i];
    static_cast<vis::TileCounters&>(tw) = rec.counters;
    tw.shape = rec.shape;
    tw.id = t.id;
    tw.draw = t.draw;
    tw.fragments_shaded = uint32_t(rec.shader_invocations);
    if (w.per_pixel) tw.depth_tests = uint32_t(tw.fragments_generated);  // the HSR unit: one test per covered sample
  }
  if (m_cfg.rtl && !w.per_pixel && !w.tris.empty()) take_rtl_clocks(w);
  if (segment_count() == 1) return;

  // Merge into the stored depth of earlier partial renders: a visible sample of this
  // segment takes the sample where it is strictly nearer; a triangle shades a pixel once
  // when it takes any of the pixel's samples.
  std::unordered_map<uint32_t, size_t> first_of_id;
  for (size_t i = 0; i < w.tris.size(); ++i) {
    first_of_id.emplace(w.tris[i].id, i);
    w.tris[i].fragments_shaded = 0;
  }
  const uint32_t ns = samples();
  const uint32_t x0 = w.tx * m_cfg.tile_w, y0 = w.ty * m_cfg.tile_h;
  const uint32_t x1 = std::min(m_frame.width, x0 + m_cfg.tile_w), y1 = std::min(m_frame.height, y0 + m_cfg.tile_h);
  uint32_t taken[trace::kMaxSamples];  // per sample of the pixel: the TriangleWork that took it
  for (uint32_t py = y0; py < y1; ++py)
    for (uint32_t px = x0; px < x1; ++px) {
      for (uint32_t k = 0; k < ns; ++k) {
        taken[k] = kNone;
        const size_t idx = (size_t(py) * m_frame.width + px) * ns + k;
        const int32_t sid = sg.result->ids[idx];
        if (sid < 0) continue;
        const geom::Point p = vis::zbuffer::sample_point(m_setup, px, py, k);
        const uint32_t fan = covering_fan(uint32_t(sid), p);
        const size_t ti = first_of_id.at(uint32_t(sid));
        const uint32_t old = m_owner[idx];
        if (old != kNone) {
          ++w.tris[ti].depth_tests;
          if (!vis::zbuffer::passes(raster(fan).plane, raster(old).plane, p)) continue;
        }
        m_owner[idx] = fan;
        taken[k] = uint32_t(ti);
      }
      vis::zbuffer::for_invocations(
          taken, ns, kNone, [&](uint32_t ti) { return sample_rate(w.tris[ti]); },
          [&](uint32_t ti) { ++w.tris[ti].fragments_shaded; });
    }
}

void FrameWork::resolve_pixels(TileWork& w) {
  const auto [list_begin, list_end] = tile_list(w.tile);
  const std::span<const uint32_t> list(list_begin, list_end);
  const uint32_t ns = samples();
  const vis::zbuffer::PixelRect region = vis::zbuffer::tile_pixels(m_grid, w.tile);
  std::unordered_map<uint32_t, size_t> local;
  w.tris.resize(list.size());
  for (size_t i = 0; i < list.size(); ++i) {
    const vis::SetupTriangle& t = m_setup.triangles[list[i]];
    w.tris[i].id = t.id;
    w.tris[i].draw = t.draw;
    local.emplace(list[i], i);
  }
  // The exact z-buffer (vis::zbuffer) in submission order against the tile's depth, which
  // earlier partial renders may have stored.
  // Shading counts shader invocations: once per pixel and triangle (vis::zbuffer::PixelShades).
  for (size_t i = 0; i < list.size(); ++i) {
    TriangleWork& tw = w.tris[i];
    const vis::FrontTriangle& t = raster(list[i]);
    vis::zbuffer::PixelShades shaded(t.t->sample_rate);
    vis::zbuffer::for_covered_samples(m_setup, t, region, [&](uint32_t px, uint32_t py, uint32_t k, geom::Point p) {
      ++tw.fragments_generated;
      uint32_t& owner = m_owner[vis::zbuffer::sample_index(m_setup, px, py, k)];
      const bool pass = owner == kNone || vis::zbuffer::passes(t.plane, raster(owner).plane, p);
      if (m_cfg.mode != Mode::none) ++tw.depth_tests;  // one test per covered sample
      if (m_cfg.mode == Mode::none || (m_cfg.mode == Mode::early_z && pass)) shaded.add(px, py, m_frame.width);
      if (pass && t.t->opaque) owner = list[i];
    });
    tw.fragments_shaded += uint32_t(shaded.count);
  }
  // Samples the tile's triangles own now; HSR shades the pixels they own (the tag buffer),
  // then translucent fragments in front of them.
  uint32_t owned[trace::kMaxSamples];  // per sample of the pixel: the local triangle owning it
  for (uint32_t py = region.y0; py < region.y1; ++py)
    for (uint32_t px = region.x0; px < region.x1; ++px) {
      for (uint32_t k = 0; k < ns; ++k) {
        owned[k] = kNone;
        const uint32_t o = m_owner[vis::zbuffer::sample_index(m_setup, px, py, k)];
        if (o == kNone) continue;
        auto it = local.find(o);
        if (it == local.end()) continue;
        ++w.tris[it->second].samples_covered;
        owned[k] = uint32_t(it->second);
      }
      if (m_cfg.mode == Mode::hsr)
        vis::zbuffer::for_invocations(
            owned, ns, kNone, [&](uint32_t i) { return sample_rate(w.tris[i]); },
            [&](uint32_t i) { ++w.tris[i].fragments_shaded; });
    }
  if (m_cfg.mode == Mode::hsr)
    for (size_t i = 0; i < list.size(); ++i) {
      const vis::FrontTriangle& t = raster(list[i]);
      if (t.t->opaque) continue;
      vis::zbuffer::PixelShades shaded(t.t->sample_rate);
      vis::zbuffer::for_covered_samples(m_setup, t, region, [&](uint32_t px, uint32_t py, uint32_t k, geom::Point p) {
        const uint32_t o = m_owner[vis::zbuffer::sample_index(m_setup, px, py, k)];
        if (o == kNone || vis::zbuffer::passes(t.plane, raster(o).plane, p)) shaded.add(px, py, m_frame.width);
      });
      w.tris[i].fragments_shaded += uint32_t(shaded.count);
    }
}

int32_t* FrameWork::sample_buffer() {
  return m_owner.empty() ? m_full.ids.data() : reinterpret_cast<int32_t*>(m_owner.data());
}

void FrameWork::record_tile(const TileWork& w) {
  RecordedSegment& rs = m_rec.segments[m_seg->index];
  RecordedTile& r = rs.results.emplace_back();
  rs.resolved.push_back(w.tile);
  r.per_pixel = w.per_pixel;
  r.detection_screens = w.detection_screens;
  r.detection_tests = w.detection_tests;
  r.tris = w.tris;
  const int32_t* buf = sample_buffer();
  const vis::zbuffer::PixelRect px = vis::zbuffer::tile_pixels(m_grid, w.tile);
  const size_t row = size_t(px.x1 - px.x0) * samples();
  for (uint32_t y = px.y0; y < px.y1; ++y) {
    const int32_t* p = buf + vis::zbuffer::sample_index(m_setup, px.x0, y, 0);
    r.samples.insert(r.samples.end(), p, p + row);
  }
  if (m_owner.empty()) {
    r.areas = std::move(m_tile_added.areas);
    r.visible_triangles = m_tile_added.visible_triangles;
    m_tile_added = {};
  }
}

// Inside the simulation's threads a tile the record lacks stops the simulation (as an RTL
// failure does); the closed form, outside them, throws.
void FrameWork::replay_tile(TileWork& w) {
  auto stop = [&](const std::string& m) {
    if (!sc_core::sc_is_running()) throw std::runtime_error(m);
    if (m_failure.empty()) m_failure = m;
    sc_core::sc_stop();
    w.tris.assign(w.ids.size(), {});  // the units finish this delta on empty work
    for (size_t i = 0; i < w.ids.size(); ++i) w.tris[i].id = w.ids[i], w.tris[i].draw = w.draws[i];
  };
  // Fidelity auto resolves a sample of the tiles: the record must have this one, and the same
  // stored depth under it (the same earlier segments resolved it).
  const std::string where = "tile " + std::to_string(w.tile) + " of segment " + std::to_string(w.segment);
  const uint32_t i = m_seg_result[w.tile];
  if (i == kNone)
    return stop("the functional record has no visibility for " + where +
                " (the recording run did not resolve it: fidelity auto sampled other tiles)");
  auto last = [](uint32_t k) { return k == kNone ? std::string("none") : std::to_string(k); };
  if (m_recorded_last[w.tile] != m_replayed_last[w.tile])
    return stop("the functional record's " + where + " lies on the stored depth of segment " +
                last(m_recorded_last[w.tile]) + ", this run's on that of segment " + last(m_replayed_last[w.tile]) +
                " (fidelity auto sampled other tiles in earlier partial renders)");
  m_replayed_last[w.tile] = w.segment;
  const RecordedTile& r = m_rec.tile(m_seg->index, i, m_replayed_tile);
  const vis::zbuffer::PixelRect px = vis::zbuffer::tile_pixels(m_grid, w.tile);
  const size_t row = size_t(px.x1 - px.x0) * samples();
  if (r.samples.size() != row * (px.y1 - px.y0) || r.tris.size() != w.ids.size())
    return stop("the functional record's tile " + std::to_string(w.tile) + " does not fit its list or the grid");
  w.per_pixel = r.per_pixel;
  w.detection_screens = r.detection_screens;
  w.detection_tests = r.detection_tests;
  w.tris = r.tris;
  int32_t* buf = sample_buffer();
  for (uint32_t y = px.y0; y < px.y1; ++y)
    std::copy_n(r.samples.data() + (y - px.y0) * row, row, buf + vis::zbuffer::sample_index(m_setup, px.x0, y, 0));
  if (m_owner.empty()) {
    vis::TileOutput added;
    added.areas = r.areas;
    added.visible_triangles = r.visible_triangles;
    m_full.add(std::move(added));
  }
}

void FrameWork::close_tile(TileWork* w) {
  const HostTime timed(m_functional_s, m_functional_depth);
  Segment& sg = *m_seg;
  auto& row = m_rows[w->tile];
  uint64_t shaded = 0, tests = 0;
  for (const TriangleWork& t : w->tris) {
    shaded += t.fragments_shaded;
    tests += t.depth_tests;
  }
  if (uses_evu(m_cfg.mode)) {
    vis::TileCounters sum = vis::TileCounters::read(row);
    for (const TriangleWork& t : w->tris) sum += t;
    sum.write(row.data());
    const size_t c = vis::TileCounters::kCount;  // then fragments_shaded, depth_tests, passes, segments
    row[c] += int64_t(shaded);
    row[c + 1] += int64_t(tests);
    row[c + 2] += w->passes;
    m_passes_extra += w->passes - 1;
    if (m_cfg.mode == Mode::hybrid) {  // per_pixel, per_pixel_cause, detection_screens, detection_tests
      if (w->per_pixel) {
        row[c + 4] = 1;
        row[c + 5] = w->per_pixel;
        ++m_per_pixel_tiles;
      }
      row[c + 6] += int64_t(w->detection_screens);
      row[c + 7] += int64_t(w->detection_tests);
      m_detection_screens += w->detection_screens;
      m_detection_tests += w->detection_tests;
    }
  } else {
    for (const TriangleWork& t : w->tris) row[1] += t.fragments_generated;
    row[3] += int64_t(shaded);
    row[4] += int64_t(tests);
  }
  m_shaded += shaded;
  m_depth_tests += tests;
  ++m_tiles_rendered;
  size_t c = m_cycles_col;
  uint64_t bottleneck = 0;
  for (size_t u = 0; u < size_t(TileUnit::count); ++u) {
    if (!unit_present(TileUnit(u), m_cfg.mode)) continue;
    row[c++] += int64_t(w->cycles[u]);
    bottleneck = std::max(bottleneck, w->cycles[u]);
  }
  row[c] += int64_t(bottleneck);
  if (m_cfg.sampled) row[m_simulated_col] = 1;
  m_tile_end[w->tile] = w->end_cycle;
  m_closed_in[w->tile] = sg.index + 1;
  sg.open[w->tile].reset();
}

bool FrameWork::tile_closed(uint32_t tile) const { return m_seg && m_closed_in[tile] == m_seg->index + 1; }

void FrameWork::finish_segment() {
  const HostTime timed(m_functional_s, m_functional_depth);
  if (!m_seg) throw std::logic_error("finish_segment: no segment");
  for (const auto& w : m_seg->open)
    if (w) throw std::logic_error("finish_segment: tile " + std::to_string(w->tile) + " was never closed");
  if (!m_cfg.record && !m_replay) m_rec.segments[m_seg->index] = {};  // needed no more
  m_seg.reset();
}

void FrameWork::finish() {
  const HostTime timed(m_functional_s, m_functional_depth);
  if (m_seg) throw std::logic_error("finish: a segment is still open");
  const uint32_t ns = samples();
  const bool from_owner = !m_owner.empty();
  if (!from_owner) {
    // The frame's golden result is complete: its buffers become the output, not copies.
    m_ids = std::move(m_full.ids);
    m_visible_area = std::move(m_full.visible_area);
    vis::sum_golden_totals(m_full);
  } else {
    m_ids.assign(m_owner.size(), -1);
    for (size_t i = 0; i < m_owner.size(); ++i)
      if (m_owner[i] != kNone) m_ids[i] = int32_t(m_setup.triangles[m_owner[i]].id);
    // samples_covered per tile: what is visible at the end of the frame.
    const size_t c_cov = uses_evu(m_cfg.mode) ? 8 : 2;
    for (auto& row : m_rows) row[c_cov] = 0;
    for (uint32_t py = 0; py < m_frame.height; ++py)
      for (uint32_t px = 0; px < m_frame.width; ++px)
        for (uint32_t k = 0; k < ns; ++k)
          if (m_owner[(size_t(py) * m_frame.width + px) * ns + k] != kNone)
            ++m_rows[m_grid.tile_at_pixel(px, py)][c_cov];
  }
  m_finished = true;
}

outputs::TileTable FrameWork::tile_table() const {
  outputs::TileTable t;
  t.resize(m_cfg.tile_w, m_cfg.tile_h, m_frame.width, m_frame.height, m_columns);
  t.rows = m_rows;
  return t;
}

nlohmann::json FrameWork::totals() const {
  const auto& st = m_setup.stats;
  nlohmann::json j = {{"triangles_in", st.triangles_in},
                      {"triangles_front", st.front_facing},
                      {"triangles_back", st.back_facing},
                      {"triangles_degenerate", st.degenerate},
                      {"triangles_clipped", st.clipped},
                      {"triangles_frustum_culled", st.frustum_culled},
                      {"triangles_edge_on", st.edge_on},
                      {"silhouette_edges", uses_evu(m_cfg.mode) ? st.silhouette_edges : 0}};
  if (m_cfg.mode == Mode::hybrid) {
    j["per_pixel_tiles"] = m_per_pixel_tiles;
    j["hybrid_detection_screens"] = m_detection_screens;
    j["hybrid_detection_tests"] = m_detection_tests;
  }
  auto sum = [&](const std::string& name) {
    const auto it = std::find(m_columns.begin(), m_columns.end(), name);
    if (it == m_columns.end()) return uint64_t{0};
    const size_t c = size_t(it - m_columns.begin());
    uint64_t s = 0;
    for (const auto& row : m_rows) s += uint64_t(row[c]);
    return s;
  };
  if (uses_evu(m_cfg.mode)) {
    j["pair_tests"] = sum("pair_tests");
    j["candidate_pairs"] = sum("candidate_pairs");
    j["clip_polygons"] = sum("clip_polygons");
    j["pieces"] = sum("pieces");
    j["visible_pieces"] = sum("visible_pieces");
    j["occlusion_tests"] = sum("occlusion_tests");
    if (m_owner.empty()) j["visible_triangles"] = m_full.visible_triangles;
  } else {
    for (const char* k : {"candidate_pairs", "clip_polygons", "visible_pieces"}) j[k] = 0;
  }
  j["samples_covered"] = sum("samples_covered");
  j["fragments_generated"] = sum("fragments_generated");
  j["fragments_shaded"] = m_shaded;  // shader invocations: once per pixel and triangle (MSAA)
  j["samples_tested"] = sum("fragments_generated");
  j["depth_tests"] = m_depth_tests;
  j["partial_renders"] = segment_count() - 1;
  j["tiles_rendered"] = m_tiles_rendered;
  j["evu_extra_passes"] = m_passes_extra;
  return j;
}

nlohmann::json FrameWork::triangle_accounts() const {
  const auto& st = m_setup.stats;
  uint64_t ids_with_setup = 0, binned = 0, off_screen = 0, refs = 0;
  for (uint32_t id = 0; id < m_trace_triangles; ++id) ids_with_setup += m_setup_begin[id + 1] > m_setup_begin[id];
  for (size_t i = 0; i < m_setup.triangles.size(); ++i) {
    if (!m_setup.triangles[i].front) continue;
    (m_tri_refs[i] ? binned : off_screen) += 1;
    refs += m_tri_refs[i];
  }
  uint64_t seg_front = 0;
  for (uint64_t f : m_seg_front) seg_front += f;
  const bool balanced = st.triangles_in == st.frustum_culled + st.edge_on + ids_with_setup &&
                        st.setup_triangles == st.front_facing + st.back_facing + st.degenerate &&
                        st.front_facing == binned + off_screen && seg_front == st.front_facing;
  if (!balanced) throw std::logic_error("triangle accounting does not balance");
  return {{"help", "every trace triangle, step by step: in = frustum_culled + edge_on + reaching setup; setup triangles "
                   "(fans of clipped ones) = front + back + degenerate; front = binned + off_screen; front = sum over "
                   "segments"},
          {"triangles_in", st.triangles_in},
          {"frustum_culled", st.frustum_culled},
          {"edge_on", st.edge_on},
          {"reaching_setup", ids_with_setup},
          {"clipped_into_fans", st.clipped},
          {"setup_triangles", st.setup_triangles},
          {"back_facing", st.back_facing},
          {"degenerate", st.degenerate},
          {"front_facing", st.front_facing},
          {"front_binned", binned},
          {"front_off_screen", off_screen},
          {"tile_references", refs},
          {"front_per_segment", m_seg_front},
          {"balanced", balanced}};
}

}  // namespace tilevis::sim
