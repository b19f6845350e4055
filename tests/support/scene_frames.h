// Frames for tests: a scene given as JSON text, or a shipped scene (traces/scenes) at a
// chosen viewport. One definition for every test folder that builds scenes.
#pragma once

#include <cstdint>
#include <string>

#include "tilevis/trace.h"

namespace tilevis::testsupport {

// Frame 0 of the scene `json` (written to a per-process temporary folder as name.json, so
// parallel CTest processes never share a file); samples 0: the scene's own.
trace::Frame frame_of(const std::string& name, const std::string& json, uint32_t samples = 0);
// Frame 0 of traces/scenes/<name>.json at the given viewport and samples per pixel.
trace::Frame shipped(const std::string& name, uint32_t width, uint32_t height, uint32_t samples = 1);

}  // namespace tilevis::testsupport
