// Video render settings (the experiment's render section). See docs/rendering.md.
#pragma once

#include <string>

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

}  // namespace tailsim
