// Headless videos of a case: OSMesa off-screen MuJoCo rendering piped into ffmpeg.
// Rendering replays the models' time series; it runs no physics. See docs/rendering.md.
#pragma once

#include <string>

#include "rendering/render_settings.h"
#include "results/time_series.h"
#include "robot/robot_params.h"
#include "trajectory/split_cycle_profile.h"

namespace tailsim {

// Checks everything that can be checked before any simulation or rendering, in this order:
// settings in range (even width/height for yuv420p, fps, slowmo, camera name), ffmpeg found
// (settings.ffmpeg on PATH, or the path itself), out_dir exists (created if missing) and is
// writable, an OSMesa context of the requested size can be made. Throws std::runtime_error
// with a message saying what is wrong and how to fix it.
void checkRenderPrerequisites(const RenderSettings& settings, const std::string& out_dir);

// Ticks at round numbers (1, 2, 2.5 or 5 times a power of ten) covering [lo, hi] in about
// `intervals` steps: the inset plot's range runs from tick lo to tick hi with count grid lines.
struct RoundTicks {
  double lo = 0.0, hi = 1.0, step = 1.0;
  int count = 2;
  int decimals = 0;  // digits after the point that print every tick exactly
};
RoundTicks roundTicks(double lo, double hi, int intervals);

struct RenderInputs {
  const RobotParams* robot = nullptr;
  const TailTrajectory* trajectory = nullptr;  // for the tail-phase text
  const TimeSeries* mujoco = nullptr;          // poses the MuJoCo model (required)
  const TimeSeries* analytic = nullptr;        // poses the translucent ghost (nullable)
  std::string mjcf_xml;                        // the case's model (generateMjcf)
  std::string title;                           // optional first overlay line (case name)
  // The colour key's names of the solid model and of the outline (what each series is: "MuJoCo",
  // "analytic model", "open-loop plan (analytic model)", ...).
  std::string solid_label = "MuJoCo";
  std::string outline_label = "analytic model";
};

struct RenderStats {
  long frames = 0;
  double setup_s = 0.0;      // wall time before the first frame: checks, ffmpeg start, model compile, GL setup
  double seconds = 0.0;      // wall time from the first frame to both files committed (encoder flush included)
  double fps = 0.0;          // frames / seconds
  double first_frame_s = 0.0;  // wall time of frame 0 (llvmpipe compiles its shaders here)
  double sim_start_s = 0.0, sim_end_s = 0.0;  // simulated time shown
  int width = 0, height = 0;
  double poster_time_s = 0.0;  // simulated time of the poster frame
  // Where the wall time went (seconds, summed over frames). GL thread:
  double pose_s = 0.0;    // series interpolation, kinematics, mjv_updateScene, ghost
  double render_s = 0.0;  // mjr_render + mjr_overlay (GL commands; llvmpipe rasterizes lazily)
  double read_s = 0.0;    // mjr_readPixels (waits for the rasterizer)
  double encode_s = 0.0;  // blocked waiting for the writer thread (encoder behind) + final flush
  // Writer thread (runs concurrently): vertical flip + pipe writes to ffmpeg + poster.
  double writer_s = 0.0;
};

// Renders the case to `mp4_path` (H.264, yuv420p, settings.fps) and a PNG poster frame to
// `png_path` ("" = none). Video frame k shows simulated time t_start + k / (fps * slowmo).
// Both files appear whole under their final names or not at all (even on exceptions).
RenderStats renderVideo(const RenderInputs& in, const RenderSettings& settings, const std::string& mp4_path,
                        const std::string& png_path);

// The bare render loop for comparison: same model, scene, camera and settings, the scene
// posed once; each frame only mjr_render + mjr_readPixels. Returns frames per second.
double benchBareRenderLoop(const RenderInputs& in, const RenderSettings& settings, int frames);

}  // namespace tailsim
