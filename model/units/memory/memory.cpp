#include "units/memory/memory.h"

namespace tilevis::sim {

Memory::Memory(const sc_core::sc_module_name& name, const MemoryConfig& config, const sc_core::sc_time& period)
    : sc_core::sc_module(name),
      socket("socket"),
      m_cfg(config),
      m_period(period),
      m_latency(sc_core::sc_time::from_value(period.value() * config.latency_cycles)),
      m_stats(std::string(sc_core::sc_module::name()), "DRAM: every unit's traffic through one data bus"),
      m_read(m_stats.add("bytes_read", "bytes", "bytes read")),
      m_written(m_stats.add("bytes_written", "bytes", "bytes written")),
      m_transactions(m_stats.add("transactions", "transactions", "TLM transactions served")),
      m_busy(m_stats.add("busy_cycles", "cycles", "cycles the data bus transfers", false)),
      m_queue(m_stats.add("queue_cycles", "cycles", "cycles transactions waited for the bus (contention)", false)) {
  socket.register_b_transport(this, &Memory::b_transport);
}

uint64_t Memory::account(uint64_t bytes, bool read) {
  if (bytes == 0) return 0;
  (read ? m_read : m_written).value += double(bytes);
  m_transactions.value += 1;
  m_busy.value += double(bytes) / double(m_cfg.bytes_per_cycle);
  return (bytes + m_cfg.bytes_per_cycle - 1) / m_cfg.bytes_per_cycle;
}

sc_core::sc_time Memory::occupy(const sc_core::sc_time& at, uint64_t bytes, bool read) {
  account(bytes, read);
  const sc_core::sc_time start = m_free_at > at ? m_free_at : at;
  // The bus holds bytes / bandwidth cycles, to the picosecond: no rounding per transaction,
  // so a stream cut into per-primitive transactions takes the same time as one transfer.
  const sc_core::sc_time hold = sc_core::sc_time::from_value(
      sc_dt::uint64(double(m_period.value()) * double(bytes) / double(m_cfg.bytes_per_cycle) + 0.5));
  m_free_at = start + hold;
  m_queue.value += double((start - at).value()) / double(m_period.value());
  // Reads return after the latency; writes are posted once the bus has taken the data.
  return (start - at) + hold + (read ? m_latency : sc_core::SC_ZERO_TIME);
}

void Memory::b_transport(int, tlm::tlm_generic_payload& p, sc_core::sc_time& delay) {
  const sc_core::sc_time at = sc_core::sc_time_stamp() + delay;
  delay += occupy(at, p.get_data_length(), p.is_read());
  p.set_response_status(tlm::TLM_OK_RESPONSE);
}

}  // namespace tilevis::sim
