// tilevis info T: per frame, one screen: draws, triangles, vertices, window-space
// bounds, flags, and anything suspicious in the geometry.
#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "commands.h"
#include "geom/homogeneous.h"
#include "tilevis/trace.h"

namespace tilevis::app {
namespace {

std::string flag_names(uint32_t flags) {
  std::string s;
  auto add = [&](uint32_t bit, const char* name) {
    if (flags & bit) s += (s.empty() ? "" : ",") + std::string(name);
  };
  add(trace::kAlphaTested, "alpha_tested");
  add(trace::kBlended, "blended");
  add(trace::kShaderWritesDepth, "writes_depth");
  add(trace::kShaderDiscards, "discards");
  add(trace::kTriangleSoup, "soup");
  add(trace::kSampleRateShading, "sample_rate");
  return s.empty() ? "opaque" : s;
}

struct FrameStats {
  size_t triangles = 0, vertices = 0;
  size_t behind_eye = 0;        // vertices with w <= 0
  size_t outside_depth = 0;     // vertices in front of the eye but beyond near/far (|z| > w)
  size_t crossing_near = 0;     // triangles with vertices on both sides of the near plane
  size_t next_to_eye = 0;       // vertices with |w| under 2^-20 of their largest coordinate
  size_t edge_on = 0;           // triangles whose plane holds the eye (det[x y w] = 0): setup culls them
  size_t degenerate = 0;        // triangles in front of the eye with zero area after snapping
  size_t back_facing = 0;       // clockwise in NDC
  size_t off_screen = 0;        // triangles wholly outside the viewport
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
};

FrameStats analyse(const trace::Frame& f) {
  FrameStats s;
  const double scale = double(1u << f.subpixel_bits);
  for (const auto& d : f.draws) {
    s.vertices += d.vertices.size();
    s.triangles += d.triangle_count();
    for (const auto& v : d.vertices) {
      if (v.w <= 0) ++s.behind_eye;
      else if (std::fabs(v.z) > v.w) ++s.outside_depth;
      const double m = std::max({std::fabs(double(v.x)), std::fabs(double(v.y)), std::fabs(double(v.z))});
      if (std::fabs(double(v.w)) < std::ldexp(m, -20) || (v.w == 0 && m == 0)) ++s.next_to_eye;
    }
    for (size_t t = 0; t < d.indices.size(); t += 3) {
      const trace::Vec4* v[3] = {&d.vertices[d.indices[t]], &d.vertices[d.indices[t + 1]], &d.vertices[d.indices[t + 2]]};
      if (geom::homogeneous_orientation(v[0]->x, v[0]->y, v[0]->w, v[1]->x, v[1]->y, v[1]->w, v[2]->x, v[2]->y,
                                        v[2]->w) == 0)
        ++s.edge_on;
      int front = 0;
      for (auto* p : v) front += p->w > 0 && p->z >= -p->w;
      if (front != 3) {
        if (front != 0) ++s.crossing_near;
        continue;
      }
      double wx[3], wy[3];
      int64_t sx[3], sy[3];
      for (int i = 0; i < 3; ++i) {
        wx[i] = (v[i]->x / v[i]->w * 0.5 + 0.5) * f.width;
        wy[i] = (0.5 - v[i]->y / v[i]->w * 0.5) * f.height;
        sx[i] = std::llround(wx[i] * scale);
        sy[i] = std::llround(wy[i] * scale);
        s.x0 = std::min(s.x0, wx[i]);
        s.x1 = std::max(s.x1, wx[i]);
        s.y0 = std::min(s.y0, wy[i]);
        s.y1 = std::max(s.y1, wy[i]);
      }
      // Doubled signed area in sub-pixel units; window y points down, so
      // counter-clockwise in NDC is negative here.
      int64_t area = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sy[1] - sy[0]) * (sx[2] - sx[0]);
      if (area == 0) ++s.degenerate;
      else if (area > 0) ++s.back_facing;
      if (std::max({wx[0], wx[1], wx[2]}) < 0 || std::min({wx[0], wx[1], wx[2]}) > f.width ||
          std::max({wy[0], wy[1], wy[2]}) < 0 || std::min({wy[0], wy[1], wy[2]}) > f.height)
        ++s.off_screen;
    }
  }
  return s;
}

void print_frame(size_t index, const trace::Frame& f, const FrameStats& s, size_t max_draws) {
  fmt::print("frame {}: {}x{}, {} sample(s)/px, depth [{}, {}], {} sub-pixel bits\n", index, f.width, f.height,
             f.samples.size(), f.depth_near, f.depth_far, f.subpixel_bits);
  fmt::print("  {} draws, {} triangles, {} vertices\n", f.draws.size(), s.triangles, s.vertices);
  if (s.x0 <= s.x1)
    fmt::print("  window bounds (vertices in front of the eye): x [{:.1f}, {:.1f}]  y [{:.1f}, {:.1f}]\n", s.x0, s.x1,
               s.y0, s.y1);
  fmt::print("  {:<24} {:>10} {:>10}  {:<22} {:>7} {:>5} {:>5}\n", "draw", "triangles", "vertices", "flags",
             "cyc/frag", "vary", "tex");
  for (size_t i = 0; i < f.draws.size() && i < max_draws; ++i) {
    const auto& d = f.draws[i];
    fmt::print("  {:<24} {:>10} {:>10}  {:<22} {:>7.1f} {:>5} {:>5}\n", d.name.substr(0, 24), d.triangle_count(),
               d.vertices.size(), flag_names(d.flags), d.shader_cycles_per_fragment, d.varying_bytes_per_vertex,
               d.texture_bytes_per_fragment);
  }
  if (f.draws.size() > max_draws) fmt::print("  ... {} more draws\n", f.draws.size() - max_draws);
  std::vector<std::string> notes;
  if (s.behind_eye) notes.push_back(fmt::format("{} vertices behind the eye (w <= 0)", s.behind_eye));
  if (s.outside_depth) notes.push_back(fmt::format("{} vertices beyond the near/far planes", s.outside_depth));
  if (s.crossing_near) notes.push_back(fmt::format("{} triangles cross the near plane (will be clipped)", s.crossing_near));
  if (s.next_to_eye)
    notes.push_back(fmt::format("{} vertices next to w = 0 (|w| < 2^-20 of their x, y, z: they project next to "
                                "infinity; setup clips them in homogeneous form)",
                                s.next_to_eye));
  if (s.edge_on)
    notes.push_back(fmt::format("{} triangles edge-on to the eye (their plane holds it, det[x y w] = 0): culled",
                                s.edge_on));
  if (s.degenerate) notes.push_back(fmt::format("{} degenerate triangles (zero area after snapping)", s.degenerate));
  if (s.off_screen) notes.push_back(fmt::format("{} triangles wholly off screen", s.off_screen));
  fmt::print("  back-facing: {} of {} triangles in front of the eye\n", s.back_facing, s.triangles - s.crossing_near);
  if (notes.empty()) fmt::print("  suspicious: nothing\n");
  for (const auto& n : notes) fmt::print("  suspicious: {}\n", n);
}

}  // namespace

Command add_info_command(CLI::App& app) {
  struct Args {
    std::string trace;
    bool summary = false;
    size_t max_draws = 12;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("info", "Describe a trace: per frame draws, triangles, bounds, flags, suspicious input");
  cmd->add_option("trace", args->trace, "Trace file")->required();
  cmd->add_flag("--summary", args->summary, "One line for the whole trace");
  cmd->add_option("--max-draws", args->max_draws, "Draws listed per frame")->capture_default_str();
  return {cmd, [args]() {
            trace::Trace t = trace::read(args->trace);
            if (args->summary) {
              size_t tris = 0, draws = 0, degenerate = 0, behind = 0;
              for (const auto& f : t.frames) {
                FrameStats s = analyse(f);
                tris += s.triangles;
                draws += f.draws.size();
                degenerate += s.degenerate;
                behind += s.behind_eye;
              }
              const auto& f0 = t.frames.front();
              fmt::print("{:<44} {:>3} frame(s) {:>5}x{:<5} {:>2} spp {:>6} draws {:>10} triangles  {} degenerate, {} "
                         "vertices behind the eye\n",
                         args->trace, t.frames.size(), f0.width, f0.height, f0.samples.size(), draws, tris, degenerate,
                         behind);
              return 0;
            }
            fmt::print("{}: {} ({} frame(s))\n", args->trace, t.source, t.frames.size());
            for (size_t i = 0; i < t.frames.size(); ++i) print_frame(i, t.frames[i], analyse(t.frames[i]), args->max_draws);
            return 0;
          }};
}

}  // namespace tilevis::app
