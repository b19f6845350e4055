// Writes a generated near-eye scene as a trace, for command-line checks of every producer:
//   make_near_eye_trace pair|random OUT.tvt
#include <cstdio>
#include <cstring>
#include <exception>

#include "near_eye_scenes.h"

int main(int argc, char** argv) {
  using namespace tilevis;
  if (argc != 3 || (std::strcmp(argv[1], "pair") != 0 && std::strcmp(argv[1], "random") != 0)) {
    std::fprintf(stderr, "usage: make_near_eye_trace pair|random OUT.tvt\n");
    return 2;
  }
  try {
    trace::Trace t;
    t.source = std::string("tests/visibility/near_eye: ") + argv[1];
    t.frames = {std::strcmp(argv[1], "pair") == 0 ? near_eye::two_triangles(480, 270, 0.0f, 0.0f)
                                                  : near_eye::random_near_eye(2, 60, 480, 270)};
    trace::write(t, argv[2]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_near_eye_trace: %s\n", e.what());
    return 1;
  }
  return 0;
}
