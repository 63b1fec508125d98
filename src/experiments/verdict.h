// One case's verdict across its models (docs/accuracy.md "Verdict across the models"): whether
// the analytic, per-foot and MuJoCo results agree within their uncertainties, whether they agree
// on falling over, and, where they do not, which step of the gap ladder (docs/per-foot-model.md
// "The gap ladder") the difference belongs to.
#pragma once

#include <string>
#include <vector>

#include "models/mujoco/run_uncertainty.h"
#include "results/time_series.h"

namespace tailsim {


// Text in a failed run's error that says the robot fell (the planar models' support check: "the
// robot tips over"; MuJoCo's standing monitor: "robot fell over").
inline constexpr char kPlanarTipText[] = "the robot tips over";
inline constexpr char kMujocoFallText[] = "robot fell over";

// The uncertainty a run estimated itself [deg]: a MuJoCo run's finite phi_net_uncertainty_deg
// (run_uncertainty.h); NaN when it has none (the planar models estimate none; a MuJoCo run with
// mujoco.uncertainty false, or whose check run failed, has none) or the run failed.
double ownUncertaintyDeg(const RunSummary& run);

// The tolerance the verdict gives a result [deg]: its own estimate, else the floor
// kUncertaintyFloorShare of max(|phi_net|, kUncertaintyFloorDeg) (run_uncertainty.h). The planar
// models' solvers are far below the floor (analytic 1.4e-6 deg at its default rel_tol,
// docs/accuracy.md), so for them the floor is a bound; for a MuJoCo run without an estimate it is
// only the least it could be, and the verdict says so. NaN for a failed run.
double phiUncertaintyDeg(const RunSummary& run);

// The verdict of one case's runs (any order; models other than analytic, perfoot and mujoco are
// left out). Empty when fewer than two of them ran. Begins with one word: "agree", "differ",
// "falls" (the models disagree on whether the robot falls), "fall" (every model sees it fall),
// "uncertain" (MuJoCo's result carries kUncertainWarning; compared all the same) or "no-verdict".
// The results it quotes carry "+- U" only where the run estimated U itself (ownUncertaintyDeg);
// "agree" and "differ" end with the tolerance each model was compared with.
std::string caseVerdict(const std::vector<RunSummary>& runs);

}  // namespace tailsim
