// Split-cycle joint trajectories (paper Sec. 3.3, Eqs. 20-23) and the equal-peak-speed rule
// of Sec. 4.7 (Eq. 25). A joint profile may also be a clamped cubic spline (the optimiser's
// smooth stroke family): JointProfile is either; SplitCycleProfile is its historical name.
#pragma once

#include <vector>

#include "settings/fields.h"

namespace tailsim {

// Parameters of one joint's split-cycle move. Angles in radians.
struct SplitCycleParams {
  double theta0_rad = 0.0;  // theta_0: angle at t0  [rad]
  double dtheta_rad = 0.0;  // Delta theta: displacement  [rad]
  double dT_s = 0.25;       // Delta T = t2 - t0  [s]
  double w_ss = 0.25;       // split-cycle parameter, Delta_a = w_ss * Delta T, in (0, 1)
  double t0_s = 0.0;        // start time t0  [s]
};

// A joint's resolved move as the resolved case (result.json "resolved") keeps it, in SI units (the
// YAML trajectory section, with its degrees, per-joint lists and rule: eq25, is read by the loader).
template <class V, class S>
settings::For<S, SplitCycleParams> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  v.number(Field{"theta0_rad", "theta_0: angle at t0 [rad]"}, s.theta0_rad, Limits::any());
  v.number(Field{"dtheta_rad", "Delta theta: displacement [rad]"}, s.dtheta_rad, Limits::any());
  v.number(Field{"dT_s", "Delta T = t2 - t0 [s]"}, s.dT_s, Limits::positive());
  v.number(Field{"w_ss", "split-cycle parameter, Delta_a = w_ss Delta T"}, s.w_ss, Limits::open(0, 1));
  v.number(Field{"t0_s", "start time [s]"}, s.t0_s, Limits::nonNegative());
}

struct JointState {
  double theta = 0.0;       // [rad]
  double theta_dot = 0.0;   // [rad/s]
  double theta_ddot = 0.0;  // [rad/s^2]
};

// One joint's smooth stroke: a cubic spline through K + 2 equally spaced knots on [t0, t0 + dT]
// (the first and last are the start and end angles), with zero speed at both ends (clamped);
// at rest before t0 and after t0 + dT. Angles in radians.
struct SplineParams {
  std::vector<double> knots_rad;  // theta at t0 + k dT / (K + 1), k = 0..K+1 (at least 2)
  double dT_s = 0.25;             // stroke duration  [s]
  double t0_s = 0.0;              // start time  [s]
};

// A spline joint as the resolved case keeps it (SI units; the YAML `family: spline` trajectory, with
// its knots in degrees and per-joint lists, is read by the loader).
template <class V, class S>
settings::For<S, SplineParams> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  v.internal(Field{"knots_rad", "theta at t0 + k dT / (K + 1), k = 0..K+1 [rad]"}, s.knots_rad);
  v.number(Field{"dT_s", "stroke duration [s]"}, s.dT_s, Limits::positive());
  v.number(Field{"t0_s", "start time [s]"}, s.t0_s, Limits::nonNegative());
}

// Eq. (20): half-sine acceleration A sin(pi (t-t0)/Delta_a) on [t0, t1], then
// -B sin(pi (t-t1)/Delta_d) on (t1, t2]; at rest before t0 and after t2.
// Or (a spline profile) the clamped cubic spline of SplineParams.
class JointProfile {
 public:
  explicit JointProfile(const SplitCycleParams& p);  // split-cycle; throws std::invalid_argument
  explicit JointProfile(const SplineParams& s);      // spline; throws std::invalid_argument

  bool isSpline() const { return !knots_.empty(); }
  JointState at(double t) const;
  // Split-cycle: its parameters. Spline: the envelope (theta0 = first knot, dtheta = last - first,
  // dT, t0, and w_ss = knot spacing / dT, so w_ss dT is the shortest smooth piece; 0.5 for 2 knots).
  const SplitCycleParams& params() const { return p_; }
  const SplineParams& spline() const { return s_; }  // spline profiles only (empty knots otherwise)
  double accelAmplitude() const { return A_; }  // A of Eq. (23)  [rad/s^2] (0 for a spline)
  double decelAmplitude() const { return B_; }  // B of Eq. (23)  [rad/s^2] (0 for a spline)
  double t1() const { return p_.t0_s + da_; }   // split-cycle: end of acceleration; spline: peak |speed|
  double t2() const { return p_.t0_s + p_.dT_s; }
  // At its final rest at t: at(t) is {theta0 + dtheta, 0, 0} (the same test at() makes).
  bool finished(double t) const { return t - p_.t0_s >= p_.dT_s; }
  double peakSpeed() const { return isSpline() ? peak_ : 2.0 * p_.dtheta_rad / p_.dT_s; }  // signed, at t1
  // Largest |acceleration| over the move  [rad/s^2]: split-cycle max(|A|, |B|); spline the largest
  // |second derivative| at a knot (linear on each piece), end knots included (at() gives 0 there:
  // at rest outside [t0, t2]).
  double peakAcceleration() const;
  // Times where the acceleration changes formula: t0, t1, t2 (split-cycle) or every knot (spline).
  void breakpoints(std::vector<double>& out) const;

 private:
  JointState splineAt(double t) const;
  SplitCycleParams p_;
  double da_ = 0, dd_ = 0, A_ = 0, B_ = 0;
  double ka_ = 0, kd_ = 0, A_over_ka_ = 0, B_over_kd_ = 0, w1_ = 0, th1_ = 0;  // split-cycle: at()'s constants
  SplineParams s_;
  std::vector<double> knots_, m_;  // spline: knot values and second derivatives
  double h_ = 0, peak_ = 0;
};
using SplitCycleProfile = JointProfile;

// All joints of a tail: one profile per joint (split-cycle or spline).
struct TailTrajectory {
  std::vector<SplitCycleProfile> joints;
  void evaluate(double t, std::vector<JointState>& out) const;
  double startTime() const;  // earliest t0
  double endTime() const;    // latest t2: the tail is at rest afterwards
  // Every joint at its final rest at t (JointProfile::finished): evaluate(t) is then the same for
  // every such t.
  bool finished(double t) const;
  // Times where some joint's acceleration changes formula (JointProfile::breakpoints), sorted.
  std::vector<double> breakpoints() const;
  // The shortest acceleration or deceleration phase (split-cycle) or knot spacing (spline) of the
  // joints moving at time t  [s]; +inf when every joint is at rest there. Between two breakpoints
  // each joint stays in one phase, so this is the time scale of the loads over that segment.
  double shortestActivePhase(double t) const;
  // The shortest acceleration or deceleration phase of any joint over the whole motion  [s]
  // (+inf without joints): min(w_ss, 1 - w_ss) dT; a spline's w_ss dT is its knot spacing.
  double shortestPhase() const;
};

// Eq. (25) with the misprint fixes of paper-notes: dtheta = -360 deg / (n+1),
// dT = 2 |dtheta| / thetadot_max, theta_0 = -0.5 dtheta.
SplitCycleParams equalPeakSpeedParams(int n_links, double thetadot_max_radps, double w_ss, double t0_s = 0.0);

}  // namespace tailsim
