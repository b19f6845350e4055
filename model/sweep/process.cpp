// Subprocesses, files and words: the plumbing every part of the sweep engine uses, and the
// machine and commit recorded with every result.
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <sstream>
#include <string_view>
#include <thread>

#include <fmt/format.h>

#include "sweep/detail.h"

namespace tilevis::sweep {

namespace fs = std::filesystem;

namespace detail {

std::vector<std::string> split_words(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> words;
  std::string w;
  while (in >> w) words.push_back(w);
  return words;
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (size_t pos = 0; (pos = s.find(from, pos)) != std::string::npos; pos += to.size()) s.replace(pos, from.size(), to);
  return s;
}

std::string shell_quote(const std::string& s) {
  bool plain = !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || std::strchr("_-./=:,+@%", c);
  });
  if (plain) return s;
  return "'" + replace_all(s, "'", "'\\''") + "'";
}

// Between fork and exec only async-signal-safe calls. The child asks the kernel to kill it
// when its parent dies (PR_SET_PDEATHSIG), so a sweep killed with SIGKILL (or a Slurm task
// cancelled) leaves no point writing into its folder.
Spawned spawn(const std::vector<std::string>& argv, const fs::path& log, const std::vector<std::string>& env) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  // The child's environment, made before fork (nothing after it may allocate).
  std::vector<char*> envp;
  for (char** e = environ; *e; ++e) {
    const std::string_view entry(*e);
    const bool replaced = std::any_of(env.begin(), env.end(), [&](const std::string& n) {
      const size_t eq = n.find('=');
      return entry.substr(0, entry.find('=')) == std::string_view(n).substr(0, eq);
    });
    if (!replaced) envp.push_back(*e);
  }
  for (const std::string& n : env) envp.push_back(const_cast<char*>(n.c_str()));
  envp.push_back(nullptr);
  const std::string log_path = log.string();
  const pid_t parent = getpid();
  int err_pipe[2];
  Spawned s;
  if (pipe2(err_pipe, O_CLOEXEC) != 0) {
    s.error = fmt::format("cannot start {}: {}", argv[0], std::strerror(errno));
    return s;
  }
  s.pid = fork();
  if (s.pid == 0) {
    int e = 0;
    if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || getppid() != parent) _exit(127);  // the sweep is gone already
    const int in = open("/dev/null", O_RDONLY);
    const int out = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (in < 0 || out < 0 || dup2(in, 0) < 0 || dup2(out, 1) < 0 || dup2(out, 2) < 0) {
      e = errno;
    } else {
      execvpe(args[0], args.data(), envp.data());
      e = errno;
    }
    (void)!write(err_pipe[1], &e, sizeof e);
    _exit(127);
  }
  close(err_pipe[1]);
  if (s.pid < 0) {
    s.error = fmt::format("cannot start {}: {}", argv[0], std::strerror(errno));
    close(err_pipe[0]);
    return s;
  }
  int e = 0;
  ssize_t n;
  while ((n = read(err_pipe[0], &e, sizeof e)) < 0 && errno == EINTR) {
  }
  close(err_pipe[0]);
  if (n == ssize_t(sizeof e)) {  // exec failed: the child has exited
    int status = 0;
    while (waitpid(s.pid, &status, 0) < 0 && errno == EINTR) {
    }
    s.pid = -1;
    s.error = fmt::format("cannot start {}: {}", argv[0], std::strerror(e));
  }
  return s;
}

// Runs argv to completion; its stdout and stderr in `output`. Returns the exit status (-1: not run).
int run_capture(const std::vector<std::string>& argv, std::string* output) {
  char name[] = "/tmp/tilevis-sweep-XXXXXX";
  int fd = mkstemp(name);
  if (fd < 0) return -1;
  close(fd);
  Spawned s = spawn(argv, name);
  int status = -1;
  if (s.pid > 0) {
    while (waitpid(s.pid, &status, 0) < 0 && errno == EINTR) {
    }
  }
  if (output) {
    std::ifstream in(name);
    std::stringstream ss;
    ss << in.rdbuf();
    *output = ss.str();
  }
  std::remove(name);
  if (s.pid <= 0) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

std::string last_line(const fs::path& file) {
  std::ifstream in(file);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

std::string now_iso() {
  std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S%z", std::localtime(&t));
  return buf;
}

void write_json_atomically(const fs::path& file, const nlohmann::json& j) {
  const fs::path tmp = file.string() + ".tmp";
  {
    errno = 0;
    std::ofstream o(tmp);
    if (!o) throw SweepError(fmt::format("cannot write {}: {}", tmp.string(), std::strerror(errno ? errno : EIO)));
    o << j.dump(2) << '\n';
    if (!o) throw SweepError(fmt::format("cannot write {}: {}", tmp.string(), std::strerror(errno ? errno : EIO)));
  }
  std::error_code ec;
  fs::rename(tmp, file, ec);
  if (ec) throw SweepError(fmt::format("cannot rename {} to {}: {}", tmp.string(), file.string(), ec.message()));
}

std::string duration_text(double s) {
  if (!(s >= 0) || s > 1e7) return "?";
  auto t = static_cast<long>(s + 0.5);
  return t >= 3600 ? fmt::format("{}:{:02}:{:02}", t / 3600, t / 60 % 60, t % 60) : fmt::format("{}:{:02}", t / 60, t % 60);
}

std::string last_line_of_text(const std::string& text) {
  std::istringstream lines(text);
  std::string last;
  for (std::string l; std::getline(lines, l);)
    if (!l.empty()) last = l;
  return last;
}

nlohmann::json read_json_or_null(const fs::path& file) {
  std::ifstream in(file);
  if (!in) return nullptr;
  try {
    return nlohmann::json::parse(in);
  } catch (const std::exception&) {
    return nullptr;
  }
}

double megasamples(Size r, uint32_t samples) { return double(r.width) * r.height * samples / 1e6; }

}  // namespace detail

using namespace detail;

nlohmann::json machine_info() {
  nlohmann::json m;
  utsname u{};
  if (uname(&u) == 0) {
    m["host"] = u.nodename;
    m["os"] = fmt::format("{} {} {}", u.sysname, u.release, u.machine);
  }
  std::ifstream cpu("/proc/cpuinfo");
  for (std::string line; std::getline(cpu, line);)
    if (line.rfind("model name", 0) == 0) {
      auto colon = line.find(':');
      m["cpu"] = colon == std::string::npos ? line : line.substr(colon + 2);
      break;
    }
  m["cores"] = std::thread::hardware_concurrency();
  std::ifstream mem("/proc/meminfo");
  for (std::string line; std::getline(mem, line);)
    if (line.rfind("MemTotal:", 0) == 0) {
      m["memory_gib"] = std::round(std::stod(line.substr(9)) / (1 << 20) * 10) / 10;
      break;
    }
  return m;
}

std::string source_commit() {
  if (const char* env = std::getenv("TILEVIS_COMMIT"); env && *env) return env;  // a copy without .git
  std::string head, status;
  const std::string dir = source_dir().string();
  if (run_capture({"git", "-C", dir, "rev-parse", "--short", "HEAD"}, &head) != 0) return "unknown";
  head.erase(head.find_last_not_of(" \n\r\t") + 1);
  if (run_capture({"git", "-C", dir, "status", "--porcelain", "--untracked-files=no"}, &status) == 0 && !status.empty())
    head += "-dirty";
  return head;
}

}  // namespace tilevis::sweep
