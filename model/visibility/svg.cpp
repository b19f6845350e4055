#include "visibility/svg.h"

#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace tilevis::vis {

void write_svg(const std::filesystem::path& file, uint32_t width, uint32_t height,
               const std::vector<PlanarPiece>& pieces) {
  std::filesystem::path tmp = file;
  tmp += ".tmp";
  {
    std::ofstream out(tmp);
    out << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
        << "\" viewBox=\"0 0 " << width << ' ' << height << "\">\n"
        << "<rect width=\"100%\" height=\"100%\" fill=\"#101418\"/>\n"
        << "<g stroke=\"#000\" stroke-opacity=\"0.35\" stroke-width=\"0.05\" stroke-linejoin=\"round\">\n";
    static const int kHue[] = {30, 200, 120, 280, 0, 60, 170, 320};
    char buf[64];
    for (const auto& p : pieces) {
      if (p.xy.size() < 6) continue;
      int hue = kHue[p.draw % 8];
      int light = 25 + int(55.0f * p.shade);
      out << "<path fill=\"hsl(" << hue << ",45%," << light << "%)\" d=\"";
      for (size_t i = 0; i < p.xy.size(); i += 2) {
        std::snprintf(buf, sizeof buf, "%c%.4f %.4f", i ? 'L' : 'M', p.xy[i], p.xy[i + 1]);
        out << buf;
      }
      out << "Z\"/>\n";
    }
    out << "</g>\n</svg>\n";
    if (!out) throw std::runtime_error(file.string() + ": write failed");
  }
  std::filesystem::rename(tmp, file);
}

}  // namespace tilevis::vis
