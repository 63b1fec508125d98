#include "models/mujoco/run_uncertainty.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace tailsim {

MujocoSettings checkRunSettings(const MujocoSettings& run) {
  MujocoSettings c = run;
  c.timestep_s *= 2.0;
  if (c.kp == 0.0) c.servo_wn_dt *= 2.0;  // the same servo w_n
  c.max_steps = std::max(1L, run.max_steps / 2);
  return c;
}

void applyCheckRun(RunSummary& run, const RunSummary& check, double check_timestep_s, double warn_share,
                   const std::string& remedy) {
  run.extra["uncertainty_solver_steps"] = static_cast<double>(check.solver_steps);
  const double phi = run.phi_net_deg;
  const double scale = std::max(std::abs(phi), kUncertaintyFloorDeg);
  std::ostringstream os;
  os.precision(3);
  if (!check.ok) {
    run.extra["phi_net_uncertainty_deg"] = std::numeric_limits<double>::quiet_NaN();
    os << kUncertainWarning << ": the check run at twice the timestep (" << check_timestep_s << " s) failed ("
       << check.error << "), so this result is not converged in the step";
    run.warnings.push_back(os.str());
    return;
  }
  run.extra["phi_net_check_deg"] = check.phi_net_deg;
  const double u = 2.0 * std::abs(phi - check.phi_net_deg) + kUncertaintyFloorShare * scale;
  run.extra["phi_net_uncertainty_deg"] = u;
  if (u > warn_share * scale) {
    os << kUncertainWarning << ": +-" << u << " deg (" << 100.0 * u / scale << " % of max(|phi_net|, 0.5 deg); limit "
       << 100.0 * warn_share << " %, mujoco.uncertainty_warn_share); at twice the timestep phi_net is "
       << check.phi_net_deg << " deg: " << remedy;
    run.warnings.push_back(os.str());
  }
}

}  // namespace tailsim
