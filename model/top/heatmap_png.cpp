#include "top/heatmap_png.h"

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>
#include <png.h>

namespace tilevis::sim {

std::array<uint8_t, 3> viridis(double t) {
  // matplotlib's viridis at 0, 1/8, ..., 1.
  static constexpr std::array<std::array<double, 3>, 9> kMap = {{{68, 1, 84},
                                                                  {71, 44, 122},
                                                                  {59, 81, 139},
                                                                  {44, 113, 142},
                                                                  {33, 144, 141},
                                                                  {39, 173, 129},
                                                                  {92, 200, 99},
                                                                  {170, 220, 50},
                                                                  {253, 231, 37}}};
  if (!(t > 0)) t = 0;  // NaN too
  if (t > 1) t = 1;
  const double x = t * double(kMap.size() - 1);
  const size_t i = std::min(size_t(x), kMap.size() - 2);
  const double f = x - double(i);
  std::array<uint8_t, 3> rgb{};
  for (size_t c = 0; c < 3; ++c) rgb[c] = uint8_t(std::lround(kMap[i][c] + f * (kMap[i + 1][c] - kMap[i][c])));
  return rgb;
}

uint32_t heatmap_scale(uint32_t tiles_x, uint32_t tiles_y, uint32_t target) {
  const uint32_t longer = std::max({tiles_x, tiles_y, 1u});
  return std::max(1u, target / longer);
}

void write_heatmap_png(const std::filesystem::path& file, const std::vector<double>& values, uint32_t tiles_x,
                       uint32_t tiles_y, const std::string& title) {
  if (tiles_x == 0 || tiles_y == 0 || values.size() != size_t(tiles_x) * tiles_y)
    throw std::runtime_error(fmt::format("{}: {} values for {}x{} tiles", file.string(), values.size(), tiles_x, tiles_y));
  const uint32_t s = heatmap_scale(tiles_x, tiles_y);
  const uint32_t w = tiles_x * s, h = tiles_y * s;
  double top = 0;
  for (double v : values) top = std::max(top, v);

  const std::filesystem::path tmp = file.string() + ".tmp";
  std::unique_ptr<FILE, int (*)(FILE*)> fp(std::fopen(tmp.c_str(), "wb"), &std::fclose);
  if (!fp) throw std::runtime_error(tmp.string() + ": cannot open for writing");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_write_struct(&png, nullptr);
    throw std::runtime_error("libpng: out of memory");
  }
  std::vector<uint8_t> row(size_t(w) * 3);
  std::string max_text = fmt::format("{}", top);
  // libpng reports errors by longjmp; nothing with a destructor is created below this point.
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    fp.reset();
    std::filesystem::remove(tmp);
    throw std::runtime_error(tmp.string() + ": PNG write failed");
  }
  png_init_io(png, fp.get());
  png_set_compression_level(png, 1);
  png_set_IHDR(png, info, w, h, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_text text[2] = {};
  text[0].compression = PNG_TEXT_COMPRESSION_NONE;
  text[0].key = const_cast<char*>("Title");
  text[0].text = const_cast<char*>(title.c_str());
  text[1].compression = PNG_TEXT_COMPRESSION_NONE;
  text[1].key = const_cast<char*>("Maximum");
  text[1].text = max_text.data();
  png_set_text(png, info, text, 2);
  png_write_info(png, info);
  for (uint32_t ty = 0; ty < tiles_y; ++ty) {
    for (uint32_t tx = 0; tx < tiles_x; ++tx) {
      const auto rgb = viridis(top > 0 ? values[size_t(ty) * tiles_x + tx] / top : 0.0);
      for (uint32_t k = 0; k < s; ++k) std::copy(rgb.begin(), rgb.end(), row.begin() + (size_t(tx) * s + k) * 3);
    }
    for (uint32_t k = 0; k < s; ++k) png_write_row(png, row.data());
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fflush(fp.get()) != 0 || std::ferror(fp.get())) throw std::runtime_error(tmp.string() + ": write failed");
  fp.reset();
  std::filesystem::rename(tmp, file);
}

}  // namespace tilevis::sim
