// A generated planar tail attached to a user's MuJoCo robot (robot_import.h), and the articulated
// run: the robot stands in its stance with the tail, then the tail follows its trajectory under
// tailsim's servos (controllers/tail_controller.h) while the legs stay held (docs/your-robot.md).
#pragma once

#include <string>
#include <vector>

#include "models/mujoco/mujoco_settings.h"
#include "models/mujoco/robot_import.h"
#include "results/time_series.h"
#include "robot/robot_params.h"
#include "trajectory/split_cycle_profile.h"

namespace tailsim {

// The robot's MJCF (r.model.xml) with the tail under the mount body: links tail_link1..n (hinges
// about the mount body's z, theta = 0 straight back along the planar frame's -x), each link's
// COM, mass and I_zz as given, visual capsules that do not collide, and one PD servo per joint
// (tail_motor<i>, gains tailServoGains at the model's own timestep). The model's keyframes are
// removed (their qpos has no tail); the stance is set by joint name from r.settled_qpos. A mu the
// user gave (r.mu_given) becomes the sliding friction of the feet and the floor.
std::string attachTail(const DerivedRobot& r, const TailMount& mount, const std::vector<TailLink>& tail,
                       const MujocoSettings& s);

// The legs' set-points trimmed for the tail's weight before standing (attach_tail.cc trimStance):
// rounds of kTrimRoundS, each moving every held joint's set-point by kTrimGain times its error from
// the settled stance, until the body's tilt from the stance is below kTrimTiltTolDeg, stops improving
// by 10 % a round, or after kTrimRounds.
inline constexpr double kTrimRoundS = 0.5;       // [s]
inline constexpr double kTrimGain = 0.5;         // share of the error moved per round
inline constexpr double kTrimTiltTolDeg = 0.2;   // [deg]
inline constexpr int kTrimRounds = 8;
struct StanceTrim {
  int rounds = 0;                  // rounds stood (0: legs locked, or none held)
  double trim_s = 0.0;             // simulated time spent trimming [s]
  double max_offset_deg = 0.0;     // largest set-point change from the stance's set-point [deg]
  double residual_deg = 0.0;       // largest held joint's error from its settled-stance angle at the end [deg]
  double end_tilt_deg = 0.0;       // the body's tilt from the stance after the last kept round [deg]
  double max_rel_tilt_deg = 0.0;   // largest tilt from the stance while trimming [deg]
};

struct ArticulatedRun {
  bool ok = true;
  std::string error;
  // Tilt: the angle of the root body's z axis from the world's z (absolute), or from its own z in
  // the settled stance the run starts from, before the tail's weight acts (from the stance).
  double stance_tilt_deg = 0.0;         // the settled stance's own tilt [deg]
  StanceTrim trim;                      // the legs' set-points trimmed for the tail, before standing
  double stand_max_tilt_deg = 0.0;      // largest body tilt while standing with the tail held [deg]
  double stand_end_tilt_deg = 0.0;      // body tilt at the end of standing (the stroke's start) [deg]
  double stand_max_rel_tilt_deg = 0.0;  // largest tilt from the stance while standing with the tail [deg]
  double stand_end_rel_tilt_deg = 0.0;  // tilt from the stance at the end of standing [deg]
  double max_tilt_deg = 0.0;            // largest body tilt during the stroke and after [deg]
  double max_rel_tilt_deg = 0.0;        // largest tilt from the stance during the stroke and after [deg]
  double phi_net_deg = 0.0;         // heading change of the root body from the stroke's start [deg]
  double stand_s = 0.0, run_s = 0.0;
  int feet_in_contact = 0;          // foot geoms touching the floor at the stroke's start
  long steps = 0;                   // mj_step calls, standing included
  bool at_rest = true;              // yaw rate below 0.1 deg/s and COM speed below 1 mm/s at the end
  std::vector<std::string> warnings;
  // sample_dt_s > 0: rows from the stroke's start (t_s = 0) every sample_dt_s: t_s, theta<i>_deg,
  // thetadot<i>_dps, x_m, y_m (root body), phi_deg (heading change), phidot_dps, track_err<i>_deg.
  TimeSeries series;
};

// Standing with the tail: a larger tilt from the stance is warned about.
inline constexpr double kStandingTiltLimitDeg = 1.0;
// A fall: the root body tilted more than this from its stance (trimming, standing or the stroke):
// the run fails ("the robot fell over"), phi_net NaN. Over kNearFallTiltFromStanceDeg during the
// stroke: the "nearly fell" uncertain warning. (The rigid box's limit is mujoco.max_tilt_deg, 5
// deg: a robot on compliant legs rocks further and stands, ANYmal C up to 9 deg at 600 deg/s.)
inline constexpr double kFallTiltFromStanceDeg = 45.0;      // [deg]
inline constexpr double kNearFallTiltFromStanceDeg = 20.0;  // [deg]

// Stands stand_s with the tail held at theta(0), then runs the stroke and settle_after_s more, at
// the model's own timestep (once the body rests after the stroke, at s.rest_step_factor times it:
// step_schedule.h, by the rigid box's guards read from the model); one run, without an uncertainty
// estimate (simulateArticulated).
ArticulatedRun runArticulated(const DerivedRobot& r, const TailMount& mount, const std::vector<TailLink>& tail,
                              const TailTrajectory& trajectory, const MujocoSettings& s, double stand_s,
                              double settle_after_s, double sample_dt_s = 0.0);

// The articulated run as a model's RunResult (tailsim run's `mujoco` model on a robot from its model
// file): phi_net, the rows, the tilt figures in `extra` and the warnings.
RunResult articulatedRunResult(const ArticulatedRun& a, const std::string& model);

// The articulated run as tailsim's `mujoco` model reports it (articulatedRunResult) with, when
// s.uncertainty, its own error estimate: the same robot run again at twice the model's timestep,
// the tail servo's natural frequency kept and the legs on the model's own actuators, by the rule
// of the rigid-box run (run_uncertainty.h: phi_net_uncertainty_deg, phi_net_check_deg,
// uncertainty_solver_steps, the uncertain warning); the check run ends once the body rests after
// the stroke. Of s it reads the tail servo (kp, kv, servo_wn_dt, velocity_feedforward,
// inverse_dynamics_feedforward), rest_step_factor, uncertainty and uncertainty_warn_share; the step
// is the model's own. wall_time_s covers both runs. `run`: optional, receives the run itself (its
// tilt figures).
RunResult simulateArticulated(const DerivedRobot& r, const TailMount& mount, const std::vector<TailLink>& tail,
                              const TailTrajectory& trajectory, const MujocoSettings& s, double stand_s,
                              double settle_after_s, double sample_dt_s, const std::string& model,
                              ArticulatedRun* run = nullptr);

}  // namespace tailsim
