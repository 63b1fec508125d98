// One experiment case, fully resolved: what a YAML experiment file (after sweep expansion)
// turns into. Every model reads its settings from here; nothing else is global.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "robot/robot_params.h"
#include "trajectory/split_cycle_profile.h"
#include "robot/scene_effects.h"
#include "analytic_model/analytic_settings.h"
#include "analytic_model/per_foot_model.h"
#include "mujoco_model/mujoco_settings.h"
#include "rendering/render_settings.h"
#include "results/output_settings.h"

namespace tailsim {


enum class CaseKind {
  kSimulate,  // integrate a trajectory
  kPose,      // loads at one tail state (Figs. 8, 10)
};
inline const settings::EnumNames<CaseKind>& kindNames() {
  static const settings::EnumNames<CaseKind> k = {{CaseKind::kSimulate, "simulate"}, {CaseKind::kPose, "pose"}};
  return k;
}
inline const char* name(CaseKind k) { return settings::nameOf(kindNames(), k); }

// kind: pose — evaluate loads at one tail state, no time integration (Figs. 8, 10).
struct PoseSpec {
  std::vector<double> theta_rad;         // per joint  [rad]
  std::vector<double> thetadot_radps;    // per joint  [rad/s]
  std::vector<double> thetaddot_radps2;  // per joint  [rad/s^2]
};

struct ExperimentCase {
  std::string experiment;   // experiment name
  std::string name;         // case name: "base" or "key=value,key=value" for sweeps
  std::string source_file;  // the YAML file it came from
  std::string robot_file;   // the robot file it names (absolute)
  std::map<std::string, std::string> sweep_values;  // swept key -> value as written

  CaseKind kind = CaseKind::kSimulate;
  PoseSpec pose;  // kind == kPose

  RobotParams robot;
  std::vector<SplitCycleParams> joints;  // one per tail link
  std::vector<std::string> models;       // "analytic", "perfoot", "mujoco" (experiments/model_registry.h)
  AnalyticSettings analytic;
  PerFootSettings perfoot;
  MujocoSettings mujoco;
  Effects effects;
  OutputSettings output;
  RenderSettings render;

  TailTrajectory trajectory() const;  // one SplitCycleProfile per joint
  double simDuration() const;         // output.duration_s, or tail end + settle_s

};

}  // namespace tailsim
