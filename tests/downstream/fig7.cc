// Downstream use of tailsim::analytic: the paper's Fig. 7 case, built from the parameter structs.
#include <tailsim/models/analytic/analytic_simulation.h>

#include <cmath>
#include <cstdio>

int main() {
  tailsim::RobotParams robot;  // Table 1 quadruped
  robot.quadruped.d_Q2B_m = 0.125;
  robot.tail.push_back(tailsim::paperTailLink(1));  // Table 2, n = 1
  tailsim::TailTrajectory trajectory;
  trajectory.joints.emplace_back(tailsim::SplitCycleParams{0.0, -M_PI / 2.0, 0.25, 0.25, 0.0});
  const tailsim::RunResult r = tailsim::simulateAnalytic(robot, trajectory, {}, {}, {});
  if (!r.summary.ok) {
    std::fprintf(stderr, "failed: %s\n", r.summary.error.c_str());
    return 1;
  }
  std::printf("phi_net_deg %.6f rows %zu\n", r.summary.phi_net_deg, r.series.numRows());
  return 0;
}
