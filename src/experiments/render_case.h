// Video of one experiment case: the MuJoCo model with the analytic model as a ghost.
#pragma once

#include <string>
#include <vector>

#include "experiments/experiment_config.h"
#include "rendering/video_renderer.h"

namespace tailsim {

// Renders <out_dir>/<case dir>.mp4 and .png from the case's runs (MuJoCo poses the model, the
// analytic run the ghost; without a MuJoCo run the analytic run poses the model, no ghost).
// outline_label names the ghost in the colour key when its series is not the analytic model's own
// run (a maneuver's "open-loop plan").
RenderStats renderCase(const ExperimentCase& c, const std::vector<RunResult>& runs, const std::string& out_dir,
                       const std::string& outline_label = "");

}  // namespace tailsim
