// The rest step schedule of a MuJoCo run (docs/mujoco-model.md "Step schedule"), shared by the
// rigid-box run (mujoco_simulation.cc) and the articulated robot's (attach_tail.cc): once the
// tail's motion has ended and every speed of the model has stayed below the rest thresholds
// (common/work_limits.h kRest*) for kRestHoldS, the run steps at rest_step_factor times its step.
#pragma once

#include <mujoco/mujoco.h>

namespace tailsim {

// Whether every speed of the state is below the rest thresholds (common/work_limits.h kRest*):
// free, ball and slide joints by their linear and angular parts, every hinge by kRestJointRadps.
bool speedsAtRest(const mjModel* m, const mjData* d);

// The shortest constraint time constant (solref[0]) of the model [s]: its colliding geoms, contact
// pairs, active equalities, limited joints and dofs with friction loss (MuJoCo's default 0.02 s),
// or opt.o_solref when the override flag is on; 0 when any of them is direct (solref[0] <= 0).
double shortestSolrefS(const mjModel* m);

// The step schedule: h until the tail's motion has ended and every speed has stayed at rest for
// kRestHoldS, then H = rest_step_factor h, back to h the step anything moves again. A coarse step
// starts only on a multiple of H and ends within the run, and only where an even number of H makes
// the output spacing, so that every row stays on its grid.
class StepSchedule {
 public:
  // `allowed`: the run may coarsen (no controller steering it, not RK4). The coarse step must also
  // leave the contact as it is (solref's time constant at least 2 H, else MuJoCo raises it: a
  // softer floor at rest) and keep the servo's explicit spring well inside its stable range
  // (w_n H <= 1; its damper is implicit), and an even number of it must make an output row, so
  // that each row's averaging window [t_k - dt/2, t_k + dt/2) stays made of whole steps.
  // sample_dt_s <= 0: no rows inside the run, no grid to keep.
  StepSchedule(double h, int factor, double tail_end_s, double duration_s, double sample_dt_s, double solref_s,
               double servo_wn_radps, bool allowed);
  // After the step that ended at t: whether the state rests, and the length of the next step.
  double next(double t, bool speeds_at_rest);
  // The body has rested for kRestHoldS after the tail's motion.
  bool rested(double t) const;
  // Whether the run may step coarser at all (the guards above).
  bool allowed() const { return allowed_; }

 private:
  double h_, H_, tail_end_, end_;
  bool allowed_ = false;
  double rest_since_ = -1.0;
};

}  // namespace tailsim
