#include "progress.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include <fmt/format.h>
#include <unistd.h>

namespace tilevis::app {
namespace {

std::string duration(double s) {
  if (s < 60) return fmt::format("{:.0f} s", s);
  if (s < 3600) return fmt::format("{:.0f} min {:02.0f} s", s / 60 - 0.5, std::fmod(s, 60.0));
  return fmt::format("{:.1f} h", s / 3600);
}

}  // namespace

Progress::Progress(std::string what) : m_what(std::move(what)) {
  const char* env = std::getenv("TILEVIS_PROGRESS");
  m_enabled = env ? std::strcmp(env, "0") != 0 : ::isatty(STDERR_FILENO) == 1;
  m_start = m_last = std::chrono::steady_clock::now();
}

Progress::~Progress() {
  if (m_drawn) std::fputc('\n', stderr);
}

void Progress::update(uint64_t done, uint64_t total) {
  if (!m_enabled || total == 0) return;
  const auto now = std::chrono::steady_clock::now();
  const bool last = done >= total;
  if (!last && now - m_last < std::chrono::milliseconds(500)) return;
  // Nothing to show for runs that end within the first second.
  if (!m_drawn && !last && now - m_start < std::chrono::seconds(1)) return;
  if (!m_drawn && last) return;
  m_last = now;
  const double elapsed = std::chrono::duration<double>(now - m_start).count();
  const double share = double(done) / double(total);
  const std::string left = share > 0 && !last ? ", about " + duration(elapsed * (1 - share) / share) + " left" : "";
  std::fprintf(stderr, "\r%s: %5.1f %% after %s%s\033[K", m_what.c_str(), 100.0 * share, duration(elapsed).c_str(),
               left.c_str());
  std::fflush(stderr);
  m_drawn = true;
}

}  // namespace tilevis::app
