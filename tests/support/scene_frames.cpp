#include "scene_frames.h"

#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "tilevis/scene.h"

namespace fs = std::filesystem;

namespace tilevis::testsupport {

trace::Frame frame_of(const std::string& name, const std::string& json, uint32_t samples) {
  const fs::path dir = fs::temp_directory_path() / ("tilevis_tests_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path p = dir / (name + ".json");
  std::ofstream(p) << json;
  scene::BuildOptions o;
  if (samples) o.samples = samples;
  return scene::build_trace(p, o).frames.at(0);
}

trace::Frame shipped(const std::string& name, uint32_t width, uint32_t height, uint32_t samples) {
  scene::BuildOptions o;
  o.width = width;
  o.height = height;
  o.samples = samples;
  return scene::build_trace(fs::path(TILEVIS_SOURCE_DIR) / "traces/scenes" / (name + ".json"), o).frames.at(0);
}

}  // namespace tilevis::testsupport
