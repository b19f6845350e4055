// Writes a generated near-eye scene as a trace, for command-line checks of every producer:
//   make_near_eye_trace pair|random|eye OUT.tvt   (eye: a triangle with a vertex at (0, 0, 0, 0))
#include <cstdio>
#include <string>
#include <exception>

#include "near_eye_scenes.h"

int main(int argc, char** argv) {
  using namespace tilevis;
  const std::string kind = argc == 3 ? argv[1] : "";
  if (kind != "pair" && kind != "random" && kind != "eye") {
    std::fprintf(stderr, "usage: make_near_eye_trace pair|random|eye OUT.tvt\n");
    return 2;
  }
  try {
    trace::Trace t;
    t.source = std::string("tests/visibility/near_eye: ") + argv[1];
    t.frames = {kind == "pair"     ? near_eye::two_triangles(480, 270, 0.0f, 0.0f)
                : kind == "random" ? near_eye::random_near_eye(2, 60, 480, 270)
                                   : near_eye::near_zero_w(0, 160, 90)};
    trace::write(t, argv[2]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_near_eye_trace: %s\n", e.what());
    return 1;
  }
  return 0;
}
