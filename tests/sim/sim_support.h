// Support for the SystemC model's tests. SystemC allows one elaboration and one
// sc_start() per process, so every test that touches SystemC runs it in a forked child
// (in_child) that reports back as JSON; the parent, which never elaborates, asserts.
// Any SystemC warning or error the child saw comes back too, and fails the test.
#pragma once

#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "tilevis/trace.h"

namespace tilevis::simtest {

// Runs fn in a child process; returns its JSON, or {"error": ...} if it threw or died.
nlohmann::json in_child(const std::function<nlohmann::json()>& fn);

// A scene built in-process from JSON text (scene file format, traces/scenes/README.md).
trace::Frame frame_of(const std::string& name, const std::string& json);
// A shipped scene at a given viewport.
trace::Frame shipped(const std::string& name, uint32_t width, uint32_t height, uint32_t samples = 1);

// Small scenes.
extern const char* const kCubes;    // floor, box, sphere, cards: clipping and occlusion
extern const char* const kSpheres;  // a grid of spheres over a plane: many silhouettes

}  // namespace tilevis::simtest
