// A MuJoCo run's own error estimate (docs/mujoco-model.md "Uncertainty of a run"): the same case
// run again at twice the timestep, the servos' natural frequency kept. One rule for both MuJoCo
// models: the rigid box (simulateMujoco) and a user's robot with the tail attached (attach_tail.h).
#pragma once

#include <string>

#include "models/mujoco/mujoco_settings.h"
#include "results/time_series.h"

namespace tailsim {

// The floor of an uncertainty: this share of max(|phi_net|, kUncertaintyFloorDeg), what a run's
// error is not resolved below (contact noise, the servo). The verdict across the models uses the
// same floor for results that carry no estimate of their own (experiments/verdict.h).
inline constexpr double kUncertaintyFloorShare = 0.005;
inline constexpr double kUncertaintyFloorDeg = 0.5;

// The check run's settings: timestep_s doubled, the servo's w_n kept (servo_wn_dt doubled when the
// gains come from it, kp = 0) and half the step budget; everything else as `run`.
MujocoSettings checkRunSettings(const MujocoSettings& run);

// The estimate from the check run's summary `check` (run at checkRunSettings): in run.extra
//   phi_net_uncertainty_deg = 2 |phi_h - phi_2h| + kUncertaintyFloorShare max(|phi_h|, kUncertaintyFloorDeg)
//     (NaN when the check run failed),
//   phi_net_check_deg = phi_2h (absent when the check run failed),
//   uncertainty_solver_steps = the check run's mj_step calls;
// and a warning beginning kUncertainWarning when the check run failed or U exceeds warn_share of
// max(|phi_h|, kUncertaintyFloorDeg). `check_timestep_s` is quoted in the warning, `remedy` ends it
// (what the user can change, e.g. "lower mujoco.timestep_s or see `tailsim trust`"). The factor 2
// and the floor were measured on the random-robot corpus (tests/bench_trust.cc).
void applyCheckRun(RunSummary& run, const RunSummary& check, double check_timestep_s, double warn_share,
                   const std::string& remedy);

}  // namespace tailsim
