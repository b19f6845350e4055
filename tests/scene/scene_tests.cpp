// Scene -> trace generator: geometry lands where a camera model says it must,
// every shipped scene builds, and bad scene files are rejected with their JSON path.
#include <cmath>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include <gtest/gtest.h>

#include "tilevis/scene.h"

namespace fs = std::filesystem;
using tilevis::scene::build_trace;
using tilevis::scene::SceneError;

namespace {

fs::path write_scene(const std::string& name, const std::string& json) {
  // One folder per process: CTest runs these tests in parallel processes.
  fs::path dir = fs::temp_directory_path() / ("tilevis_scene_tests_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  fs::path p = dir / name;
  std::ofstream(p) << json;
  return p;
}

struct Window {
  double x, y, z;
};

// OpenGL conventions (FORMAT.md): NDC = clip / w, y up; window y grows downward.
Window to_window(const tilevis::trace::Vec4& c, const tilevis::trace::Frame& f) {
  return {(c.x / c.w * 0.5 + 0.5) * f.width, (0.5 - c.y / c.w * 0.5) * f.height, c.z / c.w * 0.5 + 0.5};
}

}  // namespace

TEST(SceneGenerator, UnitCubeLandsAtExpectedWindowCoordinates) {
  // Unit cube at the origin, eye on +z at distance 3, 90° vertical field of view on a
  // square viewport: the front face (z = 0.5, 2.5 from the eye) spans NDC ±0.2,
  // the back face (3.5 from the eye) spans NDC ±0.5/3.5.
  auto p = write_scene("cube.json", R"({
    "viewport": [1000, 1000],
    "camera": {"eye": [0, 0, 3], "target": [0, 0, 0], "fov_y_deg": 90, "near": 1, "far": 10},
    "objects": [{"name": "cube", "primitive": {"type": "box", "size": 1}}]})");
  auto t = build_trace(p);
  ASSERT_EQ(t.frames.size(), 1u);
  const auto& f = t.frames[0];
  ASSERT_EQ(f.draws.size(), 1u);
  const auto& d = f.draws[0];
  EXPECT_EQ(d.vertices.size(), 8u);
  EXPECT_EQ(d.triangle_count(), 12u);
  const double n = 1, fa = 10;
  for (const auto& v : d.vertices) {
    Window w = to_window(v, f);
    bool front = v.w < 3.0f;  // eye distance 2.5 vs 3.5
    double dist = front ? 2.5 : 3.5;
    EXPECT_NEAR(v.w, dist, 1e-6);
    double half = 0.5 / dist * 500;  // NDC half-extent × half viewport
    EXPECT_NEAR(std::fabs(w.x - 500), half, 1e-3);
    EXPECT_NEAR(std::fabs(w.y - 500), half, 1e-3);
    double z_ndc = (fa + n) / (fa - n) - 2 * fa * n / ((fa - n) * dist);
    EXPECT_NEAR(w.z, z_ndc * 0.5 + 0.5, 1e-6);
  }
}

TEST(SceneGenerator, FrontFacesAreCounterClockwiseInNdc) {
  auto p = write_scene("cube_ccw.json", R"({
    "viewport": [800, 600],
    "camera": {"eye": [2, 1.5, 3], "target": [0, 0, 0]},
    "objects": [{"primitive": {"type": "box"}}, {"primitive": {"type": "sphere", "segments": 12, "rings": 6}}]})");
  auto t = build_trace(p);
  for (const auto& d : t.frames[0].draws) {
    size_t front = 0, back = 0;
    for (size_t i = 0; i < d.indices.size(); i += 3) {
      const auto &a = d.vertices[d.indices[i]], &b = d.vertices[d.indices[i + 1]], &c = d.vertices[d.indices[i + 2]];
      double ax = a.x / a.w, ay = a.y / a.w, bx = b.x / b.w, by = b.y / b.w, cx = c.x / c.w, cy = c.y / c.w;
      double area = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
      (area > 0 ? front : back)++;
    }
    // A convex closed solid seen from outside: the visible faces are front-facing and
    // at least a third but at most two thirds of the faces are visible.
    EXPECT_GT(front, 0u) << d.name;
    EXPECT_GT(back, 0u) << d.name;
    EXPECT_EQ(front + back, d.triangle_count());
  }
}

TEST(SceneGenerator, OrbitMakesFramesAndGridMakesInstances) {
  auto p = write_scene("orbit.json", R"({
    "camera": {"eye": [0, 0, 3], "orbit": {"frames": 4, "degrees": 360}},
    "objects": [{"name": "b", "primitive": {"type": "box"}, "grid": {"count": [2, 1, 3]}}]})");
  auto t = build_trace(p);
  ASSERT_EQ(t.frames.size(), 4u);
  ASSERT_EQ(t.frames[0].draws.size(), 6u);
  EXPECT_EQ(t.frames[0].draws[5].name, "b#5");
  // A quarter orbit moves the eye: the same vertex lands elsewhere.
  EXPECT_NE(t.frames[0].draws[0].vertices[0], t.frames[1].draws[0].vertices[0]);
  // A full orbit's frames are distinct, and frame 0 matches a fresh single-frame build.
  auto single = build_trace(write_scene("orbit1.json", R"({
    "camera": {"eye": [0, 0, 3]},
    "objects": [{"name": "b", "primitive": {"type": "box"}, "grid": {"count": [2, 1, 3]}}]})"));
  EXPECT_EQ(single.frames[0], t.frames[0]);
}

TEST(SceneGenerator, OptionsOverrideViewportAndSamples) {
  auto p = write_scene("opts.json", R"({"objects": [{"primitive": {"type": "plane"}}]})");
  tilevis::scene::BuildOptions o;
  o.width = 3840;
  o.height = 2160;
  o.samples = 4;
  auto t = build_trace(p, o);
  EXPECT_EQ(t.frames[0].width, 3840u);
  EXPECT_EQ(t.frames[0].height, 2160u);
  EXPECT_EQ(t.frames[0].samples.size(), 4u);
}

TEST(SceneGenerator, FlagsAndCostsReachTheDraw) {
  auto p = write_scene("flags.json", R"({"objects": [{"primitive": {"type": "quads", "count": 3},
      "flags": ["alpha_tested", "discards"], "shader_cycles": 12.5, "varying_bytes": 48, "texture_bytes": 16}]})");
  auto d = build_trace(p).frames[0].draws[0];
  EXPECT_EQ(d.flags, tilevis::trace::kAlphaTested | tilevis::trace::kShaderDiscards);
  EXPECT_FALSE(d.opaque());
  EXPECT_TRUE(d.per_pixel_only());
  EXPECT_FLOAT_EQ(d.shader_cycles_per_fragment, 12.5f);
  EXPECT_EQ(d.varying_bytes_per_vertex, 48u);
  EXPECT_EQ(d.texture_bytes_per_fragment, 16u);
  EXPECT_EQ(d.triangle_count(), 6u);
}

struct BadScene {
  const char* json;
  const char* place;  // must appear in the message
};

class SceneRejection : public ::testing::TestWithParam<BadScene> {};

TEST_P(SceneRejection, NamesTheJsonPath) {
  auto p = write_scene("bad.json", GetParam().json);
  try {
    build_trace(p);
    FAIL() << "accepted: " << GetParam().json;
  } catch (const SceneError& e) {
    std::string msg = e.what();
    EXPECT_NE(msg.find(p.string()), std::string::npos) << msg;
    EXPECT_NE(msg.find(GetParam().place), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line: " << msg;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Scenes, SceneRejection,
    ::testing::Values(
        BadScene{R"({"objects": [)", "invalid JSON"},
        BadScene{R"({})", "missing required member \"objects\""},
        BadScene{R"({"objects": [], "colour": 1})", "$.colour: unknown member"},
        BadScene{R"({"viewport": [0, 10], "objects": []})", "$.viewport[0]"},
        BadScene{R"({"viewport": [100000, 10], "objects": []})", "$.viewport[0]"},
        BadScene{R"({"samples": 3, "objects": []})", "$.samples"},
        BadScene{R"({"camera": {"near": 5, "far": 1}, "objects": []})", "$.camera.far"},
        BadScene{R"({"camera": {"eye": [0, 0, 0]}, "objects": []})", "$.camera.eye"},
        BadScene{R"({"camera": {"eye": [0, 1, 0], "up": [0, 1, 0]}, "objects": []})", "$.camera.up"},
        BadScene{R"({"objects": [{"primitive": {"type": "torus"}}]})", "$.objects[0].primitive.type"},
        BadScene{R"({"objects": [{"mesh": "nowhere.obj"}]})", "$.objects[0].mesh: mesh file"},
        BadScene{R"({"objects": [{"mesh": "cgal/none.off", "primitive": {"type": "box"}}]})", "$.objects[0]: expected exactly one"},
        BadScene{R"({"objects": [{"primitive": {"type": "box"}, "transform": {"scale": 0}}]})", "$.objects[0].transform.scale"},
        BadScene{R"({"objects": [{"primitive": {"type": "box"}, "flags": ["shiny"]}]})", "$.objects[0].flags[0]"},
        BadScene{R"({"objects": [{"primitive": {"type": "box", "size": "big"}}]})", "$.objects[0].primitive.size"},
        BadScene{R"({"objects": [{"primitive": {"type": "sphere", "segments": 2}}]})", "$.objects[0].primitive.segments"},
        BadScene{R"({"objects": [{"primitive": {"type": "box"}, "grid": {"count": [1000, 1000, 1]}}]})", "$.objects[0].grid.count"},
        BadScene{R"({"objects": [{"primitive": {"type": "box"}, "shader_cycles": -1}]})", "$.objects[0].shader_cycles"}));

TEST(SceneGenerator, EmptySceneIsAFrameWithNoDraws) {
  auto t = build_trace(write_scene("empty.json", R"({"objects": []})"));
  ASSERT_EQ(t.frames.size(), 1u);
  EXPECT_TRUE(t.frames[0].draws.empty());
}

// Every scene file shipped in traces/scenes builds into a valid trace.
class ShippedScene : public ::testing::TestWithParam<std::string> {};

TEST_P(ShippedScene, Builds) {
  fs::path p = fs::path(TILEVIS_SOURCE_DIR) / "traces/scenes" / (GetParam() + ".json");
  auto t = build_trace(p);
  ASSERT_FALSE(t.frames.empty());
  size_t tris = 0;
  for (const auto& f : t.frames) tris += f.triangle_count();
  EXPECT_GT(tris, 0u);
  if (GetParam() == "bunny") {
    EXPECT_EQ(tris, 69666u);
  } else if (GetParam() == "million") {
    EXPECT_GE(tris, 1000000u);
  } else if (GetParam() == "stack") {
    EXPECT_EQ(tris, 20000u);
  }
  // Encoding round-trips: what the generator made, the reader accepts unchanged.
  auto bytes = tilevis::trace::encode(t);
  EXPECT_EQ(tilevis::trace::decode(bytes.data(), bytes.size()), t);
}

INSTANTIATE_TEST_SUITE_P(All, ShippedScene,
                         ::testing::Values("bunny", "armadillo", "dragon", "elephant", "armadillo_box",
                                           "dragon_bunnies", "stack", "teapot_stadium", "million",
                                           "interpenetrating", "decals", "glass", "broken_mesh", "slivers",
                                           "hot_tile"));

// The list above must name every file in traces/scenes.
TEST(ShippedScenes, ListIsComplete) {
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(fs::path(TILEVIS_SOURCE_DIR) / "traces/scenes"))
    n += e.path().extension() == ".json";
  EXPECT_EQ(n, 15u);
}
