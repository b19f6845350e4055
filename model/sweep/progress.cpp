#include "sweep/progress.h"

#include <algorithm>

#include <fmt/format.h>

#include "sweep/detail.h"

namespace tilevis::sweep::detail {

void EtaModel::add(const std::string& cls, double seconds, double megasamples) {
  auto& r = m_rate[cls];
  r.first += seconds;
  r.second += megasamples;
}

double EtaModel::estimate(const std::string& cls, double megasamples) const {
  auto it = m_rate.find(cls);
  double s = 0, w = 0;
  if (it != m_rate.end()) s = it->second.first, w = it->second.second;
  else
    for (const auto& [k, v] : m_rate) s += v.first, w += v.second;
  return w > 0 ? s / w * megasamples : -1.0;
}

std::string progress_line(size_t finished, size_t total, double elapsed, double eta, size_t running,
                          const std::string& event) {
  return fmt::format("[{}/{}] {:3.0f} %  elapsed {}  ETA {}  running {}{}{}", finished, total,
                     100.0 * double(finished) / double(std::max<size_t>(1, total)), duration_text(elapsed),
                     eta < 0 ? "?" : duration_text(eta), running, event.empty() ? "" : "  ", event);
}

}  // namespace tilevis::sweep::detail
