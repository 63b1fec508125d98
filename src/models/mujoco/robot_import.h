// A user's quadruped from its MuJoCo model file (MJCF, or URDF through MuJoCo's own URDF reader):
// loaded as written, geoms whose mesh or texture file is missing dropped when they cannot collide,
// stood on the floor in a stance held by the model's own actuators, and the planar models'
// parameters derived from it (docs/your-robot.md).
#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

#include "models/mujoco/mujoco_handles.h"
#include "robot/robot_model_spec.h"
#include "robot/robot_params.h"

namespace tailsim {

// The user's file as tailsim compiles it: includes inlined, asset folders absolute, missing-file
// geoms and textures dropped, a floor added when the model has none.
struct PreparedModel {
  std::string xml;             // MJCF text
  std::string source;          // the file it came from (absolute)
  bool from_urdf = false;
  int dropped_geoms = 0;       // non-colliding geoms whose mesh file is missing
  int dropped_textures = 0;    // textures whose file is missing (their materials keep their colour)
  std::string floor_geom;      // the floor's geom name
  std::map<std::string, double> urdf_effort_Nm;  // a URDF's joint <limit effort> (> 0) by joint name
  std::vector<std::string> notes;  // one line each, for the user
};

// Throws ConfigError-like std::runtime_error (RobotImportError) naming the file, the geom and the
// missing file when a colliding geom's mesh is missing, or a body whose mass came from a dropped geom.
PreparedModel prepareRobotModel(const std::string& file);

// A position servo of the model: a joint actuator whose bias is affine with -kp q (MJCF <position>,
// or <general biastype="affine"> with biasprm[1] < 0); its ctrl is a joint angle. Others (a
// <motor>, ctrl a torque) are not.
bool isPositionServo(const mjModel* m, int a);

// A position servo's ctrl per radian of its joint (its gear for a <position>), and the ctrl at
// which it holds the joint at q with no force.
double servoCtrlPerRad(const mjModel* m, int a);
double servoCtrlFor(const mjModel* m, int a, double q);

class RobotImportError : public std::runtime_error {
 public:
  // key: the experiment key the error is about (robot.mjcf, robot.stance, robot.feet,
  // tail.mount.body), for an experiment's ConfigError.
  explicit RobotImportError(const std::string& what, std::string key = "robot.mjcf")
      : std::runtime_error(what), key_(std::move(key)) {}
  const std::string& key() const { return key_; }

 private:
  std::string key_;
};

// One derived value, as `tailsim robot` prints it.
struct DerivedValue {
  std::string key;     // e.g. "quadruped.izz_kgm2"
  double value = 0.0;
  std::string unit;
  std::string source;  // where it came from
};

// The robot standing in its stance, and the planar models' parameters derived from it.
struct DerivedRobot {
  PreparedModel model;
  QuadrupedParams quadruped;
  double mu = 0.0;                      // foot-floor friction (contacts' mu, or the spec's)
  bool mu_given = false;                // the spec's mu: the articulated run sets it on the feet and floor
  double gravity_mps2 = 9.81;
  std::vector<std::string> feet;        // foot geom names, ordered FL, FR, RR, RL (planar frame); 3 feet: front to back
  int foot_count = 4;                   // 3 or 4: on 3 feet only the articulated MuJoCo model runs (threeFeetNote)
  std::string root_body, mount_body;
  std::string stance;                   // how the stance was set, in words
  bool legs_locked = false;             // the spec's legs: locked (attachTail adds the joint equalities)
  double tilt_deg = 0.0;                // root body tilt after settling [deg]
  double stood_s = 0.0;                 // how long it stood before it was measured: settle_s, or longer until at rest [s]
  double lateral_com_to_feet_m = 0.0;   // y of the foot centroid in the planar frame (the planar models take 0) [m]
  double lateral_mount_m = 0.0;         // y of the tail base in the planar frame [m]
  // MuJoCo's own figures, for checking: body_subtreemass of the root body and the z-z entry of the
  // composite inertia (the sum of d->cinert over the robot's bodies, about their common COM).
  double mujoco_subtreemass_kg = 0.0;
  double mujoco_cinert_izz_kgm2 = 0.0;
  std::vector<DerivedValue> values;
  std::vector<std::string> notes;
  // The stood robot, for a model that adds to it (attach_tail.h): qpos by joint name (every joint
  // is named by prepareRobotModel), the held joints' targets, and the joints held by tailsim's PD.
  std::map<std::string, std::vector<double>> settled_qpos;
  std::map<std::string, double> hold_target_rad;
  std::vector<std::string> pd_joints;
  // The torque limit of each PD-held joint that has one (its motor's ctrlrange or forcerange times
  // the gear, or the URDF's effort; the smallest): tailsim's PD never exceeds it. [N m]
  std::map<std::string, double> pd_torque_limit_Nm;
  // Each foot as (body name, index of the geom among its body's geoms): unnamed geoms found again
  // in a model with more bodies.
  std::vector<std::pair<std::string, int>> foot_geoms;
};

// The PD tailsim adds on a joint that no position actuator of the model holds: the spring through
// qfrc_applied, the damper as the joint's own damping (addStancePdDamping), which MuJoCo's Euler and
// implicit integrators treat implicitly (an explicit kv = 5 on a 0.2 kg calf at 2 ms diverges).
inline constexpr double kStancePdKp = 200.0;  // [N m/rad]
inline constexpr double kStancePdKv = 5.0;    // [N m s/rad]
// Adds kStancePdKv to the damping of each of these joints' dofs.
void addStancePdDamping(mjModel* m, const std::vector<int>& joints);
// The PD's spring torque towards `target`, within +-limit (the joint's own actuator limit; HUGE_VAL: none).
inline double stancePdTorque(double target, double q, double limit) {
  const double t = kStancePdKp * (target - q);
  return t > limit ? limit : t < -limit ? -limit : t;
}

// Loads, stands (settle_s with the legs held) and measures the robot. Throws RobotImportError with
// a message for the user (no stance, not on 3-4 feet, an attribute MuJoCo 2.2 does not know at its
// file and line, MuJoCo's refusal of the file, ...); MujocoError when MuJoCo fails while standing.
DerivedRobot deriveRobot(const RobotModelSpec& spec);

// Why a robot on 3 feet runs only as the articulated MuJoCo model (a note of deriveRobot, and the
// error of an experiment that asks another model of it).
std::string threeFeetNote(const DerivedRobot& r);

// The table `tailsim robot` prints: every derived value with its unit and source, then the notes.
std::string describeDerivedRobot(const DerivedRobot& r);

}  // namespace tailsim
