// Tipping over, checked along the whole tail motion instead of at the times a solver happens to
// evaluate the loads (docs/paper-notes.md point 5).
#pragma once

#include <optional>
#include <string>

#include "models/planar/tail_dynamics.h"

namespace tailsim {

// The first time the system COM leaves the feet's support rectangle (Appendix A3; footLoads'
// test, the same slack for a COM on an edge).
struct SupportLoss {
  double t_s = 0;            // [s]
  Vec2 p_CC = Vec2::Zero();  // system COM relative to the foot centroid there, in Q  [m]
};

// The system COM relative to the quadruped COM depends on the joint angles alone, and they follow
// the prescribed trajectory, so whether the robot tips over is a property of the trajectory,
// whatever the body does. Searches [0, t_end] with a Lipschitz bound instead of samples: on an
// interval, |d p_QC/dt| <= (1/m) sum_i m_i |v_L,i| is bounded by the peak joint speeds of the
// joints moving there, so the margin's lowest value there is at least
// (g(a) + g(b)) / 2 - L (b - a) / 2; intervals are halved, earliest first, until that bound is
// >= 0 (or, from the curvature bound |d^2 p_QC/dt^2| <= M, min(g(a), g(b)) - M (b - a)^2 / 8 >= 0)
// or the exit is located to 1e-12 s. Margins are measured from kSupportSlack (l_F + w_F) beyond the
// edges, and a possible dip no deeper than that again counts as standing: within footLoads' own
// slack, so footLoads never throws in a run this check passed. Returns the first time outside,
// or nothing.
std::optional<SupportLoss> firstSupportLoss(const RobotParams& robot, const TailTrajectory& traj, double t_end);

// The message footLoads' TippingError gives, with the time (`what` as tippingMessage's).
std::string supportLossMessage(const QuadrupedParams& q, const SupportLoss& loss, const char* what = "system COM");

// Throws TippingError (supportLossMessage) when firstSupportLoss finds an exit: what a model runs
// before integrating.
void requireSupport(const RobotParams& robot, const TailTrajectory& traj, double t_end);

}  // namespace tailsim
