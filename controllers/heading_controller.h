// Turning the robot to a commanded heading with a sequence of tail strokes
// (docs/design-a-tail-stroke.md "Maneuvers"). A cycle is a fast stroke from the rest angle 0 to
// +-s A (every joint alike, peak speed 2 A / dT_fast whatever the scale s) and a slow return to 0
// in return_dT_s: the fast stroke breaks stiction and turns the body, the slow one stays below it
// (the asymmetry of the paper's Fig. 11). The tail is back at 0 after each cycle, so cycles chain.
//
// HeadingController picks the next cycle from the measured heading error: a full cycle while the
// error exceeds one cycle's yaw, else the scale whose yaw (on the analytic model's yaw-vs-scale
// map) equals the error; the direction by the error's sign, so an overshoot is corrected by a
// cycle the other way. SI units inside; degrees only in the YAML keys (the `maneuver:` section).
#pragma once

#include <cmath>
#include <optional>
#include <vector>

#include "settings/fields.h"
#include "trajectory/split_cycle_profile.h"
#include "common/units.h"

namespace tailsim {

struct ManeuverSettings {
  // Angles in degrees as in the YAML (like mujoco.max_tilt_deg); heading() etc. give radians.
  double heading_deg = 90.0;              // target heading change  [deg]
  double tolerance_deg = 1.0;             // done when |target - heading| <= this  [deg]
  double stroke_deg = 60.0;               // fast-stroke amplitude A (from the rest angle 0)  [deg]
  double stroke_dT_s = 0.2;               // full fast stroke's duration  [s]
  double stroke_w_ss = 0.1;               // its split-cycle parameter
  double return_dT_s = 1.0;               // slow return's duration (any scale)  [s]
  double return_w_ss = 0.5;               // its split-cycle parameter
  double rest_s = 0.3;                    // wait after each stroke (the body comes to rest)  [s]
  double min_scale = 0.05;                // smallest stroke scale s the controller uses
  int max_strokes = 40;                   // cycles at most (open and closed loop)
  int map_points = 12;                    // analytic yaw-vs-scale map: points in [min_scale, 1]
  bool mujoco = true;                     // run MuJoCo open- and closed-loop (false: analytic plan only)
  // Not a YAML key: the fast stroke's shape at full scale (maneuver.stroke_from: a split-cycle or
  // spline trajectory, e.g. a `tailsim optimize` best.yaml). Empty: every joint from 0 to
  // +-stroke_deg in stroke_dT_s (w_ss stroke_w_ss).
  TailTrajectory stroke_shape;

  double heading() const { return units::radians(heading_deg); }  // [rad]
  double tolerance() const { return units::radians(tolerance_deg); }
  double stroke() const { return units::radians(stroke_deg); }
};

template <class V, class S>
settings::For<S, ManeuverSettings> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  v.number(Field{"heading_deg", "target heading change (positive: counter-clockwise seen from above) [deg]"},
           s.heading_deg, Limits::closed(-720.0, 720.0));
  v.number(Field{"tolerance_deg", "done when the heading is within this of the target [deg]"}, s.tolerance_deg,
           Limits{0.0, 45.0, true, false});
  v.number(Field{"stroke_deg", "fast-stroke amplitude A: every joint from 0 to +-A at full scale [deg]"}, s.stroke_deg,
           Limits{0.0, 180.0, true, false});
  v.number(Field{"stroke_dT_s", "full-scale fast stroke's duration (a scaled stroke keeps its peak speed) [s]"},
           s.stroke_dT_s, Limits{0.0, 10.0, true, false});
  v.number(Field{"stroke_w_ss", "fast stroke's split-cycle parameter"}, s.stroke_w_ss, Limits::open(0, 1));
  v.number(Field{"return_dT_s", "slow return's duration, at any scale [s]"}, s.return_dT_s, Limits{0.0, 10.0, true, false});
  v.number(Field{"return_w_ss", "slow return's split-cycle parameter"}, s.return_w_ss, Limits::open(0, 1));
  v.number(Field{"rest_s", "wait after each stroke so the body comes to rest [s]"}, s.rest_s, Limits::closed(0.0, 10.0));
  v.number(Field{"min_scale", "smallest stroke scale the controller and planner use"}, s.min_scale, Limits{0.0, 1.0, true, false});
  v.integer(Field{"max_strokes", "cycles (fast stroke + return) at most"}, s.max_strokes, Limits::closed(1, 1000));
  v.integer(Field{"map_points", "points of the analytic yaw-vs-scale map in [min_scale, 1]"}, s.map_points, Limits::closed(2, 200));
  v.boolean(Field{"mujoco", "also run MuJoCo open- and closed-loop (false: the analytic plan only)"}, s.mujoco);
}

// One cycle: scale s in (0, 1], direction +1 or -1 (the sign of the fast stroke's dtheta).
struct StrokeCommand {
  double scale = 1.0;
  int direction = 1;
};

// The trajectory with every start time shifted so the earliest is 0 (durations and delays kept).
TailTrajectory shiftedToZero(const TailTrajectory& t);

// The smallest scale a fast stroke may have: its shortest joint duration at least an experiment's
// shortest dT (limits::kMinDT_s).
double minScaleFloor(const ManeuverSettings& s, int n_joints);

// The fast stroke at full scale, direction +1, starting at t = 0: stroke_shape shifted to start at
// 0, or (no shape) every joint from 0 to stroke_deg in stroke_dT_s.
TailTrajectory fastStrokeShape(const ManeuverSettings& s, int n_joints);
// Every joint's angle where a cycle of `direction` starts (and its return ends)  [rad]: the
// shape's start pose, mirrored (negated) for direction -1.
std::vector<double> cycleStartPose(const ManeuverSettings& s, int n_joints, int direction);

// A cycle for an n-joint tail, starting at t_start (absolute time): the fast stroke (the shape
// scaled: each joint's amplitude about its start angle and every duration and delay by `scale`, so
// the peak speeds stay; mirrored for direction -1), and the slow return to the start pose in
// return_dT_s (split-cycle, return_w_ss), rest_s after the fast stroke's end. When `from` (the pose
// the tail is at) differs from the cycle's start pose, a slow move there (`pre`, like the return)
// and rest_s come first. Every part is a trajectory in absolute time.
struct CycleStrokes {
  TailTrajectory pre, fast, back;  // pre.joints empty: no move before the stroke
  double rest_s = 0.0;
  bool hasPre() const { return !pre.joints.empty(); }
  double fastEnd() const { return fast.endTime(); }
  double backEnd() const { return back.endTime(); }
  double end() const { return back.endTime() + rest_s; }  // the cycle is over (after its last rest)
};
CycleStrokes cycleStrokes(const ManeuverSettings& s, int n_joints, const StrokeCommand& c, double t_start,
                          const std::vector<double>* from = nullptr);
// A cycle's whole duration without a move before it: fast stroke, rest, return, rest.
double cycleDuration(const ManeuverSettings& s, double scale);

// Yaw per cycle as a function of the scale (monotone in |yaw| after the map is built), for
// direction +1; direction -1 is its mirror image.
struct YawMap {
  std::vector<double> scale;    // increasing, last = 1
  std::vector<double> yaw_rad;  // cycle yaw at that scale, direction +1
  double full() const { return yaw_rad.back(); }
  // The scale whose |yaw| is |want| (linear interpolation; clamped to [scale.front(), 1]).
  double scaleFor(double want_abs_rad) const;
  // |yaw| at a scale (linear interpolation; the first point's below it).
  double yawAt(double scale) const;
};

class HeadingController {
 public:
  HeadingController(ManeuverSettings settings, YawMap map);
  // The next cycle for the measured heading change phi [rad], or none when within tolerance.
  // yaw_factor: how much of the map's yaw a partial cycle turned the body last (measured /
  // predicted); the scale is chosen for the error divided by it.
  std::optional<StrokeCommand> next(double phi_rad, double yaw_factor = 1.0) const;
  const ManeuverSettings& settings() const { return s_; }
  const YawMap& map() const { return map_; }

 private:
  ManeuverSettings s_;
  YawMap map_;
};

}  // namespace tailsim
