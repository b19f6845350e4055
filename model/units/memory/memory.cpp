#include "units/memory/memory.h"

#include <algorithm>

#include "units/common/unit_base.h"

namespace tilevis::sim {

const char* to_string(MemoryModel m) {
  switch (m) {
    case MemoryModel::automatic: return "auto";
    case MemoryModel::detailed: return "detailed";
    case MemoryModel::bandwidth: return "bandwidth";
  }
  return "?";
}

Memory::Memory(const sc_core::sc_module_name& name, const MemoryConfig& config, const sc_core::sc_time& period)
    : sc_core::sc_module(name),
      socket("socket"),
      m_cfg(config),
      m_ctrl(config.dram, config.controller),
      m_period(period),
      m_period_ps(period.value() / sc_core::sc_time(1, sc_core::SC_PS).value()),
      m_controller_ps(uint64_t(config.controller_latency_ns) * 1000),
      m_stats(std::string(sc_core::sc_module::name()), "memory system: LPDDR4-class DRAM shared by every unit"),
      m_read(m_stats.add("bytes_read", "bytes", "bytes read")),
      m_written(m_stats.add("bytes_written", "bytes", "bytes written")),
      m_transactions(m_stats.add("transactions", "transactions", "transfers served")),
      m_bursts(m_stats.add("bursts", "bursts", "DRAM bursts")),
      m_row_hits(m_stats.add("row_hits", "bursts", "bursts to an open row")),
      m_row_misses(m_stats.add("row_misses", "bursts", "bursts that opened a row in a closed bank")),
      m_row_conflicts(m_stats.add("row_conflicts", "bursts", "bursts that closed another row first")),
      m_refreshes(m_stats.add("refreshes", "refreshes", "all-bank refreshes, summed over the channels")),
      m_refresh_wait(m_stats.add("refresh_wait_cycles", "cycles", "time bursts waited for a refresh to end", false)),
      m_busy(m_stats.add("busy_cycles", "cycles", "data-bus cycles, averaged over the channels", false)),
      m_utilisation(m_stats.add("utilisation", "share", "busy_cycles / frame cycles", false)),
      m_read_bursts(m_stats.add("read_bursts", "bursts", "read bursts asked of the controller")),
      m_write_bursts(m_stats.add("write_bursts", "bursts", "write bursts posted to the controller, before combining")),
      m_reads_forwarded(m_stats.add("reads_forwarded", "bursts", "read bursts served from the write buffer")),
      m_reads_merged(m_stats.add("reads_merged", "bursts", "read bursts served by the same requester's burst already in the read queue")),
      m_writes_combined(m_stats.add("writes_combined", "bursts", "write bursts merged into one already in the write buffer")),
      m_drains(m_stats.add("write_drains", "batches", "write batches forced by the write buffer's high watermark")),
      m_drained_forced(m_stats.add("writes_drained_forced", "bursts", "write bursts sent in forced batches (or by a full buffer)")),
      m_drained_idle(m_stats.add("writes_drained_idle", "bursts", "write bursts sent in the data bus's idle gaps")),
      m_full_stalls(m_stats.add("write_buffer_full", "bursts", "posted write bursts that found the write buffer full")),
      m_write_stall(m_stats.add("write_stall_cycles", "cycles", "time posted writes waited for a write-buffer slot", false)),
      m_occupancy_mean(m_stats.add("write_buffer_occupancy", "bursts", "mean write-buffer occupancy (per channel) seen by a posted burst", false)),
      m_occupancy_peak(m_stats.add("write_buffer_peak", "bursts", "largest write-buffer occupancy (per channel) seen by a posted burst")),
      m_read_queue_full(m_stats.add("read_queue_full_cycles", "cycles", "time read bursts waited for a read-queue slot", false)),
      m_read_bus_wait(m_stats.add("read_queue_wait_cycles", "cycles", "time read bursts waited in the read queue for the bus, behind earlier bursts", false)) {
  socket.register_b_transport(this, &Memory::b_transport);
  if (config.model == MemoryModel::bandwidth) m_bw = std::make_unique<BandwidthModel>(config.dram, config.bandwidth_efficiency);
}

int Memory::attach(tlm_utils::simple_initiator_socket<UnitBase>& initiator, const std::string& stream) {
  initiator.bind(socket);
  int index = -1;
  for (size_t i = 0; i < m_streams.size(); ++i)
    if (m_streams[i]->name == "bytes_" + stream) index = int(i);
  if (index < 0) {
    m_streams.push_back(&m_stats.add("bytes_" + stream, "bytes", "bytes moved by the " + stream + " stream"));
    index = int(m_streams.size() - 1);
  }
  m_stream_of.push_back(index);
  return index;
}

uint64_t Memory::read_latency_cycles() const {
  const DramConfig& d = m_cfg.dram;
  const uint64_t ps = m_controller_ps + uint64_t(d.rcd + d.rl + d.ccd) * d.tck_ps;
  return (ps + m_period_ps - 1) / m_period_ps;
}

sc_core::sc_time Memory::occupy(const sc_core::sc_time& at, uint64_t address, uint64_t bytes, bool read, int stream,
                                bool hidden, int port) {
  if (bytes == 0) return sc_core::SC_ZERO_TIME;
  (read ? m_read : m_written).value += double(bytes);
  m_transactions.value += 1;
  if (stream >= 0 && size_t(stream) < m_streams.size()) m_streams[size_t(stream)]->value += double(bytes);
  const uint64_t ps = sc_core::sc_time(1, sc_core::SC_PS).value();
  const uint64_t at_ps = at.value() / ps;
  // A write is posted into the controller's write buffer: its issuer waits only while the
  // buffer is full. A read comes back through the fabric and controller; a latency-hidden
  // one waits only for its place on the bus.
  uint64_t wait = 0;
  if (m_bw) {
    // A posted write waits only for the room the write buffer's bursts give the bus; a read
    // for its data and the unloaded latency beyond it (a latency-hidden one: its data only).
    const uint64_t done = m_bw->transfer(at_ps, address, bytes);
    if (!read) {
      const uint64_t room = uint64_t(m_cfg.controller.write_buffer) * m_bw->burst_ps();
      wait = done > at_ps + room ? done - at_ps - room : 0;
    } else {
      const DramConfig& d = m_cfg.dram;
      wait = done - at_ps + (hidden ? 0 : m_controller_ps + uint64_t(d.rcd + d.rl) * d.tck_ps);
    }
    return sc_core::sc_time::from_value(wait * ps);
  }
  if (!read) {
    wait = m_ctrl.write(at_ps, address, bytes) - at_ps;
  } else {
    const DramController::ReadDone r = m_ctrl.read(at_ps, address, bytes, port);
    wait = hidden ? r.queued : r.done + m_controller_ps - at_ps;
  }
  return sc_core::sc_time::from_value(wait * ps);
}

uint64_t Memory::service(uint64_t at, const Traffic& traffic, bool read, int stream) {
  const sc_core::sc_time t = sc_core::sc_time::from_value(m_period.value() * at);
  uint64_t longest = 0;
  for (const Span& s : traffic.spans) {
    const uint64_t v = occupy(t, s.address, s.bytes, read, stream).value();
    longest = std::max(longest, v);
  }
  return (longest + m_period.value() - 1) / m_period.value();
}

void Memory::finish(uint64_t frame_cycles) {
  // The writes still buffered at the frame's end go to the DRAM (after the frame: the
  // next one's traffic would find them there), so that every burst is counted.
  if (m_bw) {  // bursts and bus time only: no rows, queues or drains in this model
    const double cycle = double(m_period_ps);
    m_bursts.value = double(m_bw->bursts());
    m_busy.value = double(m_bw->busy_ps()) / cycle / double(m_cfg.dram.channels);
    m_utilisation.value = frame_cycles ? m_busy.value / double(frame_cycles) : 0.0;
    return;
  }
  m_ctrl.flush();
  const DramCounters& n = m_ctrl.dram().counters();
  const ControllerCounters& q = m_ctrl.counters();
  const double cycle = double(m_period_ps);
  m_read_bursts.value = double(q.reads);
  m_write_bursts.value = double(q.writes);
  m_reads_forwarded.value = double(q.reads_forwarded);
  m_reads_merged.value = double(q.reads_merged);
  m_writes_combined.value = double(q.writes_combined);
  m_drains.value = double(q.drains);
  m_drained_forced.value = double(q.drained_forced);
  m_drained_idle.value = double(q.drained_idle);
  m_full_stalls.value = double(q.full_stalls);
  m_write_stall.value = double(q.write_stall_ps) / cycle;
  m_occupancy_mean.value = q.writes ? double(q.occupancy_sum) / double(q.writes) : 0.0;
  m_occupancy_peak.value = double(q.occupancy_peak);
  m_read_queue_full.value = double(q.read_queue_full_ps) / cycle;
  m_read_bus_wait.value = double(q.read_bus_wait_ps) / cycle;
  m_bursts.value = double(n.bursts);
  m_row_hits.value = double(n.row_hits);
  m_row_misses.value = double(n.row_misses);
  m_row_conflicts.value = double(n.row_conflicts);
  m_refreshes.value = double(n.refreshes);
  m_refresh_wait.value = double(n.refresh_wait_ps) / double(m_period_ps);
  m_busy.value = double(n.bus_busy_ps) / double(m_period_ps) / double(m_cfg.dram.channels);
  m_utilisation.value = frame_cycles ? m_busy.value / double(frame_cycles) : 0.0;
}

void Memory::b_transport(int id, tlm::tlm_generic_payload& p, sc_core::sc_time& delay) {
  const sc_core::sc_time at = sc_core::sc_time_stamp() + delay;
  LatencyHidden* hidden = nullptr;
  p.get_extension(hidden);
  delay += occupy(at, p.get_address(), p.get_data_length(), p.is_read(), size_t(id) < m_stream_of.size() ? m_stream_of[size_t(id)] : -1, hidden != nullptr, id);
  p.set_response_status(tlm::TLM_OK_RESPONSE);
}

}  // namespace tilevis::sim
