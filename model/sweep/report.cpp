// The report call: reports/make_report.py turns OUT (sweep.json and the point directories)
// into index.html, report.md, points.csv and figures/.
#include <spawn.h>
#include <sys/wait.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include <fmt/format.h>

#include "sweep/sweep.h"

extern char** environ;

namespace tilevis::sweep {

namespace fs = std::filesystem;

namespace {

fs::path report_script() {
  if (const char* env = std::getenv("TILEVIS_REPORT_SCRIPT"); env && *env) return env;
  return source_dir() / "reports" / "make_report.py";
}

}  // namespace

int make_report(const fs::path& out) {
  const fs::path script = report_script();
  if (!fs::is_regular_file(script))
    throw std::runtime_error(fmt::format("sweep: report generator {} not found (set TILEVIS_REPORT_SCRIPT)",
                                         script.string()));
  // Debian's python3 has python3-matplotlib; a python3 earlier on PATH (pyenv, venv) may not.
  std::string python = "python3";
  if (const char* env = std::getenv("TILEVIS_PYTHON"); env && *env) python = env;
  else if (fs::exists("/usr/bin/python3")) python = "/usr/bin/python3";
  std::vector<std::string> argv = {python, script.string(), out.string()};
  std::vector<char*> args;
  for (auto& a : argv) args.push_back(a.data());
  args.push_back(nullptr);
  pid_t pid = -1;
  if (int rc = posix_spawnp(&pid, python.c_str(), nullptr, nullptr, args.data(), environ); rc != 0)
    throw std::runtime_error(fmt::format("sweep: cannot run {} for the report: {}", python, std::strerror(rc)));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 1;
}

}  // namespace tilevis::sweep
