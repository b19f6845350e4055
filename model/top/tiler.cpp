#include "top/tiler.h"

#include <algorithm>
#include <atomic>
#include <future>

#include "visibility/parallel.h"

namespace tilevis::sim {

std::vector<const UnitBase*> Tiler::Core::units() const {
  std::vector<const UnitBase*> u = {fetch.get()};
  if (evu) u.push_back(evu.get());
  if (hsr) u.push_back(hsr.get());
  u.push_back(fragment.get());
  u.push_back(writer.get());
  return u;
}

Tiler::Tiler(const sc_core::sc_module_name& name, const TilerConfig& config, FrameWork& work, bool trace_signals)
    : sc_core::sc_module(name), m_cfg(config), m_work(work) {
  m_env.work = &work;
  // One cycle of the GPU clock, rounded to the 1 ps time resolution.
  m_env.period = sc_core::sc_time(1e6 / config.sim.clock_mhz, sc_core::SC_PS);
  m_env.trace = trace_signals;
  m_env.waits = &m_waits;
  const bool per_primitive = config.sim.fidelity == Fidelity::primitive || config.sim.fidelity == Fidelity::rtl ||
                             config.sim.fidelity == Fidelity::automatic;
  const int geometry_depth = per_primitive ? int(config.sim.fifo_primitives) : 2;
  const int render_depth = per_primitive ? int(config.sim.fifo_primitives) : int(config.sim.fifo_tiles);
  const uint32_t batch = per_primitive ? 1 : config.sim.batch_triangles;

  MemoryConfig memory = config.memory;
  if (memory.model == MemoryModel::automatic)
    memory.model = per_primitive ? MemoryModel::detailed : MemoryModel::bandwidth;
  m_memory = std::make_unique<Memory>("memory", memory, m_env.period);
  m_front_end = std::make_unique<GeometryFrontEnd>("front_end", m_env, config.front_end, batch);
  m_setup = std::make_unique<PrimitiveSetup>("setup", m_env, config.setup);
  m_silhouette = std::make_unique<SilhouetteUnit>("silhouette", m_env, config.silhouette);
  m_pb = std::make_unique<ParameterBuffer>("pb", m_env, config.pb);
  m_tiling = std::make_unique<TilingEngine>("tiling", m_env, config.tiling, *m_pb);
  TileSchedulerConfig scheduler = config.scheduler;
  scheduler.sampled = config.sim.fidelity == Fidelity::automatic;
  scheduler.sampling.reject_lanes = uses_evu(config.sim.mode) ? config.evu.reject.lanes : 0;
  m_scheduler = std::make_unique<TileScheduler>("scheduler", m_env, scheduler);

  auto fifo = [&](const char* n, int depth) {
    m_fifos.push_back(std::make_unique<OccupancyFifo<Item>>(n, depth));
    return m_fifos.back().get();
  };
  m_front_end->out(*fifo("front_end_to_setup", geometry_depth));
  m_setup->in(*m_fifos.back());
  m_setup->out(*fifo("setup_to_silhouette", geometry_depth));
  m_silhouette->in(*m_fifos.back());
  m_silhouette->out(*fifo("silhouette_to_tiling", geometry_depth));
  m_tiling->in(*m_fifos.back());
  m_tiling->out(*fifo("tiling_to_pb", geometry_depth));
  m_pb->in(*m_fifos.back());

  m_ready = std::make_unique<sc_core::sc_fifo<uint32_t>>("pb_ready", 4);
  m_released = std::make_unique<sc_core::sc_fifo<uint32_t>>("pb_released", 4);
  m_pb->ready(*m_ready);
  m_scheduler->ready(*m_ready);
  m_scheduler->released(*m_released);
  m_pb->released(*m_released);

  m_stream_vertex = m_memory->attach(m_front_end->mem, "vertices");
  m_stream_spill = m_memory->attach(m_silhouette->mem, "silhouette_spill");
  m_tiling->pb.bind(m_pb->socket);
  m_stream_pb = m_memory->attach(m_pb->mem, "parameter_buffer");
  m_cores.resize(config.scheduler.cores);
  for (uint32_t k = 0; k < config.scheduler.cores; ++k) build_core(k, render_depth, per_primitive);
}

void Tiler::build_core(uint32_t k, int render_depth, bool per_primitive) {
  Core& c = m_cores[k];
  const TilerConfig& config = m_cfg;
  // Core 0's units keep the plain names (fetch, evu, ...); core k's are suffixed _k.
  const std::string sfx = k ? "_" + std::to_string(k) : "";
  auto n = [&](const char* base) { return std::string(base) + sfx; };
  c.fetch = std::make_unique<TileFetch>(n("fetch").c_str(), m_env, config.fetch, *m_pb, config.framebuffer, per_primitive);
  if (uses_evu(config.sim.mode))
    c.evu = std::make_unique<EarlyVisibilityUnit>(n("evu").c_str(), m_env, config.evu, render_depth);
  if (uses_hsr(config.sim.mode)) c.hsr = std::make_unique<HsrUnit>(n("hsr").c_str(), m_env, config.hsr);
  c.fragment = std::make_unique<FragmentUnit>(n("fragment").c_str(), m_env, config.fragment, *m_pb);
  c.writer = std::make_unique<TileWriter>(n("writer").c_str(), m_env, config.writer, config.framebuffer);
  if (config.sim.fidelity == Fidelity::automatic) c.writer->closed = &m_scheduler->tile_closed();

  auto fifo = [&](const std::string& name, int depth) {
    c.fifos.push_back(std::make_unique<OccupancyFifo<Item>>((name + sfx).c_str(), depth));
    return c.fifos.back().get();
  };
  // The core's tile queue holds one tile beyond the one its fetch works on.
  c.tiles = std::make_unique<sc_core::sc_fifo<Item>>(n("tiles").c_str(), 1);
  m_scheduler->to_core[k](*c.tiles);
  c.fetch->tiles(*c.tiles);
  c.fetch->out(*fifo("fetch_to_visibility", render_depth));
  // Hybrid: the EVU, then the HSR unit; each resolves its own tiles and passes the others on.
  if (c.evu) {
    c.evu->in(*c.fifos.back());
    c.evu->out(*fifo(c.hsr ? "evu_to_hsr" : "visibility_to_fragment", render_depth));
  }
  if (c.hsr) {
    c.hsr->in(*c.fifos.back());
    c.hsr->out(*fifo("visibility_to_fragment", render_depth));
  }
  c.fragment->in(*c.fifos.back());
  c.fragment->out(*fifo("fragment_to_writer", render_depth));
  c.writer->in(*c.fifos.back());
  c.done = std::make_unique<sc_core::sc_fifo<uint32_t>>(n("done").c_str(), 2);
  c.writer->done(*c.done);
  m_scheduler->done[k](*c.done);

  c.fetch->pb.bind(m_pb->socket);
  c.fragment->pb.bind(m_pb->socket);
  m_stream_stored = m_memory->attach(c.fetch->mem, "stored_tiles");
  m_stream_texture = m_memory->attach(c.fragment->mem, "texture");
  m_stream_colour = m_memory->attach(c.writer->mem, "colour");
}

Tiler::~Tiler() = default;

void Tiler::prepare() {
  m_setup->prepare();
  // The front end's vertex cache and the silhouette hash read the trace and the setup and
  // nothing the binning or each other writes: on a host with a second core the hash runs beside
  // the binning, and the vertex cache on whichever thread is free first (the binning is the
  // longest where it is computed, the hash where it is replayed: million 148 ms binning against
  // 99 ms hash and 49 ms vertex cache computed; 18 ms, 80 ms and 23 ms replayed).
  std::atomic<bool> front_end_taken{false};
  auto front_end = [&] {
    if (!front_end_taken.exchange(true)) m_front_end->prepare();
  };
  auto tables = std::async(vis::host_threads() > 1 ? std::launch::async : std::launch::deferred, [&] {
    m_silhouette->prepare();
    front_end();
  });
  m_tiling->prepare();
  front_end();
  tables.get();
  m_pb->prepare(*m_front_end);
  // Fidelity auto: a one-segment frame's geometry is sampled too when it holds enough
  // clusters for a sample to save anything (tile_sampler.h).
  const SamplingConfig& sc = m_cfg.scheduler.sampling;
  const uint32_t n = m_work.trace_triangles();
  if (m_cfg.sim.fidelity == Fidelity::automatic && m_work.segment_count() == 1 &&
      uint64_t(n) >= 4ull * sc.first_clusters * sc.geometry_cluster) {
    std::vector<double> aux(n);
    for (uint32_t id = 0; id < n; ++id) aux[id] = double(m_front_end->read_bytes(id, id + 1) + m_pb->bytes(id, id + 1));
    m_front_end->sample(sc, std::move(aux));
    m_scheduler->share_budget(m_front_end.get());
    m_pb->arrivals = &m_front_end->arrivals();
  }
}

Tiler::Step Tiler::analytic_tile(Core& core, TileWork* w, uint64_t at, uint64_t& pb_read) {
  std::vector<Stage*> visibility;
  if (core.evu) visibility = {&core.evu->reject(), &core.evu->clip(), &core.evu->occlude()};
  if (core.hsr) visibility = {core.hsr.get()};
  Item it = core.fetch->items(w).front();
  it.count = w->triangles();
  it.last = true;
  // A tile's DRAM traffic is issued when it starts; its time on the DRAM is the longest of
  // its transfers, which the memory system serves with every other core's.
  uint64_t bus = 0;
  auto dram = [&](const Traffic& t, bool read, int stream) { bus = std::max(bus, m_memory->service(at, t, read, stream)); };
  std::vector<uint64_t> unit_cycles;
  const Cost fc = core.fetch->cost(it);
  core.fetch->account(it, fc);
  pb_read += fc.reads.bytes();
  dram(fc.reads, true, m_stream_pb);
  dram(core.fetch->reload(it), true, m_stream_stored);
  unit_cycles.push_back(fc.cycles);
  m_work.resolve_tile(*w);
  uint64_t evu_max = 0;
  for (Stage* s : visibility) {
    const Cost c = s->cost(it);
    s->account(it, c);
    s->tile_done(*w);
    unit_cycles.push_back(c.cycles);
    evu_max = std::max(evu_max, c.cycles);
  }
  if (core.evu) core.evu->account_analytic(evu_max);
  const Cost frc = core.fragment->cost(it);
  core.fragment->account(it, frc);
  core.fragment->tile_done(*w);
  dram(frc.reads, true, m_stream_texture);
  dram(frc.pb_reads, true, m_stream_pb);
  pb_read += frc.pb_reads.bytes();
  unit_cycles.push_back(frc.cycles);
  const Cost wc = core.writer->cost(it);
  core.writer->account(it, wc);
  dram(wc.writes, false, m_stream_colour);
  unit_cycles.push_back(wc.cycles);
  uint64_t sum = 0, slowest = 0;
  for (uint64_t c : unit_cycles) sum += c, slowest = std::max(slowest, c);
  Step s;
  s.step = std::max(slowest, bus);
  s.drain = sum - slowest;
  s.memory_bound = bus > slowest ? bus - slowest : 0;
  return s;
}

uint64_t Tiler::run_analytic() {
  const uint64_t latency = m_memory->read_latency_cycles();
  uint64_t frame = 0, pb_written = 0, pb_read = 0;
  std::vector<Stage*> geometry = {m_setup.get(), m_silhouette.get(), m_tiling.get()};
  const uint32_t ncores = uint32_t(m_cores.size());

  for (uint32_t k = 0; k < m_work.segment_count(); ++k) {
    // Geometry: the units stream the segment; the slowest unit (or the DRAM) sets the pace.
    Item g;
    g.segment = k;
    g.first = m_work.segment_first(k);
    g.count = m_work.segment_end(k) - g.first;
    g.last = true;
    const Cost fe = m_front_end->cost(g);
    m_front_end->account(g, fe);
    uint64_t slowest = fe.cycles, bus = m_memory->service(frame, fe.reads, true, m_stream_vertex);
    for (Stage* s : geometry) {
      const Cost c = s->cost(g);
      s->account(g, c);
      slowest = std::max(slowest, c.cycles);
      const int stream = s == m_tiling.get() ? m_stream_pb : m_stream_spill;
      bus = std::max({bus, m_memory->service(frame, c.reads, true, stream), m_memory->service(frame, c.writes, false, stream)});
      if (s == m_tiling.get()) pb_written += c.writes.bytes();
    }
    frame += std::max(slowest, bus) + latency;
    m_analytic_memory_bound += bus > slowest ? bus - slowest : 0;

    // Render: the scheduler's order; each core a pipeline of units in which a tile costs
    // its slowest unit (or its DRAM time); a core's last tile drains through the rest.
    m_work.prepare_segment(k);
    const std::vector<uint32_t> tiles = m_scheduler->order(m_work.segment_tiles());
    m_work.resolve_ahead(tiles);
    std::vector<uint64_t> busy(ncores, 0), drain(ncores, 0), bound(ncores, 0);
    for (size_t i = 0; i < tiles.size(); ++i) {
      uint32_t c = m_scheduler->static_core(i);
      if (m_scheduler->config().policy == Schedule::dynamic)
        c = uint32_t(std::min_element(busy.begin(), busy.end()) - busy.begin());
      m_scheduler->count(c);
      TileWork* w = m_work.open_tile(tiles[i]);
      const Step s = analytic_tile(m_cores[c], w, frame + busy[c], pb_read);
      busy[c] += s.step;
      drain[c] = s.drain;
      bound[c] += s.memory_bound;
      m_work.close_tile(w);
    }
    uint64_t longest = 0;
    uint32_t critical = 0;
    for (uint32_t c = 0; c < ncores; ++c)
      if (busy[c] + drain[c] > longest) longest = busy[c] + drain[c], critical = c;
    frame += longest + (tiles.empty() ? 0 : latency);
    m_analytic_memory_bound += bound[critical];
    m_work.finish_segment();
  }
  m_pb->account_analytic(pb_written, pb_read);
  m_analytic_cycles = frame;
  return frame;
}

uint64_t Tiler::simulated_cycles() const { return m_scheduler->frame_end_cycle(); }
bool Tiler::frame_done() const { return m_scheduler->frame_done(); }

double Tiler::memory_bound_share(uint64_t frame_cycles) const {
  if (!frame_cycles) return 0.0;
  const double bound = m_cfg.sim.fidelity == Fidelity::analytic
                           ? double(m_analytic_memory_bound)
                           : double(m_waits.total.value()) / double(m_env.period.value());
  return std::min(1.0, bound / double(frame_cycles));
}

nlohmann::json Tiler::cores_json() const {
  nlohmann::json cores = nlohmann::json::array();
  double most = 0, sum = 0;
  for (size_t k = 0; k < m_cores.size(); ++k) {
    uint64_t work = 0;  // the core's busiest unit: what its share of the frame costs it
    for (const UnitBase* u : m_cores[k].units()) work = std::max(work, u->busy_cycles());
    const double tiles = m_scheduler->stats().value("core" + std::to_string(k) + "_tiles");
    cores.push_back({{"core", k}, {"tiles", uint64_t(tiles)}, {"work_cycles", work}});
    most = std::max(most, double(work));
    sum += double(work);
  }
  const double mean = sum / double(m_cores.size());
  return {{"scheduler", to_string(m_cfg.scheduler.policy)},
          {"per_core", cores},
          {"load_imbalance", mean > 0 ? most / mean : 1.0}};
}

std::vector<const StatsGroup*> Tiler::stats_groups() const {
  std::vector<const StatsGroup*> g = {&m_memory->stats(), &m_front_end->stats(), &m_setup->stats(),
                                      &m_silhouette->stats(), &m_tiling->stats(), &m_pb->stats(),
                                      &m_scheduler->stats()};
  for (const Core& c : m_cores) {
    g.push_back(&c.fetch->stats());
    if (c.evu) {
      g.push_back(&c.evu->stats());
      g.push_back(&c.evu->reject().stats());
      g.push_back(&c.evu->clip().stats());
      g.push_back(&c.evu->occlude().stats());
    }
    if (c.hsr) g.push_back(&c.hsr->stats());
    g.push_back(&c.fragment->stats());
    g.push_back(&c.writer->stats());
  }
  return g;
}

void Tiler::trace(sc_core::sc_trace_file* tf) const {
  std::vector<const UnitBase*> units = {m_front_end.get(), m_setup.get(), m_silhouette.get(), m_tiling.get()};
  for (const Core& c : m_cores) {
    units.push_back(c.fetch.get());
    if (c.evu) {
      units.push_back(&c.evu->reject());
      units.push_back(&c.evu->clip());
      units.push_back(&c.evu->occlude());
    }
    if (c.hsr) units.push_back(c.hsr.get());
    units.push_back(c.fragment.get());
    units.push_back(c.writer.get());
    for (const auto& f : c.fifos) sc_core::sc_trace(tf, f->occupancy, std::string(f->name()) + ".occupancy");
    if (c.evu) {
      sc_core::sc_trace(tf, c.evu->reject_to_clip().occupancy, std::string(c.evu->reject_to_clip().name()) + ".occupancy");
      sc_core::sc_trace(tf, c.evu->clip_to_occlude().occupancy, std::string(c.evu->clip_to_occlude().name()) + ".occupancy");
    }
  }
  for (const UnitBase* u : units) sc_core::sc_trace(tf, u->busy, std::string(u->name()) + ".busy");
  for (const auto& f : m_fifos) sc_core::sc_trace(tf, f->occupancy, std::string(f->name()) + ".occupancy");
}

uint64_t Tiler::dram_bytes() const { return m_memory->bytes(); }
uint64_t Tiler::param_buffer_bytes() const {
  // Sampled geometry writes only its sample; the frame's bytes are known functionally.
  return m_front_end->sampled() ? m_pb->total_bytes() : uint64_t(m_pb->stats().value("bytes_written"));
}
uint64_t Tiler::param_buffer_peak() const { return uint64_t(m_pb->stats().value("peak_bytes")); }
const std::vector<uint64_t>& Tiler::geometry_end_cycles() const { return m_pb->ready_cycles(); }
uint64_t Tiler::evu_busy_cycles() const {
  uint64_t n = 0;
  for (const Core& c : m_cores)
    if (c.evu) n += c.evu->busy_cycles();
  return n;
}

}  // namespace tilevis::sim
