// One experiment case, fully resolved: what a YAML experiment file (after sweep expansion)
// turns into. Every model reads its settings from here; nothing else is global.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "robot/robot_params.h"
#include "trajectory/split_cycle_profile.h"
#include "robot/scene_effects.h"
#include "analytic_model/analytic_settings.h"
#include "mujoco_model/mujoco_settings.h"
#include "rendering/render_settings.h"

namespace tailsim {

struct OutputSettings {
  double sample_dt_s = 1e-3;  // CSV row spacing (both models share this grid)  [s]
  double duration_s = 0.0;    // simulated time; 0 = tail end time + settle_s
  double settle_s = 0.5;      // time after the tail stops  [s]
};

struct ExperimentCase {
  std::string experiment;   // experiment name
  std::string name;         // case name: "base" or "key=value,key=value" for sweeps
  std::string source_file;  // the YAML file it came from
  std::map<std::string, std::string> sweep_values;  // swept key -> value as written

  RobotParams robot;
  std::vector<SplitCycleParams> joints;  // one per tail link
  std::vector<std::string> models;       // "analytic", "mujoco"
  AnalyticSettings analytic;
  MujocoSettings mujoco;
  Effects effects;
  OutputSettings output;
  RenderSettings render;

  double simDuration() const;  // output.duration_s, or tail end + settle_s
};

}  // namespace tailsim
