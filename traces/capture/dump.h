// The capture dump: what the interposer (interposer.cpp) writes while the application runs
// and `tilevis capture` turns into a trace. Host byte order (the two run on one machine);
// records follow each other to the end of the file, so a run cut short leaves every record
// it finished. Not a TileVis format: it lives for the duration of one capture.
//
//   file   = "TVCAPDMP" record*
//   record = u32 tag, then its fields
//   'DRAW' = u32 frame, u32 pass, u32 name_length, name, u32 flags (tilevis::trace::DrawFlag bits),
//            u32 state (kState* bits), i32 viewport[4] (x, y, w, h, window pixels, y up),
//            f32 depth_range[2], u32 vertex_count, f32 vertices[4 × n] (clip space),
//            u32 index_count, u32 indices[] (triangle list, as drawn: facing not yet applied)
//   'SKIP' = u32 frame, u32 reason_length, reason    (a draw that is not in the trace, and why)
//   'CLRD' = u32 frame, u32 pass, u32 draws_before   (a depth clear inside a pass; draws_before
//            counts the frame's draw calls so far, the number after '#' in draw names)
//   'PEND' = u32 frame, u32 pass, u32 framebuffer (0: the window), u32 width, u32 height,
//            f32 depth_clear, u32 depth_bits, u32 depth_width, u32 depth_height,
//            f32 depth[depth_width × depth_height] (the pass's depth buffer when it ended, rows
//            bottom-up as glReadPixels gives them; 0 x 0 when there is none)
// A pass is a run of captured draws into one framebuffer; a frame's last pass ends at its
// swap, and a frame with no draw into the window still gets an empty window pass.
#pragma once

#include <cstdint>

namespace tilevis::capture {

inline constexpr char kDumpMagic[8] = {'T', 'V', 'C', 'A', 'P', 'D', 'M', 'P'};

constexpr uint32_t tag(const char (&s)[5]) {
  return uint32_t(uint8_t(s[0])) | uint32_t(uint8_t(s[1])) << 8 | uint32_t(uint8_t(s[2])) << 16 |
         uint32_t(uint8_t(s[3])) << 24;
}
inline constexpr uint32_t kTagDraw = tag("DRAW");
inline constexpr uint32_t kTagSkip = tag("SKIP");
inline constexpr uint32_t kTagPassEnd = tag("PEND");
inline constexpr uint32_t kTagDepthClear = tag("CLRD");

// Rasteriser state the trace's flags cannot hold; `tilevis capture` applies what it can
// (facing) and names the rest in the draw's name.
enum StateBit : uint32_t {
  kStateCullEnabled = 1u << 0,
  kStateCullFront = 1u << 1,       // GL_FRONT or GL_FRONT_AND_BACK
  kStateCullBack = 1u << 2,        // GL_BACK or GL_FRONT_AND_BACK
  kStateFrontCw = 1u << 3,         // glFrontFace(GL_CW)
  kStateDepthTest = 1u << 4,
  kStateDepthWrite = 1u << 5,
  kStateBlend = 1u << 6,
  kStateAlphaTest = 1u << 7,
  kStateScissor = 1u << 8,
  kStateColorMaskNone = 1u << 9,   // no colour channel written
  kStatePolygonOffset = 1u << 10,  // GL_POLYGON_OFFSET_FILL
  kStateDepthClamp = 1u << 11,
  kStateDepthFuncOther = 1u << 12, // depth function other than LESS / LEQUAL
  kStateDepthFuncAlways = 1u << 13,
  kStateStencil = 1u << 14,
};

}  // namespace tilevis::capture
