// MJCF generation (tinyxml2) for the MuJoCo contact model: the quadruped on four point-like
// feet with an n-link planar tail (paper Figs. 1-3, Tables 1-2). See docs/mujoco-model.md.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "models/mujoco/mujoco_settings.h"
#include "robot/robot_params.h"
#include "robot/scene_effects.h"

namespace tailsim {

// Element names in the generated model (menagerie style).
namespace mjcf {
inline constexpr const char* kQuadrupedBody = "quadruped";
inline constexpr const char* kRootJoint = "root";   // freejoint (translation) or ball (no translation)
inline constexpr const char* kHeightJoint = "height";  // slide z, only when translation is off
inline constexpr const char* kFloorGeom = "floor";
inline constexpr const char* kHomeKey = "home";
std::string footGeomName(int k);       // k = 1..4: foot1_FL, foot2_FR, foot3_RR, foot4_RL
std::string tailBodyName(int i);       // i = 1..n: tail_link<i>
std::string tailJointName(int i);      // tail_joint<i>
std::string tailActuatorName(int i);   // tail_motor<i>
}  // namespace mjcf

// Foot position (k = 1..4) relative to the quadruped COM in the body x-y plane, Eq. (17):
// (d_Q2C + x_F,k, y_F,k), x_F = +-l_F/2, y_F = +-w_F/2.
std::array<double, 2> footXY(const QuadrupedParams& q, int k);

// Quadruped principal inertia (Ixx, Iyy, Izz): Izz = I_zz,Q exactly; Ixx, Iyy from the uniform box
// (height 0.1 m, x:y aspect l_F:w_F) whose Izz equals I_zz,Q. Only Izz matters to the planar paper.
std::array<double, 3> quadrupedDiagInertia(const QuadrupedParams& q);

// Tail link principal inertia about its COM: (axial, transverse, Izz) = (0.01 Izz, Izz, Izz)
// (a slender link; Izz exact from Table 2).
std::array<double, 3> tailLinkDiagInertia(const TailLink& l);

// z inertia about joint i of links i..n with the tail straight (all theta = 0): the servo's load.
std::vector<double> tailJointInertias(const RobotParams& p);

// PD gains of the tail position servos. kp_i = I_i w_n^2, kv_i = 2 I_i w_n (critically damped),
// w_n = servo_wn_dt / timestep_s, I_i from tailJointInertias. settings.kp/kv > 0 override.
struct ServoGains {
  std::vector<double> kp;  // [N m / rad]
  std::vector<double> kv;  // [N m s / rad]
};
ServoGains tailServoGains(const RobotParams& p, const MujocoSettings& s);

// The foot friction coefficient written into the model: settings.mu, or max(mu_s, mu_d) if mu < 0
// (paper-notes point 1); 0 for FrictionLaw::kNone; 0 at start for kContinuous (mu(0) = 0, the
// simulation updates it every step).
double footFrictionCoefficient(const RobotParams& p, const MujocoSettings& s, const Effects& e);

// One self-contained MJCF document (no includes, no assets on disk). Throws std::invalid_argument
// on bad parameters or settings.
std::string generateMjcf(const RobotParams& p, const MujocoSettings& s, const Effects& e);

// The paper robot (Table 1 defaults of RobotParams, Table 2 n-link tail).
RobotParams paperRobot(int links);

// ---- Menagerie form (mjcf/README.md) ------------------------------------------------------------
// The same robot split as MuJoCo Menagerie splits its models: a robot file (compiler, options,
// default classes, bodies, joints, actuators, the `home` keyframe, comments naming the paper's
// symbols) and a scene that <include>s it and adds a floor with MuJoCo's default friction (1), a light
// and a skybox. The foot geoms carry `priority="1"`, so every contact of a foot takes the foot's
// friction, condim, solref and solimp whatever the floor says (MuJoCo's mj_contactParam: the geom
// of higher priority wins; equal priorities take the max friction and mix solref/solimp): the paper's
// mu in any scene. generateMjcf above stays the single-file model that tailsim simulates.
struct MenagerieFiles {
  std::string robot_file;  // "tailsim_<stem>.xml"
  std::string robot_xml;
  std::string scene_file;  // "scene_<stem>.xml"
  std::string scene_xml;
};

// The foot friction written into the robot file: footFrictionCoefficient, except the continuous
// law (which the simulation varies every step from mu(0) = 0) gets its stiction value
// (settings.mu, or max(mu_s, mu_d)): a static file cannot vary it, and mu = 0 would let the robot
// slide off in any viewer.
double menagerieFootFriction(const RobotParams& p, const MujocoSettings& s, const Effects& e);

// Half-width of the tail servos' ctrlrange in the robot file [rad]: a half turn each way plus room
// for the velocity feed-forward (kv/kp) theta_dot. (The single-file model has no ctrl limits.)
inline constexpr double kMenagerieCtrlRange = 4.0;

// stem: one file-name component of [A-Za-z0-9._=,~-], not starting with '.' or '-' (else
// std::invalid_argument). Throws std::invalid_argument on bad parameters or settings, as generateMjcf.
MenagerieFiles generateMenagerie(const RobotParams& p, const MujocoSettings& s, const Effects& e,
                                 const std::string& stem);

// Writes both files into dir (created if missing), each whole or not at all; returns their paths.
std::vector<std::string> writeMenagerie(const MenagerieFiles& f, const std::string& dir);

// `tailsim mjcf --links N --out FILE`: the paper robot with default settings and effects, written
// as writeUserFile (FILE may be "-" for stdout, a symlink or a device). True when it went to a stream.
bool writeMjcfFile(int links, const std::string& out);

// Every generated model's first comment holds this; `--out FILE` replaces only a file that does.
inline constexpr const char* kGeneratedMjcfMarker = "Generated by tailsim";

// `tailsim mjcf --links N --menagerie DIR`: DIR/tailsim_n<N>.xml and DIR/scene_n<N>.xml (the files in mjcf/).
std::vector<std::string> writeMenagerieFiles(int links, const std::string& dir);

}  // namespace tailsim
