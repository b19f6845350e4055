// The per-tile cycles heatmap PNG: read back with libpng, it has one scale x scale block per
// tile, the colour of each block is viridis at value / max, and it names its own maximum.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <png.h>
#include <unistd.h>

#include "top/heatmap_png.h"

using tilevis::sim::heatmap_scale;
using tilevis::sim::viridis;
using tilevis::sim::write_heatmap_png;

namespace {

struct Png {
  uint32_t w = 0, h = 0;
  std::vector<std::vector<uint8_t>> rows;
  std::map<std::string, std::string> text;
  std::array<uint8_t, 3> at(uint32_t x, uint32_t y) const { return {rows[y][3 * x], rows[y][3 * x + 1], rows[y][3 * x + 2]}; }
};

Png read_png(const std::filesystem::path& file) {
  Png p;
  std::unique_ptr<FILE, int (*)(FILE*)> fp(std::fopen(file.c_str(), "rb"), &std::fclose);
  if (!fp) return p;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    return {};
  }
  png_init_io(png, fp.get());
  png_read_info(png, info);
  p.w = png_get_image_width(png, info);
  p.h = png_get_image_height(png, info);
  if (png_get_color_type(png, info) != PNG_COLOR_TYPE_RGB || png_get_bit_depth(png, info) != 8) {
    png_destroy_read_struct(&png, &info, nullptr);
    return {};
  }
  p.rows.assign(p.h, std::vector<uint8_t>(size_t(p.w) * 3));
  for (auto& r : p.rows) png_read_row(png, r.data(), nullptr);
  png_textp text = nullptr;
  int n = 0;
  png_get_text(png, info, &text, &n);
  for (int i = 0; i < n; ++i) p.text[text[i].key] = text[i].text;
  png_destroy_read_struct(&png, &info, nullptr);
  return p;
}

std::filesystem::path temp_file(const std::string& name) {
  return std::filesystem::temp_directory_path() / (name + "_" + std::to_string(getpid()) + ".png");
}

}  // namespace

TEST(Viridis, EndsAndMiddleAreMatplotlibs) {
  EXPECT_EQ(viridis(0.0), (std::array<uint8_t, 3>{68, 1, 84}));
  EXPECT_EQ(viridis(0.5), (std::array<uint8_t, 3>{33, 144, 141}));
  EXPECT_EQ(viridis(1.0), (std::array<uint8_t, 3>{253, 231, 37}));
  EXPECT_EQ(viridis(-3.0), viridis(0.0));
  EXPECT_EQ(viridis(7.0), viridis(1.0));
  EXPECT_EQ(viridis(std::nan("")), viridis(0.0));
}

TEST(HeatmapPng, OneBlockPerTileColouredByValueOverMax) {
  // 60 x 34 tiles: the 1080p frame at 32x32.
  const uint32_t tx = 60, ty = 34;
  std::vector<double> v(size_t(tx) * ty);
  for (uint32_t y = 0; y < ty; ++y)
    for (uint32_t x = 0; x < tx; ++x) v[size_t(y) * tx + x] = double(x * 100 + y);
  const double top = double((tx - 1) * 100 + ty - 1);
  const auto file = temp_file("heatmap");
  write_heatmap_png(file, v, tx, ty, "tile_cycles");
  const Png p = read_png(file);
  std::filesystem::remove(file);
  const uint32_t s = heatmap_scale(tx, ty);
  EXPECT_EQ(s, 16u);
  ASSERT_EQ(p.w, tx * s);
  ASSERT_EQ(p.h, ty * s);
  for (uint32_t y = 0; y < ty; ++y)
    for (uint32_t x = 0; x < tx; ++x) {
      const auto want = viridis(v[size_t(y) * tx + x] / top);
      ASSERT_EQ(p.at(x * s, y * s), want) << x << "," << y;
      ASSERT_EQ(p.at(x * s + s - 1, y * s + s - 1), want) << x << "," << y;
    }
  EXPECT_EQ(p.text.at("Title"), "tile_cycles");
  EXPECT_EQ(p.text.at("Maximum"), "5933");
}

TEST(HeatmapPng, AllZeroIsDarkAndBadShapesAreRejected) {
  const auto file = temp_file("zero");
  write_heatmap_png(file, std::vector<double>(12, 0.0), 4, 3, "zero");
  const Png p = read_png(file);
  std::filesystem::remove(file);
  ASSERT_EQ(p.w, 4 * heatmap_scale(4, 3));
  EXPECT_EQ(p.at(0, 0), viridis(0.0));
  EXPECT_EQ(p.text.at("Maximum"), "0");
  EXPECT_THROW(write_heatmap_png(temp_file("bad"), std::vector<double>(11, 1.0), 4, 3, "bad"), std::runtime_error);
  EXPECT_THROW(write_heatmap_png(temp_file("bad"), {}, 0, 3, "bad"), std::runtime_error);
  EXPECT_THROW(write_heatmap_png("/nonexistent_dir/x.png", std::vector<double>(12, 1.0), 4, 3, "bad"),
               std::runtime_error);
}
