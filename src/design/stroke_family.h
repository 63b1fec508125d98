// Tail-stroke families for the optimiser, the limits a stroke must keep, and the
// stroke's figures (peak joint speed, angle range, peak joint torque, energy) measured on a
// sampled trajectory. SI units inside (radians); degrees only in the YAML (optimize_config.h).
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "models/planar/tail_dynamics.h"
#include "robot/robot_params.h"
#include "trajectory/split_cycle_profile.h"

namespace tailsim {

enum class StrokeFamily { kSplitCycle, kSpline };
enum class StrokeEnd { kAtRest, kAtStart };  // the tail ends at rest anywhere, or where it started
enum class StrokeObjective { kPhiNet, kPhiNetPerTorque, kPhiNetPerEnergy };
// The model whose phi_net the objective is: analytic and per-foot are searched directly; MuJoCo
// re-ranks the best candidates of a search on the analytic or per-foot model.
enum class ObjectiveModel { kAnalytic, kPerFoot, kMujoco };
const char* objectiveModelName(ObjectiveModel m);

// One joint's actuator and range: its angle stays in [theta_min, theta_max], its speed within
// thetadot_max, its torque within torque_max.
struct JointLimits {
  double theta_min_rad = -M_PI / 2, theta_max_rad = M_PI / 2;
  double thetadot_max_radps = 600.0 * M_PI / 180.0;
  double torque_max_Nm = 0.0;  // 0 = no torque limit
};

// What the search may vary and what a stroke must keep. The joint limits are per joint: `joints`
// holds one entry per joint, or is empty and the scalars below hold for every joint (joint(i)).
struct StrokeLimits {
  double theta_min_rad = -M_PI / 2, theta_max_rad = M_PI / 2;
  double thetadot_max_radps = 600.0 * M_PI / 180.0;
  double torque_max_Nm = 0.0;  // 0 = no torque limit
  std::vector<JointLimits> joints;  // empty: the scalars for every joint
  JointLimits joint(std::size_t i) const {
    return joints.empty() ? JointLimits{theta_min_rad, theta_max_rad, thetadot_max_radps, torque_max_Nm} : joints.at(i);
  }
  StrokeEnd end = StrokeEnd::kAtRest;
  double dT_min_s = 0.05, dT_max_s = 1.0;      // stroke duration range  [s]
  double w_ss_min = 0.05, w_ss_max = 0.95;     // split-cycle only
  double t0_max_s = 0.0;                       // start delay range [0, t0_max]  [s]
};

// A family maps a point x of the unit box [0, 1]^dim to a trajectory of n joints.
struct StrokeFigures;

struct StrokeSpace {
  StrokeFamily family = StrokeFamily::kSplitCycle;
  int n_links = 1;
  int knots = 3;  // spline: interior knots K per joint
  StrokeLimits limits;
  // Split-cycle only: each joint's stroke direction, +1 (end >= start), -1 (end <= start) or 0
  // (free); empty = all free. With a direction, the point's second coordinate is the share of the
  // way from the start angle to the angle limit on that side.
  std::vector<int> directions;
  // limits.over_torque: slow_down. A stroke whose peak joint torque (tail base held still: `tail`'s
  // torques) exceeds a joint's limit is slowed in time, every joint's duration and start delay by
  // one factor s >= 1, until it meets the limit (those torques scale with 1/s^2; speeds fall as
  // 1/s), or as far as the dT and start-delay ranges allow (it then stays over the limit);
  // slowedToTorqueLimit.
  // false (penalize): the stroke is searched as it is and an excess counts as a violation.
  bool slow_down_over_torque = false;
  std::vector<TailLink> tail;

  int dimPerJoint() const;
  int dim() const { return n_links * dimPerJoint(); }
  TailTrajectory trajectory(const std::vector<double>& x) const;  // x in [0, 1]^dim (clamped)
  // The same; with slow_down_over_torque also the returned stroke's figures (of `tail`, computed
  // on the way) into *figures, and true; false (figures untouched) otherwise.
  TailTrajectory trajectory(const std::vector<double>& x, StrokeFigures* figures, bool* have_figures) const;
  // The unit-box point of a split-cycle trajectory (the search's start); entries are clamped.
  std::vector<double> pointOf(const std::vector<SplitCycleParams>& joints) const;
};

// The same stroke run k times faster (every duration and start delay divided by k): joint speeds
// scale by k, joint torques and the tail's loads on the body (all inertial) by k^2.
TailTrajectory timeScaled(const TailTrajectory& traj, double k);

// StrokeSpace::slow_down_over_torque: t itself when it keeps L's torque limits; else t slowed by the
// smallest s >= 1 that brings every joint's peak torque (strokeFigures of links) within L, capped
// where a joint's dT would pass L.dT_max_s or its start delay L.t0_max_s (the stroke then stays over
// the limit).
// figures (optional): the returned stroke's figures, computed on the way.
TailTrajectory slowedToTorqueLimit(const std::vector<TailLink>& links, const StrokeLimits& L, const TailTrajectory& t,
                                   StrokeFigures* figures = nullptr);

// slowedToTorqueLimit with every correction read from the slowed stroke's full samples: what its
// windowed corrections must match (tests), and its fallback where they do not.
TailTrajectory slowedToTorqueLimitOnFullSamples(const std::vector<TailLink>& links, const StrokeLimits& L,
                                                const TailTrajectory& t, StrokeFigures* figures = nullptr);

// Joint torques tau_i = M_J,i (the Newton-Euler recursion of Eqs. 5-7, tail base held still).
std::vector<double> jointTorques(const std::vector<TailLink>& links, const std::vector<JointState>& joints);
// The same into tau, with kin as scratch (no allocation once sized): for sampling loops.
void jointTorques(const std::vector<TailLink>& links, const std::vector<JointState>& joints, TailKinematics& kin,
                  std::vector<double>& tau);

// One joint's figures over the samples.
struct JointFigures {
  double theta_min_rad = 0, theta_max_rad = 0;
  double peak_speed_radps = 0;  // max |thetadot_i|
  double peak_torque_Nm = 0;    // max |tau_i|
};

struct StrokeFigures {
  double theta_min_rad = 0, theta_max_rad = 0;  // over all joints and samples
  double peak_speed_radps = 0;                  // max |thetadot_i|
  double peak_torque_Nm = 0;                    // max |tau_i|
  double energy_J = 0;                          // sum_i integral |tau_i thetadot_i| dt
  double end_offset_rad = 0;                    // max_i |theta_i(end) - theta_i(start)|
  std::vector<JointFigures> joints;             // per joint (the maxima above are over these)
  // Adds one sample of every joint (angle, speed, torque) to the per-joint and overall figures.
  void addSample(const std::vector<JointState>& js, const std::vector<double>& tau);
};

// Figures on the absolute grid t = k dt covering the stroke, plus every breakpoint; the grid
// dt = 0.5 ms holds the 1 ms output grid, so the re-simulated series never shows more.
StrokeFigures strokeFigures(const std::vector<TailLink>& links, const TailTrajectory& traj, double dt = 5e-4);

// A value exceeds its limit when over it by more than 1e-9 of max(1, |limit|) (less is rounding).
inline bool exceedsLimit(double value, double limit) { return value > limit + 1e-9 * std::max(1.0, std::abs(limit)); }

// Relative excess over the limits (0 when all are kept, exceedsLimit): per kind of limit (upper
// angle, lower angle, speed, torque) the largest over the joints of the excess relative to that
// joint's limit (angles: to its range), summed over the kinds.
double limitViolation(const StrokeFigures& f, const StrokeLimits& lim);

// The limits a stroke uses up: every joint limit whose figure is within `share` of it (torque and
// speed: figure >= (1 - share) limit; angles: within share x range of an end), most used first,
// as "joint 2 torque 19.99 N m (limit 20 N m)". Empty when none is.
std::vector<std::string> bindingLimits(const StrokeFigures& f, const StrokeLimits& lim, double share = 1e-3);
// The joint whose torque is the largest share of its limit (of the largest torque without a torque
// limit), 0-based; -1 without joints.
int mostLoadedJoint(const StrokeFigures& f, const StrokeLimits& lim);

// The objective's value for a signed phi_net [rad] (the optimiser maximises |phi_net| / divisor).
double objectiveValue(StrokeObjective o, double phi_net_rad, const StrokeFigures& f);
const char* objectiveName(StrokeObjective o);
// The objective as reported (console, summary.json, history.csv): signed like phi_net, in degrees
// (per N m, per J): objectiveValue x sign(phi_net) x 180 / pi. Its unit, and the unit as a
// column-name suffix ("deg", "deg_per_Nm", "deg_per_J").
double signedObjectiveDeg(double objective, double phi_net_rad);
const char* objectiveUnit(StrokeObjective o);
const char* objectiveUnitSuffix(StrokeObjective o);
const char* familyName(StrokeFamily f);

}  // namespace tailsim
