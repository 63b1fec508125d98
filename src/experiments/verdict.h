// One case's verdict across its models (docs/accuracy.md "Verdict across the models"): whether
// the analytic, per-foot and MuJoCo results agree within their uncertainties, whether they agree
// on falling over, and, where they do not, which step of the gap ladder (docs/per-foot-model.md
// "The gap ladder") the difference belongs to.
#pragma once

#include <string>
#include <vector>

#include "results/time_series.h"

namespace tailsim {

// Uncertainty of a planar (analytic, per-foot) result: their solvers' tolerances are orders below
// this, so it is the same floor the MuJoCo estimate carries: this share of max(|phi_net|, 0.5 deg).
inline constexpr double kPlanarUncertaintyShare = 0.005;
inline constexpr double kUncertaintyFloorDeg = 0.5;

// Text in a failed run's error that says the robot fell (the planar models' support check: "the
// robot tips over"; MuJoCo's standing monitor: "robot fell over").
inline constexpr char kPlanarTipText[] = "the robot tips over";
inline constexpr char kMujocoFallText[] = "robot fell over";

// A result's uncertainty [deg]: MuJoCo's phi_net_uncertainty_deg when the run estimated it, else
// the planar floor above. NaN for a failed run.
double phiUncertaintyDeg(const RunSummary& run);

// The verdict of one case's runs (any order; models other than analytic, perfoot and mujoco are
// left out). Empty when fewer than two of them ran. Begins with one word: "agree", "differ",
// "falls" (the models disagree on whether the robot falls), "fall" (every model sees it fall),
// "uncertain" (MuJoCo's result carries kUncertainWarning; compared all the same) or "no-verdict".
std::string caseVerdict(const std::vector<RunSummary>& runs);

}  // namespace tailsim
