#include "sim_support.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <systemc>

// libsystemc brings a main() that calls sc_main(); GoogleTest's main() is used instead.
int sc_main(int, char**) { return 1; }

namespace tilevis::simtest {

nlohmann::json in_child(const std::function<nlohmann::json()>& fn) {
  int fds[2];
  if (pipe(fds) != 0) return {{"error", "pipe failed"}};
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return {{"error", "fork failed"}};
  if (pid == 0) {
    close(fds[0]);
    std::string text;
    int code = 0;
    try {
      text = fn().dump();
    } catch (const std::exception& e) {
      text = nlohmann::json{{"error", e.what()}}.dump();
      code = 1;
    }
    for (size_t off = 0; off < text.size();) {
      const ssize_t n = write(fds[1], text.data() + off, text.size() - off);
      if (n <= 0) break;
      off += size_t(n);
    }
    close(fds[1]);
    std::fflush(nullptr);
    _exit(code);
  }
  close(fds[1]);
  std::string text;
  char buf[65536];
  for (ssize_t n; (n = read(fds[0], buf, sizeof buf)) > 0;) text.append(buf, size_t(n));
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (!WIFEXITED(status)) return {{"error", "child died with signal " + std::to_string(WTERMSIG(status))}};
  auto j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded()) return {{"error", "child wrote no result (exit " + std::to_string(WEXITSTATUS(status)) + ")"}};
  return j;
}

const char* const kCubes = R"({
  "viewport": [320, 240],
  "camera": {"eye": [1.6, 1.2, 3.0], "target": [0, 0, 0], "fov_y_deg": 50, "near": 0.1, "far": 20},
  "objects": [
    {"name": "floor", "primitive": {"type": "plane", "size": [6, 6], "subdivisions": 3}, "transform": {"translate": [0, -0.6, 0]}},
    {"name": "box", "primitive": {"type": "box", "size": [1, 1, 1]}, "transform": {"rotate_deg": [10, 30, 0]}},
    {"name": "ball", "primitive": {"type": "sphere", "radius": 0.45, "segments": 24, "rings": 12},
     "transform": {"translate": [-0.9, -0.1, 0.8]}},
    {"name": "cards", "primitive": {"type": "quads", "count": 4, "size": [0.5, 0.7], "origin": [1.6, 0, 1.5], "step": [-0.1, 0.05, -0.25]}}
  ]})";

const char* const kSpheres = R"({
  "viewport": [256, 192],
  "camera": {"eye": [0, 2.5, 4.5], "target": [0, 0, 0], "fov_y_deg": 45, "near": 0.5, "far": 30},
  "objects": [
    {"name": "ground", "primitive": {"type": "plane", "size": [8, 8], "subdivisions": 4}, "transform": {"translate": [0, -0.5, 0]}},
    {"name": "ball", "primitive": {"type": "sphere", "radius": 0.35, "segments": 16, "rings": 8},
     "grid": {"count": [4, 1, 3], "spacing": [0.9, 0, 0.9]}, "transform": {"translate": [-1.35, 0, -0.9]}}
  ]})";

}  // namespace tilevis::simtest
