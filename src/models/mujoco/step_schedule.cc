#include "models/mujoco/step_schedule.h"

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

StepSchedule::StepSchedule(double h, int factor, double tail_end_s, double duration_s, double sample_dt_s,
                           double solref_s, double servo_wn_radps, bool allowed)
    : h_(h), H_(h * factor), tail_end_(tail_end_s), end_(duration_s) {
  const double per_two = sample_dt_s / (2.0 * H_);
  allowed_ = allowed && factor > 1 && per_two >= 1.0 - 1e-9 &&
             std::abs(per_two - std::round(per_two)) < 1e-9 * per_two && solref_s >= 2.0 * H_ * (1.0 - 1e-9) &&
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
