// Scene description (JSON) -> trace: meshes imported with assimp, procedural
// primitives, instances, cameras (look-at, perspective, optional orbit).
// The scene file format is documented in traces/scenes/README.md.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>

#include "tilevis/trace.h"

namespace tilevis::scene {

// A bad scene: names the file and the JSON path of the problem, e.g.
// "traces/scenes/bunny.json: $.objects[2].transform.scale: expected a positive number".
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct BuildOptions {
  std::optional<uint32_t> width, height;   // override the scene's viewport
  std::optional<uint32_t> samples;         // override the scene's sample count
  std::function<void(const std::string&)> progress;  // called per loaded mesh / frame
  std::function<void(const std::string&)> warn;      // what was accepted but changed (a flipped winding)
};

trace::Trace build_trace(const std::filesystem::path& scene_file, const BuildOptions& options = {});

// Where "glmark2/..." and "cgal/..." mesh references resolve to.
std::filesystem::path glmark2_models_dir();
std::filesystem::path cgal_meshes_dir();

}  // namespace tilevis::scene
