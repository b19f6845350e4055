#include "top/tiler.h"

#include <algorithm>

namespace tilevis::sim {

Tiler::Tiler(const sc_core::sc_module_name& name, const TilerConfig& config, FrameWork& work, bool trace_signals)
    : sc_core::sc_module(name), m_cfg(config), m_work(work) {
  m_env.work = &work;
  // One cycle of the GPU clock, rounded to the 1 ps time resolution.
  m_env.period = sc_core::sc_time(1e6 / config.sim.clock_mhz, sc_core::SC_PS);
  m_env.trace = trace_signals;
  m_env.memory_latency = sc_core::sc_time::from_value(m_env.period.value() * config.memory.latency_cycles);
  const bool per_primitive = config.sim.fidelity == Fidelity::primitive;
  const int geometry_depth = per_primitive ? int(config.sim.fifo_primitives) : 2;
  const int render_depth = per_primitive ? int(config.sim.fifo_primitives) : int(config.sim.fifo_tiles);
  const uint32_t batch = per_primitive ? 1 : config.sim.batch_triangles;

  m_memory = std::make_unique<Memory>("memory", config.memory, m_env.period);
  m_front_end = std::make_unique<GeometryFrontEnd>("front_end", m_env, config.front_end, batch);
  m_setup = std::make_unique<PrimitiveSetup>("setup", m_env, config.setup);
  m_silhouette = std::make_unique<SilhouetteUnit>("silhouette", m_env, config.silhouette);
  m_pb = std::make_unique<ParameterBuffer>("pb", m_env, config.pb);
  m_tiling = std::make_unique<TilingEngine>("tiling", m_env, config.tiling, *m_pb);
  m_fetch = std::make_unique<TileFetch>("fetch", m_env, config.fetch, *m_pb, config.framebuffer, per_primitive);
  if (uses_evu(config.sim.mode))
    m_evu = std::make_unique<EarlyVisibilityUnit>("evu", m_env, config.evu, render_depth);
  if (uses_hsr(config.sim.mode)) m_hsr = std::make_unique<HsrUnit>("hsr", m_env, config.hsr);
  m_fragment = std::make_unique<FragmentUnit>("fragment", m_env, config.fragment, *m_pb);
  m_writer = std::make_unique<TileWriter>("writer", m_env, config.writer, config.framebuffer);

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
  m_fetch->ready(*m_ready);
  m_writer->released(*m_released);
  m_pb->released(*m_released);

  m_fetch->out(*fifo("fetch_to_visibility", render_depth));
  // Hybrid: the EVU, then the HSR unit; each resolves its own tiles and passes the others on.
  if (m_evu) {
    m_evu->in(*m_fifos.back());
    m_evu->out(*fifo(m_hsr ? "evu_to_hsr" : "visibility_to_fragment", render_depth));
  }
  if (m_hsr) {
    m_hsr->in(*m_fifos.back());
    m_hsr->out(*fifo("visibility_to_fragment", render_depth));
  }
  m_fragment->in(*m_fifos.back());
  m_fragment->out(*fifo("fragment_to_writer", render_depth));
  m_writer->in(*m_fifos.back());

  m_front_end->mem.bind(m_memory->socket);
  m_silhouette->mem.bind(m_memory->socket);
  m_tiling->pb.bind(m_pb->socket);
  m_pb->mem.bind(m_memory->socket);
  m_fetch->pb.bind(m_pb->socket);
  m_fetch->mem.bind(m_memory->socket);
  m_fragment->mem.bind(m_memory->socket);
  m_fragment->pb.bind(m_pb->socket);
  m_writer->mem.bind(m_memory->socket);
}

Tiler::~Tiler() = default;

void Tiler::prepare() {
  m_setup->prepare();
  m_tiling->prepare();
  m_front_end->prepare();
  m_silhouette->prepare();
  m_pb->prepare(*m_front_end);
}

uint64_t Tiler::run_analytic() {
  const uint64_t latency = m_memory->latency_cycles();
  uint64_t frame = 0, pb_written = 0, pb_read = 0;
  std::vector<Stage*> geometry = {m_setup.get(), m_silhouette.get(), m_tiling.get()};
  std::vector<Stage*> visibility;
  if (m_evu) visibility = {&m_evu->reject(), &m_evu->clip(), &m_evu->occlude()};
  if (m_hsr) visibility = {m_hsr.get()};

  for (uint32_t k = 0; k < m_work.segment_count(); ++k) {
    // Geometry: the units stream the segment; the slowest unit (or the bus) sets the pace.
    Item g;
    g.segment = k;
    g.first = m_work.segment_first(k);
    g.count = m_work.segment_end(k) - g.first;
    g.last = true;
    const Cost fe = m_front_end->cost(g);
    m_front_end->account(g, fe);
    uint64_t slowest = fe.cycles, bus = m_memory->account(fe.read_bytes, true);
    for (Stage* s : geometry) {
      const Cost c = s->cost(g);
      s->account(g, c);
      slowest = std::max(slowest, c.cycles);
      bus += m_memory->account(c.read_bytes, true) + m_memory->account(c.write_bytes, false);
      if (s == m_tiling.get()) pb_written += c.write_bytes;
    }
    frame += std::max(slowest, bus) + latency;

    // Render: tiles in order through a pipeline of units; a tile costs its slowest unit
    // (or its memory traffic), and the last tile drains through the rest.
    m_work.prepare_segment(k);
    uint64_t drain = 0;
    for (uint32_t tile : m_work.segment_tiles()) {
      TileWork* w = m_work.open_tile(tile);
      Item it = m_fetch->items(w).front();
      it.count = w->triangles();
      it.last = true;
      std::vector<uint64_t> unit_cycles;
      const Cost fc = m_fetch->cost(it);
      m_fetch->account(it, fc);
      pb_read += fc.read_bytes;
      uint64_t tile_bus = m_memory->account(fc.read_bytes, true) + m_memory->account(m_fetch->reload_bytes(it), true);
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
      if (m_evu) m_evu->account_analytic(evu_max);
      const Cost frc = m_fragment->cost(it);
      m_fragment->account(it, frc);
      m_fragment->tile_done(*w);
      tile_bus += m_memory->account(frc.read_bytes, true) + m_memory->account(frc.pb_read_bytes, true);
      pb_read += frc.pb_read_bytes;
      unit_cycles.push_back(frc.cycles);
      const Cost wc = m_writer->cost(it);
      m_writer->account(it, wc);
      tile_bus += m_memory->account(wc.write_bytes, false);
      unit_cycles.push_back(wc.cycles);
      uint64_t sum = 0, slowest_unit = 0;
      for (uint64_t c : unit_cycles) sum += c, slowest_unit = std::max(slowest_unit, c);
      frame += std::max(slowest_unit, tile_bus);
      drain = sum - slowest_unit;
      m_work.close_tile(w);
    }
    frame += drain + (m_work.segment_tiles().empty() ? 0 : latency);
    m_work.finish_segment();
  }
  m_pb->account_analytic(pb_written, pb_read);
  m_analytic_cycles = frame;
  return frame;
}

uint64_t Tiler::simulated_cycles() const { return m_writer->frame_end_cycle(); }
bool Tiler::frame_done() const { return m_writer->frame_done(); }

std::vector<const StatsGroup*> Tiler::stats_groups() const {
  std::vector<const StatsGroup*> g = {&m_memory->stats(), &m_front_end->stats(), &m_setup->stats(),
                                      &m_silhouette->stats(), &m_tiling->stats(), &m_pb->stats(), &m_fetch->stats()};
  if (m_evu) {
    g.push_back(&m_evu->stats());
    g.push_back(&m_evu->reject().stats());
    g.push_back(&m_evu->clip().stats());
    g.push_back(&m_evu->occlude().stats());
  }
  if (m_hsr) g.push_back(&m_hsr->stats());
  g.push_back(&m_fragment->stats());
  g.push_back(&m_writer->stats());
  return g;
}

void Tiler::trace(sc_core::sc_trace_file* tf) const {
  std::vector<const UnitBase*> units = {m_front_end.get(), m_setup.get(),  m_silhouette.get(), m_tiling.get(),
                                        m_fetch.get(),     m_fragment.get(), m_writer.get()};
  if (m_evu) {
    units.push_back(&m_evu->reject());
    units.push_back(&m_evu->clip());
    units.push_back(&m_evu->occlude());
  }
  if (m_hsr) units.push_back(m_hsr.get());
  for (const UnitBase* u : units) sc_core::sc_trace(tf, u->busy, std::string(u->name()) + ".busy");
  for (const auto& f : m_fifos) sc_core::sc_trace(tf, f->occupancy, std::string(f->name()) + ".occupancy");
  if (m_evu) {
    sc_core::sc_trace(tf, m_evu->reject_to_clip().occupancy, std::string(m_evu->reject_to_clip().name()) + ".occupancy");
    sc_core::sc_trace(tf, m_evu->clip_to_occlude().occupancy, std::string(m_evu->clip_to_occlude().name()) + ".occupancy");
  }
}

uint64_t Tiler::dram_bytes() const { return m_memory->bytes(); }
uint64_t Tiler::param_buffer_bytes() const { return uint64_t(m_pb->stats().value("bytes_written")); }
uint64_t Tiler::param_buffer_peak() const { return uint64_t(m_pb->stats().value("peak_bytes")); }
uint64_t Tiler::evu_busy_cycles() const { return m_evu ? m_evu->busy_cycles() : 0; }

}  // namespace tilevis::sim
