#include "models/mujoco/step_schedule.h"

#include <algorithm>
#include <cmath>

#include "common/work_limits.h"

namespace tailsim {

bool speedsAtRest(const mjModel* m, const mjData* d) {
  for (int j = 0; j < m->njnt; ++j) {
    const mjtNum* v = d->qvel + m->jnt_dofadr[j];
    auto below = [](const mjtNum* x, int n, double lim) {
      double s = 0.0;
      for (int i = 0; i < n; ++i) s += x[i] * x[i];
      return s < lim * lim;
    };
    switch (m->jnt_type[j]) {
      case mjJNT_FREE:
        if (!below(v, 3, limits::kRestSpeedMps) || !below(v + 3, 3, limits::kRestAngularRadps)) return false;
        break;
      case mjJNT_BALL:
        if (!below(v, 3, limits::kRestAngularRadps)) return false;
        break;
      case mjJNT_SLIDE:
        if (!below(v, 1, limits::kRestSpeedMps)) return false;
        break;
      default:
        if (!below(v, 1, limits::kRestJointRadps)) return false;
    }
  }
  return true;
}

double shortestSolrefS(const mjModel* m) {
  if (m->opt.enableflags & mjENBL_OVERRIDE) return std::max(0.0, static_cast<double>(m->opt.o_solref[0]));
  double tc = HUGE_VAL;
  auto take = [&tc](const mjtNum* solref) { tc = std::min(tc, std::max(0.0, static_cast<double>(solref[0]))); };
  for (int g = 0; g < m->ngeom; ++g)
    if (m->geom_contype[g] || m->geom_conaffinity[g]) take(m->geom_solref + mjNREF * g);
  for (int p = 0; p < m->npair; ++p) take(m->pair_solref + mjNREF * p);
  for (int e = 0; e < m->neq; ++e)
    if (m->eq_active[e]) take(m->eq_solref + mjNREF * e);
  for (int j = 0; j < m->njnt; ++j)
    if (m->jnt_limited[j]) take(m->jnt_solref + mjNREF * j);
  for (int v = 0; v < m->nv; ++v)
    if (m->dof_frictionloss[v] > 0.0) take(m->dof_solref + mjNREF * v);
  return tc;
}

StepSchedule::StepSchedule(double h, int factor, double tail_end_s, double duration_s, double sample_dt_s,
                           double solref_s, double servo_wn_radps, bool allowed)
    : h_(h), H_(h * factor), tail_end_(tail_end_s), end_(duration_s) {
  const double per_two = sample_dt_s / (2.0 * H_);
  const bool rows_on_grid =
      sample_dt_s <= 0.0 || (per_two >= 1.0 - 1e-9 && std::abs(per_two - std::round(per_two)) < 1e-9 * per_two);
  allowed_ = allowed && factor > 1 && rows_on_grid && solref_s >= 2.0 * H_ * (1.0 - 1e-9) &&
             servo_wn_radps * H_ <= 1.0 + 1e-9;
}

double StepSchedule::next(double t, bool speeds_at_rest) {
  if (!(t >= tail_end_ - 1e-6 * h_) || !speeds_at_rest) {
    rest_since_ = -1.0;
    return h_;
  }
  if (rest_since_ < 0.0) rest_since_ = t;
  if (!rested(t) || !allowed_) return h_;
  const bool on_grid = std::abs(t - std::round(t / H_) * H_) < 1e-6 * h_;
  return on_grid && t + H_ <= end_ + 1e-6 * h_ ? H_ : h_;
}

bool StepSchedule::rested(double t) const {
  return rest_since_ >= 0.0 && t - rest_since_ >= limits::kRestHoldS - 1e-6 * h_;
}

}  // namespace tailsim
