// Shared by the commands that take a size (--tile, --viewport): "N" or "WxH".
#include <cstdio>

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

}  // namespace tilevis::app
