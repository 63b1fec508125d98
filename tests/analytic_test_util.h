// Shared helpers of the analytic-model tests.
#pragma once

#include <cmath>

#include "models/analytic/analytic_simulation.h"

namespace tailsim::testing {

inline double deg(double d) { return d * M_PI / 180.0; }

// Table 1 quadruped with the paper's n-link tail (Table 2).
inline RobotParams paperRobot(int n, double d_Q2B = 0.125) {
  RobotParams r;
  r.quadruped.d_Q2B_m = d_Q2B;
  for (int i = 0; i < n; ++i) r.tail.push_back(paperTailLink(n));
  return r;
}

// Every joint on the same split-cycle move.
inline TailTrajectory sameMove(int n, double theta0_deg, double dtheta_deg, double dT, double w_ss) {
  TailTrajectory t;
  for (int i = 0; i < n; ++i) t.joints.emplace_back(SplitCycleParams{deg(theta0_deg), deg(dtheta_deg), dT, w_ss, 0.0});
  return t;
}

// Fig. 7 case: n = 1, dT = 0.25 s, dtheta = -90 deg, theta0 = 0, w_ss = 0.25, d_Q2B = 0.125 m.
inline RunResult runFig7(AnalyticSettings s = {}, Effects e = {}, OutputSettings o = {}) {
  return simulateAnalytic(paperRobot(1), sameMove(1, 0, -90, 0.25, 0.25), s, e, o);
}

}  // namespace tailsim::testing
