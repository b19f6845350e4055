// Arguments several commands share: sizes ("N" or "WxH"), tile sizes, and the frame of a
// trace with an optional sample-count override.
#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

#include "commands.h"
#include "geom/tile_grid.h"

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
  if (!parse_size(text, width, height) || !geom::TileGrid::valid_tile(width) || !geom::TileGrid::valid_tile(height))
    throw std::runtime_error(fmt::format("--tile {}: expected N or WxH with {}", text, geom::TileGrid::valid_range()));
}

void parse_occlusion_bin(const std::string& text, uint32_t tile_w, uint32_t tile_h, uint32_t& width,
                         uint32_t& height) {
  if (text.empty()) return;  // the caller's default
  if (!parse_size(text, width, height) || width > tile_w || height > tile_h)
    throw std::runtime_error(
        fmt::format("--occlusion-bin {}: expected N or WxH no larger than the tile ({}x{})", text, tile_w, tile_h));
}

nlohmann::json visibility_config(uint32_t tile_w, uint32_t tile_h, uint32_t occlusion_bin_w, uint32_t occlusion_bin_h,
                                 uint32_t samples, uint32_t depth_bits) {
  return {{"tile_w", tile_w},
          {"tile_h", tile_h},
          {"occlusion_bin_w", occlusion_bin_w ? std::min(occlusion_bin_w, tile_w) : tile_w},
          {"occlusion_bin_h", occlusion_bin_h ? std::min(occlusion_bin_h, tile_h) : tile_h},
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

void check_memory(const std::string& what, const trace::Frame& frame, uint32_t tile_w, uint32_t tile_h) {
  const uint64_t pixels = uint64_t(frame.width) * frame.height;
  const uint64_t samples = pixels * std::max<size_t>(1, frame.samples.size());
  const uint64_t tiles = ((frame.width + tile_w - 1) / tile_w) * uint64_t((frame.height + tile_h - 1) / tile_h);
  // ids and owners (4 B each, twice: the result and its copy on output), overdraw (4 B per pixel),
  // tile rows (about 24 counters of 8 B plus a vector's 40 B), setup and binning (~256 B per triangle).
  const uint64_t need = samples * 16 + pixels * 8 + tiles * (24 * 8 + 40) + uint64_t(frame.triangle_count()) * 256;
  uint64_t limit = 0;
  std::string source;
  rlimit rl{};
  if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) {
    limit = rl.rlim_cur;
    source = "the address-space limit (ulimit -v)";
  }
  std::ifstream meminfo("/proc/meminfo");
  for (std::string key; meminfo >> key;) {
    uint64_t kib = 0;
    meminfo >> kib;
    if (key == "MemAvailable:" && (limit == 0 || kib * 1024 < limit)) {
      limit = kib * 1024;
      source = "the memory available (MemAvailable)";
    }
    meminfo.ignore(1 << 10, '\n');
  }
  if (limit && need > limit)
    throw std::runtime_error(fmt::format(
        "{}: a {}x{} frame at {} sample(s) and {}x{} tiles ({} tiles, {} triangles) needs about {:.1f} GiB, over {} "
        "of {:.1f} GiB: use larger tiles, fewer samples or a smaller viewport",
        what, frame.width, frame.height, frame.samples.size(), tile_w, tile_h, tiles, frame.triangle_count(),
        double(need) / double(1ull << 30), source, double(limit) / double(1ull << 30)));
}

}  // namespace tilevis::app
