// Progress and time left: the ETA model both the local runner's progress line and
// `tilevis sweep --status` use. A job's time is estimated from its class's measured seconds
// per megasample (a producer, "trace" or "compare"), or from every class's when its own has
// none yet.
#pragma once

#include <map>
#include <string>
#include <utility>

namespace tilevis::sweep::detail {

class EtaModel {
 public:
  void add(const std::string& cls, double seconds, double megasamples);
  // Seconds for `megasamples` of work of class `cls`; negative when nothing is measured yet.
  double estimate(const std::string& cls, double megasamples) const;
  bool empty() const { return m_rate.empty(); }

 private:
  std::map<std::string, std::pair<double, double>> m_rate;  // class -> (seconds, megasamples)
};

// "[done/total] pct %  elapsed E  ETA T  running R  event"; eta < 0 prints "?".
std::string progress_line(size_t finished, size_t total, double elapsed, double eta, size_t running,
                          const std::string& event);

}  // namespace tilevis::sweep::detail
