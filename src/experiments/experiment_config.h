// One experiment case, fully resolved: what a YAML experiment file (after sweep expansion)
// turns into. Every model reads its settings from here; nothing else is global.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "robot/robot_model_spec.h"
#include "robot/robot_params.h"
#include "trajectory/split_cycle_profile.h"
#include "robot/scene_effects.h"
#include "models/analytic/analytic_settings.h"
#include "models/perfoot/per_foot_model.h"
#include "models/mujoco/mujoco_settings.h"
#include "rendering/render_settings.h"
#include "results/output_settings.h"

namespace tailsim {

struct DerivedRobot;  // models/mujoco/robot_import.h


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
  std::string robot_file;   // the robot file it names (absolute); robot: {mjcf: ...}: the model file
  // robot: {mjcf: PATH, ...}: the robot from its MuJoCo model file. The loader reads the spec (and
  // where each key was written, "file:line:col" by dotted key); robot, quadruped, friction, gravity
  // and a `tail: {links: n}` tail are then derived by resolveRobotModels (experiments/robot_model_cases.h)
  // before any case runs, which sets robot_derived (the stood robot, shared by the cases of one
  // experiment: the MuJoCo model runs it articulated).
  std::optional<RobotModelSpec> robot_model;
  int robot_model_links = 0;  // tail: {links: n} of a model-file robot (0: tail: {custom: [...]})
  std::map<std::string, std::string> robot_model_at;
  std::shared_ptr<const DerivedRobot> robot_derived;
  std::map<std::string, std::string> sweep_values;  // swept key -> value as written

  CaseKind kind = CaseKind::kSimulate;
  PoseSpec pose;  // kind == kPose

  RobotParams robot;
  std::vector<SplitCycleParams> joints;  // one per tail link (split-cycle trajectory)
  std::vector<SplineParams> splines;     // or one per tail link (trajectory family: spline; joints empty)
  std::vector<std::string> models;       // "analytic", "perfoot", "mujoco" (experiments/model_registry.h)
  AnalyticSettings analytic;
  PerFootSettings perfoot;
  MujocoSettings mujoco;
  Effects effects;
  OutputSettings output;
  RenderSettings render;

  TailTrajectory trajectory() const;  // one JointProfile per joint (split-cycle or spline)
  double simDuration() const;         // output.duration_s, or tail end + settle_s

};

// An experiment file's settings sections: each is a struct that declares its own fields once
// (settings/fields.h) and is listed once, in forEachSection below. The loader (its allowed keys and
// reading), the resolved case (result.json and the resume key), the JSON Schema and the key tables
// of docs/experiment-format.md iterate that list, so a new section is its struct + a member above
// + one line below. (Sections with checks across keys keep a reader of their own in the loader.)
struct SectionInfo {
  const char* key;    // YAML key, result.json key, doc table title
  const char* note;   // the doc table's note
  const char* model;  // in the resolved case only when this model runs (nullptr: always), so the
                      // other cases' resume keys stay as they were
};

// Calls f(SectionInfo, section member) for every section, in file order (the loader's order:
// render is read after output, whose duration it checks against).
template <class Case, class F>
void forEachSection(Case& c, F&& f) {
  f(SectionInfo{"analytic", "Solver and modelling settings of the analytic model.", nullptr}, c.analytic);
  f(SectionInfo{"perfoot",
                "Solver and modelling settings of the per-foot model (docs/per-foot-model.md); its friction "
                "law is `effects.friction`.",
                "perfoot"},
    c.perfoot);
  f(SectionInfo{"mujoco", "Settings of the MuJoCo contact model (docs/mujoco-model.md).", nullptr}, c.mujoco);
  f(SectionInfo{"effects", "Which physical effects a scene simulates; the defaults reproduce the paper.", nullptr},
    c.effects);
  f(SectionInfo{"output",
                "The output time grid both models sample on, and which rows are kept where "
                "([Time-series output](#time-series-output)).",
                nullptr},
    c.output);
  f(SectionInfo{"render", "The section's presence turns video on (`render: {}` = defaults); docs/rendering.md.",
                nullptr},
    c.render);
}

// The section keys, in forEachSection's order.
std::vector<std::string> sectionKeys();

}  // namespace tailsim
