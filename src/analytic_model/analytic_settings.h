// Solver and modelling settings of the analytic ("Simulink") model.
#pragma once

#include <string>

#include "results/work_limits.h"

namespace tailsim {

enum class Coupling {
  kPaper,  // Eqs. (5)-(13) as printed: tail loads from an inertial base, I_zz phi_ddot = M
  kExact,  // planar multibody with the base moving (paper-notes point 3)
};

// Settings of the analytic ("Simulink") model.
struct AnalyticSettings {
  std::string solver = "adaptive";  // "adaptive" (dense-output Dormand-Prince) or "fixed" (RK4)
  double rel_tol = 1e-8;            // adaptive: relative error tolerance
  double abs_tol = 1e-10;           // adaptive: absolute error tolerance
  double fixed_dt_s = 1e-4;         // fixed: step  [s]
  double event_tol_s = 1e-12;       // stick/slip event location tolerance in time  [s]
  double max_step_s = 0.0;          // adaptive: step bound while the tail moves; 0 = dT/50  [s]
  // Translation: sliding speed below which the body is declared stopped  [m/s]. Near zero speed
  // the 2-D velocity turns ever faster (paper-notes point 4); stopping at v_stop instead of 0
  // moves the body by at most v_stop^2 / (2 a) (~5e-9 m here) and saves ~10^4 tiny steps.
  double v_stop_mps = 1e-4;
  Coupling coupling = Coupling::kPaper;
  // Step budget: a run needing more accepted steps fails with a clear error (not a loader key).
  long max_steps = static_cast<long>(limits::kMaxAnalyticSteps);
};

}  // namespace tailsim
