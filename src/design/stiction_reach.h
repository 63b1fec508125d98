// How close a tail stroke comes to breaking stiction (the stiction friction law): the yaw moment
// the feet must hold while the body stays still, against the static friction limit. When no
// stroke within the limits turns the body, the optimiser reports the torque and speed a stroke
// of the best shape needs (docs/design-a-tail-stroke.md "Infeasible limits").
#pragma once

#include "design/stroke_family.h"
#include "experiments/experiment_config.h"

namespace tailsim {

struct StictionReach {
  bool applies = false;          // the base uses the stiction law with friction and gravity
  double peak_moment_Nm = 0.0;   // max over the stroke of |M_required| (the stuck body's friction moment)
  double limit_Nm = 0.0;         // the static limit max(mu_s, mu_d) m g L_F at that time
  double ratio = 0.0;            // max over the stroke of |M_required| / M_break (> 1: the body breaks away)
  double t_s = 0.0;              // where the ratio peaks
};

// The analytic model at every sample of the stroke (t = k dt plus every breakpoint, as
// strokeFigures), body and translation held stuck, with searchEffects(base).
StictionReach stictionReach(const ExperimentCase& base, const TailTrajectory& traj, double dt = 5e-4);

}  // namespace tailsim
