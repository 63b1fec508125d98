// Video render settings (the experiment's render section). See docs/rendering.md.
#pragma once

#include <cmath>
#include <string>

#include "common/work_limits.h"
#include "settings/fields.h"

namespace tailsim {

enum class RenderCamera {
  kTop,          // from above, tracking the body
  kPerspective,  // angled, tracking the body
};
inline const settings::EnumNames<RenderCamera>& cameraNames() {
  static const settings::EnumNames<RenderCamera> k = {{RenderCamera::kTop, "top"},
                                                       {RenderCamera::kPerspective, "perspective"}};
  return k;
}

struct RenderSettings {
  bool enabled = false;
  std::string size;  // a frame-size preset name (kRenderSizePresets) or "" (width, height as given)
  int width = 640, height = 480, fps = 30;
  double slowmo = 4.0;        // video seconds per simulated second
  double duration_s = 0.0;    // simulated seconds to show; 0 = whole run
  RenderCamera camera = RenderCamera::kTop;
  // Quality. Defaults chosen by measured cost on llvmpipe (docs/rendering.md, 640x480 bare
  // loop): msaa 0 -> 4 halves the frame rate (163 -> 81 fps) and smooths the thin tail;
  // reflections cost 1.4x more, shadows 2.5x more (and hide under the body in the top view).
  bool shadows = false, reflections = false;
  int msaa = 4;               // offscreen multisamples (0 = off)
  bool ghost = true;          // translucent analytic-model ghost
  // The encoder executable, looked up on PATH unless it contains a '/'. Not a declared field: no
  // experiment file, result folder or Python call names a program to run; only C++ callers set it.
  std::string ffmpeg = "ffmpeg";
  int crf = 20;                   // libx264 constant rate factor (lower = better, bigger)
  std::string preset = "ultrafast";  // libx264 preset (ultrafast: least CPU next to llvmpipe)
};

// The limits of every render setting, declared once: the experiment loader refuses a value outside
// them with file:line:col, and the renderer checks them again before it starts (so no value the
// loader accepts can fail after files are written).
constexpr int kRenderMinSize = 16, kRenderMaxSize = 8192;  // width and height, pixels; both even (H.264 yuv420p)
constexpr int kRenderMinFps = 1, kRenderMaxFps = 240;
constexpr double kRenderMinSlowmo = 1e-3, kRenderMaxSlowmo = 1e3;  // video seconds per simulated second
constexpr int kRenderMaxMsaa = 4;  // 0..4 multisamples: llvmpipe's GL_MAX_SAMPLES (more rendered as 4)
constexpr int kRenderMinCrf = 0, kRenderMaxCrf = 51;                // libx264
constexpr double kRenderMaxFrames = limits::kMaxRenderFrames;  // declared with the other work limits

// Frame-size presets (`render.size`): the default 640x480 and 720p for talks.
struct RenderSizePreset {
  const char* name;
  int width, height;
};
inline constexpr RenderSizePreset kRenderSizePresets[] = {{"640x480", 640, 480}, {"1280x720", 1280, 720}};

// The keys of the render section (settings/fields.h), declared once; the renderer checks the same.
template <class V, class S>
settings::For<S, RenderSettings> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  v.internal(Field{"enabled", "a video is made (the render section is present); not a YAML key"}, s.enabled);
  const auto even = settings::IntSet::multiple(2, "H.264 yuv420p");
  v.text(Field{"size", "frame-size preset, 640x480 or 1280x720: sets width and height (give one or the other)"},
         s.size, settings::TextRule{false, {"640x480", "1280x720"}});
  v.integer(Field{"width", "frame width, even [pixels]"}, s.width, Limits::closed(kRenderMinSize, kRenderMaxSize), even);
  v.integer(Field{"height", "frame height, even [pixels]"}, s.height, Limits::closed(kRenderMinSize, kRenderMaxSize),
            even);
  v.integer(Field{"fps", "video frames per second"}, s.fps, Limits::closed(kRenderMinFps, kRenderMaxFps));
  v.number(Field{"slowmo", "video seconds per simulated second"}, s.slowmo,
           Limits::closed(kRenderMinSlowmo, kRenderMaxSlowmo));
  v.number(Field{"duration_s", "simulated seconds to show; 0 = whole run [s]"}, s.duration_s, Limits::nonNegative());
  v.choice(Field{"camera", "top: from above; perspective: angled (both track the body)"}, s.camera, cameraNames());
  v.boolean(Field{"shadows", "shadows (2.5x the cost)"}, s.shadows);
  v.boolean(Field{"reflections", "floor reflections (1.4x the cost)"}, s.reflections);
  v.integer(Field{"msaa", "offscreen multisamples; 0 = off"}, s.msaa, Limits::closed(0, kRenderMaxMsaa));
  v.boolean(Field{"ghost", "translucent analytic-model ghost"}, s.ghost);
  v.integer(Field{"crf", "libx264 constant rate factor (lower = better, bigger)"}, s.crf,
            Limits::closed(kRenderMinCrf, kRenderMaxCrf));
  v.text(Field{"preset", "libx264 preset (ultrafast: least CPU next to llvmpipe)"}, s.preset,
         settings::TextRule{false, {"ultrafast", "superfast", "veryfast", "faster", "fast", "medium", "slow", "slower",
                                    "veryslow", "placebo"}});
}

// Frames of a video showing `span_s` simulated seconds (a double: compare with kRenderMaxFrames
// before converting, so a huge span or slowmo never overflows).
inline double renderFrameCount(double span_s, const RenderSettings& s) {
  return std::floor(span_s * s.fps * s.slowmo + 1e-9) + 1.0;
}

}  // namespace tailsim
