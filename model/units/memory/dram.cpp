#include "units/memory/dram.h"

#include <algorithm>
#include <stdexcept>

namespace tilevis::sim {

Dram::Dram(const DramConfig& config)
    : m_cfg(config),
      m_tck(config.tck_ps),
      m_burst_ps(uint64_t(config.ccd) * config.tck_ps),
      m_refi(uint64_t(config.refi) * config.tck_ps),
      m_rfc(uint64_t(config.rfc) * config.tck_ps),
      m_channels(config.channels),
      m_banks(size_t(config.channels) * config.banks) {
  if (!config.channels || !config.banks || !config.burst_bytes || !config.tck_ps || !config.ccd)
    throw std::invalid_argument("DRAM: channels, banks, burst bytes, tCK and CCD must be positive");
  if (config.row_bytes % config.burst_bytes || config.interleave_bytes % config.burst_bytes)
    throw std::invalid_argument("DRAM: row and interleave sizes must be whole bursts");
  if (config.rfc >= config.refi) throw std::invalid_argument("DRAM: refresh cycle time must be below its interval");
}

Dram::Location Dram::locate(uint64_t a) const {
  const uint64_t il = m_cfg.interleave_bytes;
  const uint64_t block = a / il;
  Location l;
  l.channel = uint32_t(block % m_cfg.channels);
  const uint64_t local = (block / m_cfg.channels) * il + a % il;  // byte address within the channel
  const uint64_t row_index = local / m_cfg.row_bytes;
  l.row = row_index / m_cfg.banks;
  // Permutation-based bank interleaving (Zhang, Zhu and Zhang, MICRO 2000): the row's
  // digits (base `banks`) are folded into the bank index, so that streams whose bases
  // are far apart (the regions of traffic.h) do not all start in the same bank.
  uint64_t fold = 0;
  for (uint64_t r = l.row; r; r /= m_cfg.banks) fold += r % m_cfg.banks;
  l.bank = uint32_t((row_index + fold) % m_cfg.banks);
  return l;
}

uint64_t Dram::burst(uint64_t t, uint64_t address, bool read) {
  const Location l = locate(address);
  Channel& ch = m_channels[l.channel];
  Bank& b = m_banks[size_t(l.channel) * m_cfg.banks + l.bank];
  ++m_n.bursts;
  ch.queued_until = std::max(ch.queued_until, t) + m_burst_ps;

  // All-bank refresh every tREFI, lasting tRFC: a burst inside a window waits for its
  // end, and every row of the channel is closed by it.
  const uint64_t window = t / m_refi;
  if (window > ch.refreshed) {
    m_n.refreshes += window - ch.refreshed;
    ch.refreshed = window;
    for (uint32_t k = 0; k < m_cfg.banks; ++k) m_banks[size_t(l.channel) * m_cfg.banks + k].open_row = -1;
  }
  if (window > 0 && t < window * m_refi + m_rfc) {
    m_n.refresh_wait_ps += window * m_refi + m_rfc - t;
    t = window * m_refi + m_rfc;
  }

  uint64_t column = std::max(t, b.ready);
  if (b.open_row == int64_t(l.row)) {
    ++m_n.row_hits;
  } else {
    uint64_t activate = column;
    if (b.open_row >= 0) {
      ++m_n.row_conflicts;
      const uint64_t precharge = std::max(column, b.activated + uint64_t(m_cfg.ras) * m_tck);
      activate = precharge + uint64_t(m_cfg.rp) * m_tck;
    } else {
      ++m_n.row_misses;
    }
    b.open_row = int64_t(l.row);
    b.activated = activate;
    column = activate + uint64_t(m_cfg.rcd) * m_tck;
  }
  const uint64_t latency = uint64_t(read ? m_cfg.rl : m_cfg.wl) * m_tck;
  const uint64_t data = std::max(column + latency, ch.bus_free);
  ch.bus_free = data + m_burst_ps;
  b.ready = data - latency + m_burst_ps;  // the next column command to this bank
  m_n.bus_busy_ps += m_burst_ps;
  return read ? data + m_burst_ps : data - latency;
}

uint64_t Dram::backlog(uint64_t at) const {
  uint64_t behind = 0;
  for (const Channel& ch : m_channels) behind += ch.queued_until > at ? ch.queued_until - at : 0;
  return behind / m_cfg.channels;
}

uint64_t Dram::access(uint64_t at, uint64_t address, uint64_t bytes, bool read) {
  if (bytes == 0) return at;
  const uint64_t bb = m_cfg.burst_bytes;
  uint64_t done = at;
  bool first = true;
  for (uint64_t a = address / bb * bb; a < address + bytes; a += bb) {
    const uint64_t t = burst(at, a, read);
    if (read || first) done = std::max(done, t);
    first = false;
  }
  return done;
}

}  // namespace tilevis::sim
