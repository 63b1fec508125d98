// Solver and modelling settings of the analytic ("Simulink") model.
#pragma once

#include <string>

#include "common/work_limits.h"
#include "settings/fields.h"

namespace tailsim {

enum class Coupling {
  kPaper,  // Eqs. (5)-(13) as printed: tail loads from an inertial base, I_zz phi_ddot = M
  kExact,  // planar multibody with the base moving (paper-notes point 3)
};

enum class AnalyticSolver {
  kAdaptive,  // dense-output Dormand-Prince with event location
  kFixed,     // fixed-step RK4
};

// Settings of the analytic ("Simulink") model.
struct AnalyticSettings {
  AnalyticSolver solver = AnalyticSolver::kAdaptive;
  double rel_tol = 1e-8;            // adaptive: relative error tolerance
  double abs_tol = 1e-10;           // adaptive: absolute error tolerance
  double fixed_dt_s = 1e-4;         // fixed: step  [s]
  double event_tol_s = 1e-12;       // stick/slip event location tolerance in time  [s]
  double max_step_s = 0.0;          // adaptive: step bound while the tail moves; 0 = 1/8 of the moving joints' shortest phase  [s]
  // Translation: sliding speed below which the body is declared stopped  [m/s]. Near zero speed
  // the 2-D velocity turns ever faster (paper-notes point 4); stopping at v_stop instead of 0
  // moves the body by at most v_stop^2 / (2 a) (~5e-9 m here) and saves ~10^4 tiny steps.
  double v_stop_mps = 1e-4;
  Coupling coupling = Coupling::kPaper;
  // Step budget: a run needing more accepted steps fails with a clear error (not a loader key).
  long max_steps = static_cast<long>(limits::kMaxAnalyticSteps);
};

// The YAML/JSON keys of AnalyticSettings (settings/fields.h), declared once.
template <class V, class S>
settings::For<S, AnalyticSettings> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  static const settings::EnumNames<AnalyticSolver> kSolvers = {{AnalyticSolver::kAdaptive, "adaptive"},
                                                               {AnalyticSolver::kFixed, "fixed"}};
  static const settings::EnumNames<Coupling> kCouplings = {{Coupling::kPaper, "paper"}, {Coupling::kExact, "exact"}};
  v.choice(Field{"solver", "adaptive: dense-output Dormand-Prince with event location; fixed: RK4 with step fixed_dt_s"},
           s.solver, kSolvers);
  v.number(Field{"rel_tol", "adaptive: relative error tolerance"}, s.rel_tol, Limits::positive());
  v.number(Field{"abs_tol", "adaptive: absolute error tolerance"}, s.abs_tol, Limits::positive());
  v.number(Field{"fixed_dt_s", "fixed: step [s]"}, s.fixed_dt_s, Limits::positive());
  v.number(Field{"event_tol_s", "stick/slip event location tolerance in time [s]"}, s.event_tol_s, Limits::positive());
  v.number(Field{"max_step_s", "adaptive: step bound while the tail moves; 0 = 1/8 of the shortest phase of the joints moving [s]"}, s.max_step_s,
           Limits::nonNegative());
  v.number(Field{"v_stop_mps", "sliding speed below which the body is declared stopped [m/s]"}, s.v_stop_mps,
           Limits::positive());
  v.choice(Field{"coupling", "paper: Eqs. (5)-(13) as printed; exact: planar multibody with the base moving"},
           s.coupling, kCouplings);
  v.internal(Field{"max_steps", "step budget (common/work_limits.h); not a YAML key"}, s.max_steps);
}

}  // namespace tailsim
