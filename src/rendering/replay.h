// Replaying time series for video: the renderer does not run physics. It samples the
// models' TimeSeries (columns t_s, x_m, y_m, phi_deg, theta<i>_deg) at each frame's time, poses
// the MuJoCo model from the MuJoCo series and a "ghost" from the analytic series with the
// paper's planar kinematics (Eqs. 1-3).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "results/time_series.h"
#include "robot/robot_params.h"
#include "trajectory/split_cycle_profile.h"

struct mjModel_;
typedef struct mjModel_ mjModel;

namespace tailsim {

// Planar state of the robot (radians inside): quadruped COM p_Q = (x, y), yaw phi, joints theta_i.
struct PlanarState {
  double x = 0.0, y = 0.0, phi = 0.0;  // [m], [m], [rad]
  std::vector<double> theta;           // theta_1..theta_n  [rad]
};

// Linear interpolation of the columns t_s, x_m, y_m, phi_deg, theta<i>_deg (i = 1..n_links).
// Times outside the series clamp to its ends. Missing columns throw std::invalid_argument
// naming the column; the series must have >= 1 row and increasing t_s.
class PlanarStateSampler {
 public:
  PlanarStateSampler(const TimeSeries& ts, int n_links, const std::string& what);
  PlanarState at(double t) const;
  double startTime() const { return t_->front(); }
  double endTime() const { return t_->back(); }

 private:
  const std::vector<double>* t_;
  const std::vector<double>*x_, *y_, *phi_;
  std::vector<const std::vector<double>*> theta_;
};

// Paper Eqs. (1)-(3): tail base p_B = p_Q - d_Q2B R_Q x; R_B = R_Q R_Z(180 deg); link i points
// along R_B R_T,i x with R_T,i = R_Z(theta_1 + ... + theta_i); joint i+1 = joint i + L_L,i R_T,i x
// (Eq. 3 with the paper-notes misprint fix).
struct PlanarTailPose {
  std::vector<std::array<double, 2>> joints;  // p of joint 1 (= p_B) .. joint n, then the tip (n+1 points)
  std::vector<double> link_yaw;               // world yaw of link i  [rad]
};
PlanarTailPose planarTailPose(const RobotParams& robot, const PlanarState& s);

// Tail phase for the on-frame text: accelerating while some joint is in [t0, t1], else
// decelerating while some joint is in (t1, t2], else at rest (Eq. 20's pieces).
enum class TailPhase { kAtRest, kAccelerating, kDecelerating };
TailPhase tailPhase(const TailTrajectory& traj, double t);
// True when every joint moves by a split-cycle stroke (no spline): only then has the tail phases.
bool splitCycleStrokes(const TailTrajectory& traj);
const char* tailPhaseName(TailPhase p);

// Where the planar state goes in a MuJoCo model's qpos, found by joint name (mj_name2id with the
// generator's names, src/models/mujoco/mjcf_generator.h), not by assuming an order: the root joint
// "root" is a free joint (translation on) or a ball joint (translation off; x, y stay fixed);
// the tail joints "tail_joint<i>" are hinges about z.
struct MujocoReplayLayout {
  int root_body = -1;    // body moved by the root joint
  int root_qpos = -1;    // qpos address of the root joint
  bool free_root = true;  // free (7 numbers) or ball (4 numbers)
  std::vector<int> tail_qpos;                    // one per link
  std::array<double, 3> root_pos0{};            // free joint: qpos0 position (z kept)
  std::array<double, 4> root_quat0{1, 0, 0, 0};  // qpos0 orientation (yaw applied on top)
  std::array<double, 2> com_offset{};            // quadruped COM in the root body frame (x, y)
  std::string describe(const mjModel* m) const;  // for error messages and docs
};

// Throws std::runtime_error listing the model's joints when the layout cannot be found.
MujocoReplayLayout findReplayLayout(const mjModel* m, int n_links);

// Writes the state into qpos: the quadruped COM lands on (x, y) (free root), the yaw is phi on top
// of qpos0's orientation, z stays as in qpos0; a ball root ignores x, y.
void setReplayQpos(const mjModel* m, const MujocoReplayLayout& layout, const PlanarState& s, double* qpos);

}  // namespace tailsim
