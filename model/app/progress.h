// Progress of a long single run on a terminal: one line on stderr, rewritten in place at most
// every half second, with the share done, the elapsed time and an estimate of what is left.
// Silent when stderr is not a terminal (logs, sweeps, tests) unless TILEVIS_PROGRESS=1.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace tilevis::app {

class Progress {
 public:
  explicit Progress(std::string what);
  ~Progress();  // ends the line if one was drawn
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  bool enabled() const { return m_enabled; }
  // done out of total units of work; draws when due.
  void update(uint64_t done, uint64_t total);

 private:
  std::string m_what;
  bool m_enabled = false, m_drawn = false;
  std::chrono::steady_clock::time_point m_start, m_last;
};

}  // namespace tilevis::app
