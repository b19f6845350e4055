// Support for the SystemC model's tests. SystemC allows one elaboration and one
// sc_start() per process, so every test that touches SystemC runs it in a forked child
// (in_child) that reports back as JSON; the parent, which never elaborates, asserts.
// Any SystemC warning or error the child saw comes back too, and fails the test.
#pragma once

#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "scene_frames.h"
#include "tilevis/trace.h"

namespace tilevis::simtest {

// Runs fn in a child process; returns its JSON, or {"error": ...} if it threw or died.
nlohmann::json in_child(const std::function<nlohmann::json()>& fn);

// Scenes from JSON text or traces/scenes (tests/support/scene_frames.h).
using testsupport::frame_of;
using testsupport::shipped;

// Small scenes.
extern const char* const kCubes;    // floor, box, sphere, cards: clipping and occlusion
extern const char* const kSpheres;  // a grid of spheres over a plane: many silhouettes

}  // namespace tilevis::simtest
