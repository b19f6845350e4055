#include "units/common/stage.h"

namespace tilevis::sim {

Stage::Stage(const sc_core::sc_module_name& name, const UnitEnv& env, const std::string& help, TileUnit column,
             bool resolves)
    : UnitBase(name, env, help), in("in"), out("out"), m_column(column), m_resolves(resolves) {
  SC_THREAD(run);
}

void Stage::account(const Item& item, const Cost& c) {
  m_busy.value += double(c.cycles);
  m_items.value += 1;
  m_bytes.value += double(c.reads.bytes() + c.writes.bytes() + c.pb_reads.bytes());
  if (item.tile && m_column != TileUnit::count) item.tile->cycles[size_t(m_column)] += c.cycles;
}

void Stage::run() {
  for (;;) {
    const Item item = in.read();
    if (item.kind == Item::Kind::work) {
      if (m_resolves && item.first_of_tile) m_work.resolve_tile(*item.tile);
      const Cost c = cost(item);
      sc_core::sc_time memory = sc_core::SC_ZERO_TIME;
      if (m_mem) {
        memory = transfer(*m_mem, tlm::TLM_READ_COMMAND, c.reads, m_latency_hidden);
        const sc_core::sc_time w = transfer(*m_mem, tlm::TLM_WRITE_COMMAND, c.writes);
        if (w > memory) memory = w;
      }
      if (m_pb) {
        const sc_core::sc_time v = transfer(*m_pb, tlm::TLM_READ_COMMAND, c.pb_reads, m_latency_hidden);
        if (v > memory) memory = v;
      }
      spend(c.cycles, memory, item.tile, m_column);
      m_items.value += 1;
      if (item.last && item.tile) tile_done(*item.tile);
    }
    push(out, item);
  }
}

}  // namespace tilevis::sim
