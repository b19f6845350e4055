#include "units/common/unit_base.h"

#include "units/memory/memory.h"

namespace tilevis::sim {

UnitBase::UnitBase(const sc_core::sc_module_name& name, const UnitEnv& env, const std::string& help)
    : sc_core::sc_module(name),
      m_work(*env.work),
      m_period(env.period),
      m_trace(env.trace),
      m_waits(env.waits),
      m_stats(std::string(sc_core::sc_module::name()), help),
      m_busy(m_stats.add("busy_cycles", "cycles", "cycles spent on the unit's own work")),
      m_stall(m_stats.add("stall_cycles", "cycles",
                          "cycles blocked: output FIFO full, memory slower than the work, parameter buffer full")),
      m_items(m_stats.add("items", "transactions", "work transactions processed")),
      m_bytes(m_stats.add("bytes", "bytes", "bytes moved to or from memory")) {}

void UnitBase::enter_busy() {
  if (m_active++ == 0) m_active_since = sc_core::sc_time_stamp();
}

void UnitBase::leave_busy() {
  // The union of the sub-units' busy intervals (their own signals go to the VCD).
  if (--m_active == 0) m_busy.value += double(cycles(sc_core::sc_time_stamp() - m_active_since));
}

void UnitBase::spend(uint64_t n, const sc_core::sc_time& memory, TileWork* tile, TileUnit column) {
  const sc_core::sc_time work = time(n);
  const sc_core::sc_time total = memory > work ? memory : work;
  if (tile && column != TileUnit::count) tile->cycles[size_t(column)] += n;
  if (total == sc_core::SC_ZERO_TIME) return;
  m_stall.value += double(cycles(total - work));
  if (m_parent) m_parent->enter_busy();
  busy = true;
  sc_core::wait(work);
  m_busy.value += double(n);
  busy = false;
  if (total > work) {
    if (m_waits) m_waits->enter();
    sc_core::wait(total - work);
    if (m_waits) m_waits->leave();
  }
  if (m_parent) m_parent->leave_busy();
}

void UnitBase::push(sc_core::sc_fifo_out<Item>& out, const Item& item) {
  if (out->num_free() > 0) {
    out->write(item);
    return;
  }
  const sc_core::sc_time t0 = sc_core::sc_time_stamp();
  out->write(item);
  m_stall.value += double(cycles(sc_core::sc_time_stamp() - t0));
}

sc_core::sc_time UnitBase::transfer(tlm_utils::simple_initiator_socket<UnitBase>& socket, tlm::tlm_command cmd,
                                    const Traffic& traffic, bool latency_hidden) {
  sc_core::sc_time longest = sc_core::SC_ZERO_TIME;
  for (const Span& s : traffic.spans) {
    tlm::tlm_generic_payload p;
    p.set_command(cmd);
    p.set_address(s.address);
    p.set_data_ptr(&m_dummy);
    p.set_data_length(uint32_t(std::min<uint64_t>(s.bytes, 0xffffffffu)));
    p.set_streaming_width(p.get_data_length());
    p.set_byte_enable_ptr(nullptr);
    p.set_dmi_allowed(false);
    p.set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
    LatencyHidden hidden;
    if (latency_hidden && cmd == tlm::TLM_READ_COMMAND) p.set_extension(&hidden);
    sc_core::sc_time delay = sc_core::SC_ZERO_TIME;
    const sc_core::sc_time t0 = sc_core::sc_time_stamp();
    socket->b_transport(p, delay);
    if (p.is_response_error()) SC_REPORT_ERROR(name(), "memory transaction failed");
    m_stall.value += double(cycles(sc_core::sc_time_stamp() - t0));
    m_bytes.value += double(s.bytes);
    if (latency_hidden && cmd == tlm::TLM_READ_COMMAND) p.clear_extension(&hidden);
    if (delay > longest) longest = delay;
  }
  return longest;
}

}  // namespace tilevis::sim
