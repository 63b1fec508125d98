// What the user says about a robot given by its MuJoCo model file (MJCF or URDF) besides the file:
// the stance, the feet, the friction and where the tail goes. Plain values, no MuJoCo: the
// experiment loader reads them (`robot: {mjcf: PATH, ...}`, `tail: {mount: {...}}`), and
// models/mujoco/robot_import.h stands and measures the robot from them (docs/your-robot.md).
#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

#include "settings/fields.h"
#include "common/units.h"

namespace tailsim {

// Where the tail goes: under body `body`, at pos_m in that body's frame. The planar robot frame's
// forward axis is the mount body's x axis turned by yaw_rad about z (0: the body's x is forward);
// the straight tail points backward along it.
struct TailMount {
  std::string body;                   // "": the robot's root body (the one with the free joint)
  std::array<double, 3> pos_m{};      // [m]
  double yaw_rad = 0.0;               // [rad]
};

// What the user says about the model besides its file.
struct RobotModelSpec {
  std::string file;                                // MJCF or URDF (absolute or relative to the working dir)
  std::string keyframe;                            // "": the model's `home` key when it has one
  std::map<std::string, double> joint_angles_rad;  // stance by joint name (over the keyframe, or qpos0)
  std::vector<std::string> feet;                   // foot geom names; empty: those touching the floor
  double mu = -1.0;                                // < 0: from the foot contacts
  TailMount mount;
  double settle_s = 1.0;                           // standing time before the robot is measured [s]
  // The articulated run's legs: "servos", held by the model's own actuators (and tailsim's PD where
  // it has none); "locked", each leg joint held at its stood angle by a MuJoCo joint equality.
  std::string legs = "servos";
};

// The experiment keys (settings/fields.h), declared once. `robot: {mjcf, mu, stance: {keyframe,
// joints_deg}, feet}`; `joints_deg` (a map of joint names) and `feet` (a list of geom names) are
// read by the loader's robot reader, which names them in its messages.
template <class V, class S>
settings::For<S, RobotModelSpec> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  v.text(Field{"mjcf", "the robot's MuJoCo model file (MJCF or URDF), relative to the experiment file; the "
                       "planar models' parameters are derived from it (docs/your-robot.md)"},
         s.file, settings::TextRule{true, {}});
  v.number(Field{"mu", "foot-floor friction for every model (absent, shown as -1: the model's foot contacts)"}, s.mu,
           Limits::nonNegative());
  v.text(Field{"legs", "the articulated MuJoCo run's legs: `servos` (the model's own actuators) or `locked` (each "
                       "leg joint held at its stood angle by a joint equality: legs as stiff as the rigid box's)"},
         s.legs, settings::TextRule{false, {"servos", "locked"}});
}
// `robot.stance`: a keyframe, with joint angles over it (`joints_deg: {NAME: deg}`).
struct RobotStanceKeys {
  std::string keyframe;
};
template <class V, class S>
settings::For<S, RobotStanceKeys> declareFields(V& v, S& s) {
  v.text(settings::Field{"keyframe", "the model's keyframe to stand in (absent: `home` when the model has it, else "
                                     "the reference pose qpos0 with joints_deg over it)"},
         s.keyframe, settings::TextRule{});
}
// `tail.mount` (a robot given by its model file only).
template <class V, class S>
settings::For<S, TailMount> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  v.text(Field{"body", "the body the tail hangs under (absent: the root body, the one with the free joint)"}, s.body,
         settings::TextRule{});
  v.numbers(Field{"pos_m", "the tail base in that body's frame [m]"}, s.pos_m);
  v.number(Field{"yaw_deg", "forward is the body's x axis turned by this about z; the straight tail points backward "
                            "[deg]",
                 units::kRadPerDeg, "yaw_rad"},
           s.yaw_rad, Limits::closed(-360.0, 360.0));
}

}  // namespace tailsim
