#include "design/stiction_reach.h"

#include <algorithm>
#include <cmath>

#include "models/analytic/analytic_model.h"
#include "design/stroke_optimizer.h"

namespace tailsim {

StictionReach stictionReach(const ExperimentCase& base, const TailTrajectory& traj, double dt) {
  StictionReach r;
  const Effects e = searchEffects(base);
  const AnalyticModel m(base.robot, traj, base.analytic, e);
  if (!m.stiction()) return r;
  r.applies = true;
  AnalyticWorkspace w;
  Modes stuck;
  stuck.stuck[kRot] = stuck.stuck[kTrans] = true;
  const State y{};
  const double t_a = traj.startTime(), t_b = traj.endTime();
  std::vector<double> ts;
  for (long k = static_cast<long>(std::floor(t_a / dt)); k * dt <= t_b + dt; ++k) ts.push_back(k * dt);
  for (double b : traj.breakpoints()) ts.push_back(b);
  for (double t : ts) {
    const Eval ev = evaluate(m, w, t, y, stuck);
    if (!(ev.M_break > 0.0)) continue;
    const double q = std::abs(ev.M_required) / ev.M_break;
    if (q > r.ratio) {
      r.ratio = q;
      r.peak_moment_Nm = std::abs(ev.M_required);
      r.limit_Nm = ev.M_break;
      r.t_s = t;
    }
  }
  return r;
}

}  // namespace tailsim
