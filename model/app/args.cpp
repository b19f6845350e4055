// Arguments several commands share: sizes ("N" or "WxH"), tile sizes, and the frame of a
// trace with an optional sample-count override.
#include <cstdio>
#include <stdexcept>

#include <fmt/format.h>

#include "commands.h"

namespace tilevis::app {

bool parse_size(const std::string& text, uint32_t& width, uint32_t& height) {
  unsigned long w = 0, h = 0;
  char x = 0, extra = 0;
  int n = std::sscanf(text.c_str(), "%lu%c%lu%c", &w, &x, &h, &extra);
  if (n == 1) h = w;
  else if (n != 3 || x != 'x') return false;
  if (w == 0 || h == 0 || w > 65536 || h > 65536) return false;
  width = static_cast<uint32_t>(w);
  height = static_cast<uint32_t>(h);
  return true;
}

void parse_tile(const std::string& text, uint32_t& width, uint32_t& height) {
  if (!parse_size(text, width, height) || width < 4 || height < 4 || width > 256 || height > 256)
    throw std::runtime_error(fmt::format("--tile {}: expected N or WxH with 4 <= N <= 256", text));
}

void parse_occlusion_bin(const std::string& text, uint32_t tile_w, uint32_t tile_h, uint32_t& width,
                         uint32_t& height) {
  width = height = 0;
  if (text.empty()) return;
  if (!parse_size(text, width, height) || width > tile_w || height > tile_h)
    throw std::runtime_error(
        fmt::format("--occlusion-bin {}: expected N or WxH no larger than the tile ({}x{})", text, tile_w, tile_h));
}

nlohmann::json visibility_config(uint32_t tile_w, uint32_t tile_h, uint32_t occlusion_bin_w, uint32_t occlusion_bin_h,
                                 uint32_t samples, uint32_t depth_bits) {
  return {{"tile_w", tile_w},
          {"tile_h", tile_h},
          {"occlusion_bin_w", occlusion_bin_w ? occlusion_bin_w : tile_w},
          {"occlusion_bin_h", occlusion_bin_h ? occlusion_bin_h : tile_h},
          {"samples", samples},
          {"depth_bits", depth_bits}};
}

trace::Frame load_frame(const std::string& path, uint32_t frame_index, uint32_t samples) {
  trace::Trace t = trace::read(path);
  if (frame_index >= t.frames.size())
    throw std::runtime_error(fmt::format("--frame {}: {} has {} frame(s)", frame_index, path, t.frames.size()));
  trace::Frame frame = std::move(t.frames[frame_index]);
  if (samples) {
    try {
      frame.samples = trace::standard_samples(samples, frame.subpixel_bits);
    } catch (const std::invalid_argument&) {
      throw std::runtime_error(fmt::format("--samples {}: expected 1, 2, 4, 8 or 16", samples));
    }
  }
  return frame;
}

}  // namespace tilevis::app
