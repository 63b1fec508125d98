// Video render settings (the experiment's render section). See docs/rendering.md.
#pragma once

#include <cmath>
#include <string>

#include "results/work_limits.h"

namespace tailsim {

struct RenderSettings {
  bool enabled = false;
  int width = 640, height = 480, fps = 30;
  double slowmo = 4.0;        // video seconds per simulated second
  double duration_s = 0.0;    // simulated seconds to show; 0 = whole run
  std::string camera = "top"; // top (tracking) | perspective (angled, tracking)
  // Quality. Defaults chosen by measured cost on llvmpipe (docs/rendering.md, 640x480 bare
  // loop): msaa 0 -> 4 halves the frame rate (163 -> 81 fps) and smooths the thin tail;
  // reflections cost 1.4x more, shadows 2.5x more (and hide under the body in the top view).
  bool shadows = false, reflections = false;
  int msaa = 4;               // offscreen multisamples (0 = off)
  bool ghost = true;          // translucent analytic-model ghost
  // Added for issue 5 (rendering): the encoder.
  std::string ffmpeg = "ffmpeg";  // executable: looked up on PATH unless it contains a '/'
  int crf = 20;                   // libx264 constant rate factor (lower = better, bigger)
  std::string preset = "ultrafast";  // libx264 preset (ultrafast: least CPU next to llvmpipe)
};

// The limits of every render setting, declared once: the experiment loader refuses a value outside
// them with file:line:col, and the renderer checks them again before it starts (so no value the
// loader accepts can fail after files are written).
constexpr int kRenderMinSize = 16, kRenderMaxSize = 8192;  // width and height, pixels; both even (H.264 yuv420p)
constexpr int kRenderMinFps = 1, kRenderMaxFps = 240;
constexpr double kRenderMinSlowmo = 1e-3, kRenderMaxSlowmo = 1e3;  // video seconds per simulated second
constexpr int kRenderMaxMsaa = 16;                                  // 0..16 multisamples
constexpr int kRenderMinCrf = 0, kRenderMaxCrf = 51;                // libx264
constexpr double kRenderMaxFrames = limits::kMaxRenderFrames;  // declared with the other work limits

// Frames of a video showing `span_s` simulated seconds (a double: compare with kRenderMaxFrames
// before converting, so a huge span or slowmo never overflows).
inline double renderFrameCount(double span_s, const RenderSettings& s) {
  return std::floor(span_s * s.fps * s.slowmo + 1e-9) + 1.0;
}

}  // namespace tailsim
