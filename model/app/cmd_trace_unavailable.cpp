// `tilevis trace` in a TILEVIS_MINIMAL build (no assimp/GLM: no scene generator): the
// command exists and says why it cannot run; traces are made elsewhere and carried along.
#include <fmt/format.h>

#include "commands.h"

namespace tilevis::app {

Command add_trace_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("trace", "Build a trace from a scene file (not in this minimal build)");
  cmd->allow_extras();
  return {cmd, []() {
            fmt::print(stderr, "tilevis trace: this is a TILEVIS_MINIMAL build without the scene generator "
                               "(assimp, GLM); make traces with a full build\n");
            return 2;
          }};
}

}  // namespace tilevis::app
