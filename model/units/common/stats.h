// Statistics as named groups with units and help text (gem5's ADD_STAT, DRAMSys's
// per-module groups): each unit owns its group, one walker dumps every group as JSON.
#pragma once

#include <deque>
#include <string>

#include <nlohmann/json.hpp>

namespace tilevis::sim {

struct Stat {
  std::string name, unit, help;
  double value = 0;        // counts stay exact below 2^53
  bool integer = true;     // printed as an integer
};

class StatsGroup {
 public:
  StatsGroup(std::string name, std::string help) : m_name(std::move(name)), m_help(std::move(help)) {}
  StatsGroup(const StatsGroup&) = delete;
  StatsGroup& operator=(const StatsGroup&) = delete;

  // The returned reference stays valid for the group's lifetime.
  Stat& add(std::string name, std::string unit, std::string help, bool integer = true) {
    m_stats.push_back({std::move(name), std::move(unit), std::move(help), 0.0, integer});
    return m_stats.back();
  }
  const std::string& name() const { return m_name; }
  const std::string& help() const { return m_help; }
  const std::deque<Stat>& stats() const { return m_stats; }
  const Stat* find(const std::string& name) const {
    for (const Stat& s : m_stats)
      if (s.name == name) return &s;
    return nullptr;
  }
  double value(const std::string& name) const {
    const Stat* s = find(name);
    return s ? s->value : 0.0;
  }

  // {"help": ..., "stats": {name: {"value", "unit", "help"}}}
  nlohmann::json to_json() const {
    nlohmann::json stats = nlohmann::json::object();
    for (const Stat& s : m_stats) {
      nlohmann::json v = s.integer ? nlohmann::json(static_cast<uint64_t>(s.value < 0 ? 0 : s.value))
                                   : nlohmann::json(s.value);
      stats[s.name] = {{"value", v}, {"unit", s.unit}, {"help", s.help}};
    }
    return {{"help", m_help}, {"stats", stats}};
  }

 private:
  std::string m_name, m_help;
  std::deque<Stat> m_stats;
};

}  // namespace tilevis::sim
