// Video render settings (the experiment's render section).
#pragma once

#include <string>

namespace tailsim {

struct RenderSettings {
  bool enabled = false;
  int width = 640, height = 480, fps = 30;
  double slowmo = 4.0;        // video seconds per simulated second
  double duration_s = 0.0;    // simulated seconds to show; 0 = whole run
  std::string camera = "top"; // top (tracking) | perspective
  bool shadows = false, reflections = false;
  int msaa = 0;
  bool ghost = true;          // translucent analytic-model ghost
};

}  // namespace tailsim
