#include "units/memory/dram_controller.h"

#include <algorithm>
#include <stdexcept>

namespace tilevis::sim {

DramController::DramController(const DramConfig& dram, const ControllerConfig& config)
    : m_dram(dram),
      m_cfg(config),
      m_wl_ps(uint64_t(dram.wl) * dram.tck_ps),
      m_ch(dram.channels) {
  if (!config.read_queue || !config.write_buffer || !config.frfcfs_window)
    throw std::invalid_argument("DRAM controller: queue depths and the FR-FCFS window must be positive");
  if (config.read_merge > 1) throw std::invalid_argument("DRAM controller: read merge is 0 or 1");
  if (config.write_low >= config.write_high || config.write_high > config.write_buffer)
    throw std::invalid_argument("DRAM controller: watermarks must satisfy low < high <= write buffer");
}

void DramController::retire(uint32_t c, uint64_t at) {
  Channel& ch = m_ch[c];
  while (!ch.sent.empty() && ch.sent.front() <= at) ch.sent.pop_front();
  while (!ch.reads.empty() && ch.reads.front().end <= at) {
    --ch.read_keys[key(ch.reads.front().address)];
    ch.reads.pop_front();
  }
}

size_t DramController::pick(uint32_t c) const {
  const std::vector<Write>& p = m_ch[c].pending;
  const size_t n = std::min<size_t>(p.size(), m_cfg.frfcfs_window);
  for (size_t i = 0; i < n; ++i)
    if (m_dram.open_row(c, p[i].where.bank) == int64_t(p[i].where.row)) return i;  // first ready: a row hit
  return 0;  // first come
}

uint64_t DramController::send(uint32_t c, size_t index, uint64_t at) {
  Channel& ch = m_ch[c];
  const Write w = ch.pending[index];
  ch.pending.erase(ch.pending.begin() + std::ptrdiff_t(index));
  --ch.pending_keys[key(w.address)];
  const BurstSlot s = m_dram.issue(std::max(at, w.arrived), w.where, false);
  ch.sent.insert(std::upper_bound(ch.sent.begin(), ch.sent.end(), s.data), s.data);  // a burst may fill an earlier gap
  return s.data;
}

void DramController::advance(uint32_t c, uint64_t at) {
  // Idle gaps: above the low watermark a write goes whenever its column command can issue
  // before the next read arrives (at); a command already issued is not taken back.
  Channel& ch = m_ch[c];
  while (ch.pending.size() > m_cfg.write_low && m_dram.bus_first_idle(c) < at + m_wl_ps) {
    const size_t i = pick(c);
    const BurstSlot s = m_dram.plan(ch.pending[i].arrived, ch.pending[i].where, false);
    if (s.column >= at) break;
    send(c, i, ch.pending[i].arrived);
    ++m_n.drained_idle;
  }
  retire(c, at);
}

uint64_t DramController::read_burst(uint64_t at, uint64_t address, int source, uint64_t& accepted) {
  const Dram::Location l = m_dram.locate(address);
  const uint32_t c = l.channel;
  Channel& ch = m_ch[c];
  advance(c, at);
  ++m_n.reads;
  if (ch.pending_keys[key(address)])
    for (const Write& w : ch.pending)
      if (w.address == address) {
        ++m_n.reads_forwarded;
        accepted = at;
        return at;
      }
  if (m_cfg.read_merge && ch.read_keys[key(address)])
    for (const Read& r : ch.reads)
      if (r.address == address && r.source == source) {  // in flight: its data serves this read too
        ++m_n.reads_merged;
        accepted = at;
        return r.end;
      }
  uint64_t accept = at;
  if (ch.reads.size() >= m_cfg.read_queue) {
    accept = ch.reads[ch.reads.size() - m_cfg.read_queue].end;  // the queue has a free slot from here
    m_n.read_queue_full_ps += accept - at;
  }
  const BurstSlot s = m_dram.issue(accept, l, true);
  m_n.read_bus_wait_ps += s.bus_wait;
  accepted = accept;
  const uint64_t end = s.data + m_dram.burst_ps();
  const Read r{end, address, source};
  ++ch.read_keys[key(address)];
  ch.reads.insert(std::upper_bound(ch.reads.begin(), ch.reads.end(), r, [](const Read& x, const Read& y) { return x.end < y.end; }), r);
  return end;
}

uint64_t DramController::write_burst(uint64_t at, uint64_t address) {
  const Dram::Location l = m_dram.locate(address);
  const uint32_t c = l.channel;
  Channel& ch = m_ch[c];
  advance(c, at);
  ++m_n.writes;
  const uint64_t occupancy = ch.pending.size() + ch.sent.size();
  m_n.occupancy_sum += occupancy;
  m_n.occupancy_peak = std::max(m_n.occupancy_peak, occupancy);
  if (ch.pending_keys[key(address)])
    for (const Write& w : ch.pending)
      if (w.address == address) {
        ++m_n.writes_combined;
        return at;
      }
  // Full: wait until the oldest sent write's data has left the buffer (or send one).
  uint64_t t = at;
  while (ch.pending.size() + ch.sent.size() >= m_cfg.write_buffer) {
    if (ch.sent.empty()) {
      send(c, pick(c), t);
      ++m_n.drained_forced;
    }
    t = std::max(t, ch.sent.front());
    retire(c, t);
  }
  if (t > at) {
    ++m_n.full_stalls;
    m_n.write_stall_ps += t - at;
  }
  ch.pending.push_back({address, t, l});
  ++ch.pending_keys[key(address)];
  // High watermark: a batch to the bus now, ahead of later reads, down to the low one.
  if (ch.pending.size() + ch.sent.size() >= m_cfg.write_high) {
    ++m_n.drains;
    while (ch.pending.size() > m_cfg.write_low) {
      send(c, pick(c), t);
      ++m_n.drained_forced;
    }
  }
  return t;
}

DramController::ReadDone DramController::read(uint64_t at, uint64_t address, uint64_t bytes, int source) {
  // The bursts enter the read queue in order: one that waits for a slot holds the rest.
  ReadDone r{at, 0};
  const uint64_t bb = m_dram.config().burst_bytes;
  uint64_t t = at;
  for (uint64_t a = address / bb * bb; a < address + bytes; a += bb) r.done = std::max(r.done, read_burst(t, a, source, t));
  r.queued = t - at;
  return r;
}

uint64_t DramController::write(uint64_t at, uint64_t address, uint64_t bytes) {
  // The writer posts its bursts in order: one that waits for a slot holds the rest.
  uint64_t t = at;
  const uint64_t bb = m_dram.config().burst_bytes;
  for (uint64_t a = address / bb * bb; a < address + bytes; a += bb) t = write_burst(t, a);
  return t;
}

void DramController::flush() {
  for (uint32_t c = 0; c < m_ch.size(); ++c)
    while (!m_ch[c].pending.empty()) {
      const size_t i = pick(c);
      send(c, i, m_ch[c].pending[i].arrived);
      ++m_n.drained_flush;
    }
}

uint32_t DramController::write_occupancy(uint32_t c, uint64_t at) const {
  const Channel& ch = m_ch[c];
  return uint32_t(ch.pending.size() + size_t(std::count_if(ch.sent.begin(), ch.sent.end(), [&](uint64_t d) { return d > at; })));
}

}  // namespace tilevis::sim
