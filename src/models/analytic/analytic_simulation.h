// The paper's analytic ("Simulink") model in time: planar quadruped dynamics (Eq. 9) driven by
// the tail (Eq. 13) against foot friction (Eqs. 14-16 stiction, or the ADAMS law), integrated
// with event-located stick/slip switching.
#pragma once

#include <vector>

#include "models/analytic/analytic_settings.h"
#include "models/planar/foot_loads.h"
#include "models/planar/stick_slip.h"  // breakawayCoefficient
#include "models/planar/system_loads.h"
#include "results/output_settings.h"
#include "results/time_series.h"
#include "robot/scene_effects.h"

namespace tailsim {

// Integrates from t = 0 (tail at rest at theta_0, body at rest) to the output duration.
// Never throws for physics failures: summary.ok = false with the reason (e.g. tipping).
// Throws std::invalid_argument for settings it cannot run with (e.g. a negative tolerance).
// With output.time_series thin the series holds only the rows thinRowIndices keeps, and only those
// are evaluated (RunResult::series_thinned); otherwise every sample.
RunResult simulateAnalytic(const RobotParams& robot, const TailTrajectory& trajectory,
                           const AnalyticSettings& settings, const Effects& effects,
                           const OutputSettings& output);

// kind: pose — loads, mass properties and L_F at one tail state; one row, no integration.
RunResult evaluatePose(const RobotParams& robot, const std::vector<JointState>& joints, const Effects& effects);

}  // namespace tailsim
