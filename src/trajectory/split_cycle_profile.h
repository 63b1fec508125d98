// Split-cycle joint trajectories (paper Sec. 3.3, Eqs. 20-23) and the equal-peak-speed rule
// of Sec. 4.7 (Eq. 25).
#pragma once

#include <vector>

namespace tailsim {

// Parameters of one joint's split-cycle move. Angles in radians.
struct SplitCycleParams {
  double theta0_rad = 0.0;  // theta_0: angle at t0  [rad]
  double dtheta_rad = 0.0;  // Delta theta: displacement  [rad]
  double dT_s = 0.25;       // Delta T = t2 - t0  [s]
  double w_ss = 0.25;       // split-cycle parameter, Delta_a = w_ss * Delta T, in (0, 1)
  double t0_s = 0.0;        // start time t0  [s]
};

struct JointState {
  double theta = 0.0;       // [rad]
  double theta_dot = 0.0;   // [rad/s]
  double theta_ddot = 0.0;  // [rad/s^2]
};

// Eq. (20): half-sine acceleration A sin(pi (t-t0)/Delta_a) on [t0, t1], then
// -B sin(pi (t-t1)/Delta_d) on (t1, t2]; at rest before t0 and after t2.
class SplitCycleProfile {
 public:
  explicit SplitCycleProfile(const SplitCycleParams& p);  // throws std::invalid_argument

  JointState at(double t) const;
  const SplitCycleParams& params() const { return p_; }
  double accelAmplitude() const { return A_; }  // A of Eq. (23)  [rad/s^2]
  double decelAmplitude() const { return B_; }  // B of Eq. (23)  [rad/s^2]
  double t1() const { return p_.t0_s + da_; }
  double t2() const { return p_.t0_s + p_.dT_s; }
  double peakSpeed() const { return 2.0 * p_.dtheta_rad / p_.dT_s; }  // signed, at t1

 private:
  SplitCycleParams p_;
  double da_, dd_, A_, B_;
};

// All joints of a tail: one profile per joint.
struct TailTrajectory {
  std::vector<SplitCycleProfile> joints;
  void evaluate(double t, std::vector<JointState>& out) const;
  double startTime() const;  // earliest t0
  double endTime() const;    // latest t2: the tail is at rest afterwards
  // Times where some joint's acceleration changes formula (t0, t1, t2 of every joint), sorted.
  std::vector<double> breakpoints() const;
};

// Eq. (25) with the misprint fixes of paper-notes: dtheta = -360 deg / (n+1),
// dT = 2 |dtheta| / thetadot_max, theta_0 = -0.5 dtheta.
SplitCycleParams equalPeakSpeedParams(int n_links, double thetadot_max_radps, double w_ss, double t0_s = 0.0);

}  // namespace tailsim
