#include "units/memory/dram.h"

#include <algorithm>
#include <bit>
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
  if (config.banks > 1 && !(config.banks & (config.banks - 1)))
    while ((1u << m_bank_bits) < config.banks) ++m_bank_bits;
  // Every size a power of two (the defaults): the address map by shifts and masks.
  auto log2_exact = [](uint64_t v) { return v && !(v & (v - 1)) ? std::countr_zero(v) : -1; };
  const int il = log2_exact(config.interleave_bytes), ch = log2_exact(config.channels), row = log2_exact(config.row_bytes);
  if (m_bank_bits && il >= 0 && ch >= 0 && row >= 0) {
    m_il_bits = uint32_t(il);
    m_channel_bits = uint32_t(ch);
    m_row_bits = uint32_t(row);
    m_shift_map = true;
  }
}

Dram::Location Dram::locate(uint64_t a) const {
  // Channels interleaved every interleave_bytes; the byte address within the channel, its
  // row index (rows of every bank in turn) and the row within the bank. Shifts and masks
  // where every size is a power of two (the defaults), the same map.
  Location l;
  uint64_t row_index;
  if (m_shift_map) {
    const uint64_t block = a >> m_il_bits;
    l.channel = uint32_t(block & (m_cfg.channels - 1));
    row_index = (((block >> m_channel_bits) << m_il_bits) | (a & (m_cfg.interleave_bytes - 1))) >> m_row_bits;
    l.row = row_index >> m_bank_bits;
  } else {
    const uint64_t il = m_cfg.interleave_bytes;
    const uint64_t block = a / il;
    l.channel = uint32_t(block % m_cfg.channels);
    row_index = ((block / m_cfg.channels) * il + a % il) / m_cfg.row_bytes;
    l.row = row_index / m_cfg.banks;
  }
  // Permutation-based bank interleaving (Zhang, Zhu and Zhang, MICRO 2000): the row's
  // digits (base `banks`) are folded into the bank index, so that streams whose bases
  // are far apart (the regions of traffic.h) do not all start in the same bank.
  uint64_t fold = 0;
  if (m_bank_bits) {  // a power of two (JESD209-4: 8): the same digits by shifts
    const uint64_t mask = m_cfg.banks - 1;
    for (uint64_t r = l.row; r; r >>= m_bank_bits) fold += r & mask;
    l.bank = uint32_t((row_index + fold) & mask);
    return l;
  }
  for (uint64_t r = l.row; r; r /= m_cfg.banks) fold += r % m_cfg.banks;
  l.bank = uint32_t((row_index + fold) % m_cfg.banks);
  return l;
}

Dram::Plan Dram::plan_burst(uint64_t t, const Location& where, bool read) const {
  Plan p;
  p.where = where;
  const Channel& ch = m_channels[p.where.channel];
  const Bank& b = m_banks[size_t(p.where.channel) * m_cfg.banks + p.where.bank];
  // All-bank refresh every tREFI, lasting tRFC: a command inside a window waits for its
  // end, and every row of the channel is closed by it.
  uint64_t column = std::max(t, b.ready);
  p.window = column / m_refi;
  const bool refreshed = p.window > ch.refreshed;
  if (p.window > 0 && column < p.window * m_refi + m_rfc) {
    p.refresh_wait = p.window * m_refi + m_rfc - column;
    column = p.window * m_refi + m_rfc;
  }
  const int64_t open_row = refreshed ? -1 : b.open_row;
  if (open_row == int64_t(p.where.row)) {
    p.row = RowState::hit;
  } else {
    uint64_t activate = column;
    if (open_row >= 0) {
      p.row = RowState::conflict;
      const uint64_t precharge = std::max(column, b.activated + uint64_t(m_cfg.ras) * m_tck);
      activate = precharge + uint64_t(m_cfg.rp) * m_tck;
    } else {
      p.row = RowState::miss;
    }
    p.activate = activate;
    column = activate + uint64_t(m_cfg.rcd) * m_tck;
  }
  const uint64_t latency = uint64_t(read ? m_cfg.rl : m_cfg.wl) * m_tck;
  const uint64_t ready = column + latency;
  p.slot.data = std::max(ready, ch.bus_free);
  for (const Gap& g : ch.gaps)
    if (std::max(g.start, ready) + m_burst_ps <= g.end) {
      p.slot.data = std::max(g.start, ready);
      break;
    }
  p.slot.bus_wait = p.slot.data - (column + latency);
  p.slot.column = p.slot.data - latency;  // a column command waits for its data's bus slot
  return p;
}

BurstSlot Dram::issue(uint64_t at, const Location& where, bool read) {
  const Plan p = plan_burst(at, where, read);
  Channel& ch = m_channels[p.where.channel];
  Bank& b = m_banks[size_t(p.where.channel) * m_cfg.banks + p.where.bank];
  ++m_n.bursts;
  if (p.window > ch.refreshed) {
    m_n.refreshes += p.window - ch.refreshed;
    ch.refreshed = p.window;
    for (uint32_t k = 0; k < m_cfg.banks; ++k) m_banks[size_t(p.where.channel) * m_cfg.banks + k].open_row = -1;
  }
  m_n.refresh_wait_ps += p.refresh_wait;
  if (p.row == RowState::hit) {
    ++m_n.row_hits;
  } else {
    ++(p.row == RowState::conflict ? m_n.row_conflicts : m_n.row_misses);
    b.open_row = int64_t(p.where.row);
    b.activated = p.activate;
  }
  // The bus: a burst past its end leaves an idle stretch behind it; one inside a stretch
  // splits it. Stretches that end before this burst's arrival are of no more use.
  const uint64_t end = p.slot.data + m_burst_ps;
  if (p.slot.data >= ch.bus_free) {
    if (p.slot.data > ch.bus_free) ch.gaps.push_back({ch.bus_free, p.slot.data});
    ch.bus_free = end;
  } else {
    for (size_t i = 0; i < ch.gaps.size(); ++i) {
      Gap& g = ch.gaps[i];
      if (p.slot.data < g.start || end > g.end) continue;
      const Gap after{end, g.end};
      g.end = p.slot.data;
      if (after.end > after.start) ch.gaps.insert(ch.gaps.begin() + std::ptrdiff_t(i) + 1, after);
      break;
    }
  }
  std::erase_if(ch.gaps, [&](const Gap& g) { return g.end < g.start + m_burst_ps || g.end <= at; });
  if (ch.gaps.size() > kGaps) ch.gaps.erase(ch.gaps.begin(), ch.gaps.begin() + std::ptrdiff_t(ch.gaps.size() - kGaps));
  b.ready = p.slot.column + m_burst_ps;  // the next column command to this bank
  m_n.bus_busy_ps += m_burst_ps;
  return p.slot;
}

uint64_t Dram::access(uint64_t at, uint64_t address, uint64_t bytes, bool read) {
  if (bytes == 0) return at;
  const uint64_t bb = m_cfg.burst_bytes;
  uint64_t done = at;
  bool first = true;
  for (uint64_t a = address / bb * bb; a < address + bytes; a += bb) {
    const BurstSlot s = issue(at, a, read);
    const uint64_t t = read ? s.data + m_burst_ps : s.column;
    if (read || first) done = std::max(done, t);
    first = false;
  }
  return done;
}

}  // namespace tilevis::sim
