// The configuration layers: unknown keys and bad values are one-line errors naming the
// place and the expectation; files (nested or dotted) and -p overrides apply; the
// effective config reads back to itself; --list-params covers every parameter.
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <unistd.h>

#include "top/config.h"

using namespace tilevis::sim;
namespace fs = std::filesystem;

namespace {

std::string error_of(const std::string& file, const std::vector<std::string>& overrides) {
  try {
    load_config(file, overrides);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

fs::path write_temp(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / ("tilevis_sim_config_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / name) << text;
  return dir / name;
}

}  // namespace

TEST(Config, DefaultsResembleAPowerVRClassGpu) {
  const TilerConfig c = load_config("", {});
  EXPECT_EQ(c.sim.tile_width, 32u);
  EXPECT_EQ(c.sim.tile_height, 32u);
  EXPECT_EQ(c.sim.fidelity, Fidelity::tile);
  EXPECT_EQ(c.sim.mode, Mode::analytic);
  EXPECT_EQ(c.pb.capacity_bytes, 256ull << 20);
  EXPECT_EQ(c.writer.pixels_per_clock, 4u);
}

TEST(Config, UnknownKeyIsAOneLineErrorWithASuggestion) {
  const std::string e = error_of("", {"evu.reject.lanez=16"});
  EXPECT_NE(e.find("-p evu.reject.lanez=16: evu.reject.lanez: unknown parameter"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean evu.reject.lanes"), std::string::npos) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos);
  const fs::path f = write_temp("unknown.json", R"({"evu": {"reject": {"lanes": 16}}, "memory": {"speed": 3}})");
  const std::string ef = error_of(f.string(), {});
  EXPECT_NE(ef.find(f.string() + ": $: memory.speed: unknown parameter"), std::string::npos) << ef;
}

TEST(Config, OutOfRangeAndWrongTypeNameTheExpectation) {
  EXPECT_NE(error_of("", {"evu.reject.lanes=0"}).find("expected an integer in [1, 1024], got 0"), std::string::npos);
  EXPECT_NE(error_of("", {"sim.mode=magic"}).find("expected one of analytic, hybrid, hsr, early_z, none"), std::string::npos);
  EXPECT_NE(error_of("", {"writer.colour_compression=1.5"}).find("expected a number in [0.01, 1]"), std::string::npos);
  EXPECT_NE(error_of("", {"sim.tile_width"}).find("expected key=value"), std::string::npos);
  const fs::path f = write_temp("broken.json", R"({"sim": {"tile_width": 32,})");
  EXPECT_NE(error_of(f.string(), {}).find(f.string() + ": line 1, column"), std::string::npos);
}

TEST(Config, FileThenOverridesApply) {
  const fs::path f = write_temp("layers.json", R"({"evu": {"reject": {"lanes": 16}}, "sim.mode": "hsr", "pb.capacity_bytes": 1000})");
  const TilerConfig c = load_config(f.string(), {"evu.reject.lanes=32", "sim.fidelity=primitive"});
  EXPECT_EQ(c.evu.reject.lanes, 32u);  // -p wins over the file
  EXPECT_EQ(c.sim.mode, Mode::hsr);
  EXPECT_EQ(c.pb.capacity_bytes, 1000u);
  EXPECT_EQ(c.sim.fidelity, Fidelity::primitive);
}

TEST(Config, EffectiveConfigReadsBackToItself) {
  const TilerConfig c = load_config("", {"evu.clip.lanes=5", "sim.mode=early_z", "sim.clock_mhz=650.5"});
  const fs::path f = write_temp("effective.json", to_json(c).dump(2));
  EXPECT_EQ(to_json(load_config(f.string(), {})), to_json(c));
}

TEST(Config, ListParamsNamesEveryParameterWithDefaultAndUnit) {
  const std::string list = list_params();
  for (const std::string& name : param_names()) EXPECT_NE(list.find(name + " "), std::string::npos) << name;
  EXPECT_NE(list.find("evu.reject.lanes"), std::string::npos);
  EXPECT_NE(list.find("memory.rcd"), std::string::npos);
  EXPECT_NE(list.find("tCK"), std::string::npos);
  EXPECT_GT(param_names().size(), 50u);
}

TEST(Config, EveryMemorySystemDefaultCitesItsSourceOrSaysItIsAnAssumption) {
  // Issue 12: the memory system's defaults decide most frames, so a user must see where each
  // comes from. One line of --list-params per parameter: name, default, unit, help.
  const std::vector<std::string> prefixes = {"memory.", "framebuffer.", "pb.", "fetch.cache", "fragment.tex",
                                             "writer.colour", "energy."};
  const std::vector<std::string> sources = {"assumption", "JESD209-4", "LPDDR4-4266", "BL16", "Horowitz"};
  std::istringstream list(list_params());
  size_t checked = 0;
  for (std::string line; std::getline(list, line);) {
    const std::string name = line.substr(0, line.find(' '));
    bool memory = false;
    for (const std::string& p : prefixes) memory = memory || name.rfind(p, 0) == 0;
    if (!memory) continue;
    ++checked;
    bool cited = false;
    for (const std::string& src : sources) cited = cited || line.find(src) != std::string::npos;
    EXPECT_TRUE(cited) << line;
  }
  EXPECT_GE(checked, 30u);
}

TEST(Config, RulesBetweenParametersAreCheckedWithTheirNames) {
  EXPECT_NE(error_of("", {"fetch.cache_bytes=1000"}).find("fetch.cache_bytes must be a multiple"), std::string::npos);
  EXPECT_NE(error_of("", {"memory.row_bytes=100"}).find("memory.row_bytes must be a multiple of memory.burst_bytes"),
            std::string::npos);
  EXPECT_NE(error_of("", {"memory.rfc=9000"}).find("memory.rfc must be below memory.refi"), std::string::npos);
  EXPECT_NE(error_of("", {"sim.sample_geometry_warm=256"}).find("sim.sample_geometry_warm must be below sim.sample_geometry_cluster"),
            std::string::npos);
  EXPECT_EQ(error_of("", {"sim.sample_geometry_warm=256", "sim.sample_geometry_cluster=512"}), "");
  EXPECT_EQ(error_of("", {"sim.cores=4", "sim.scheduler=dynamic", "memory.channels=8"}), "");
  EXPECT_NE(error_of("", {"sim.scheduler=zigzag"}).find("expected one of row_major, morton, dynamic"), std::string::npos);
}
