// Step-size control shared by the analytic and per-foot models' Dormand-Prince solvers.
#pragma once

#include <algorithm>
#include <boost/numeric/odeint.hpp>
#include <cmath>

namespace tailsim {

// Step-size control of Hairer, Norsett & Wanner's DOPRI5 (Solving ODEs I, Sec. II.4, with Lund
// stabilization, beta = 0.04), in odeint's StepAdjuster shape. odeint's default shrinks a rejected
// step by err^(-1/3) and grows an accepted one by err^(-1/5) only below err = 0.5: where the local
// error rises faster than h^5 (a sliding translation slowing to a stop, whose direction turns ever
// faster), it overshrinks, regrows and is rejected again, one rejection every step. This one
// grows and shrinks by err^-(0.2 - 0.75 beta) with the previous accepted error damping the growth, and never
// grows the step right after a rejection: the same accuracy with far fewer rejected trials
// (docs/scale.md "Analytic hot path"). Where the error grows from step to step (a slide slowing to a stop,
// its direction turning ever faster) that still proposes a step the next error test rejects, one
// rejection every other step; Gustafsson's predictive controller (Hairer & Wanner, Solving ODEs II,
// Sec. IV.8, Eq. 8.21, as RADAU5 uses it) extrapolates the error's trend from the last two
// accepted steps, h_new = h (h / h_acc) (err_acc / err^2)^(1/5) safety, and the smaller of the
// two proposals is taken.
class StabilizedStepAdjuster {
 public:
  using time_type = double;
  using value_type = double;
  explicit StabilizedStepAdjuster(double max_dt = 0.0, long* rejections = nullptr)
      : max_dt_(max_dt), rejections_(rejections) {}

  // Rejected (err > 1): shrink by at most 5.
  double decrease_step(double dt, double err, int /*error_order*/) const {
    rejected_ = true;
    if (rejections_) ++*rejections_;
    return clampMax(dt / std::min(kMaxShrink, std::pow(err, kExpo1) / kSafety));
  }
  // Accepted (err <= 1): grow by at most 10, damped by the previous accepted error.
  double increase_step(double dt, double err, int /*stepper_order*/) const {
    if (!(err >= 0.0)) return clampMax(dt / kMaxShrink);  // NaN error (odeint accepts it): shrink
    // err^kExpo1 / err_old^kBeta as one exp (err = 0: exp(-inf) = 0, the largest growth).
    const double log_err = std::log(err);
    double fac = std::clamp(std::exp(kExpo1 * log_err - kBeta * log_err_old_) / kSafety, 1.0 / kMaxGrow, kMaxShrink);
    const double log_err_floor = std::max(kLogMinErr, log_err);
    if (h_acc_ > 0.0) {  // predictive: (h_acc / h) (err^2 / err_acc)^(1/5) / safety, as a divisor of h
      const double fac_pred = h_acc_ / dt * std::exp(0.2 * (2.0 * log_err_floor - log_err_old_)) / kSafety;
      fac = std::max(fac, std::clamp(fac_pred, 1.0 / kMaxGrow, kMaxShrink));
    }
    h_acc_ = dt;
    log_err_old_ = log_err_floor;
    double h = dt / fac;
    if (rejected_) h = std::min(h, dt);
    rejected_ = false;
    return clampMax(h);
  }
  bool check_step_size_limit(double dt) const { return max_dt_ == 0.0 || std::abs(dt) <= max_dt_; }
  double get_max_dt() const { return max_dt_; }

 private:
  static constexpr double kBeta = 0.04, kExpo1 = 0.2 - kBeta * 0.75, kSafety = 0.9, kMaxShrink = 5.0, kMaxGrow = 10.0;
  double clampMax(double dt) const { return max_dt_ > 0.0 ? std::min(dt, max_dt_) : dt; }
  double max_dt_;
  long* rejections_;  // counts rejected trial steps (may be null)
  static inline const double kLogMinErr = std::log(1e-4);
  mutable double log_err_old_ = kLogMinErr;  // log of the previous accepted error, at least 1e-4
  mutable bool rejected_ = false;
  mutable double h_acc_ = 0.0;  // the last accepted step (0: none yet)
};

// Dense-output Dormand-Prince (odeint) with StabilizedStepAdjuster; construct it with
// StabilizedDenseDopri5<S>::controlled_stepper_type(error_checker(abs_tol, rel_tol),
// StabilizedStepAdjuster(max_dt, &rejections)).
template <class S>
using StabilizedDenseDopri5 = boost::numeric::odeint::dense_output_runge_kutta<boost::numeric::odeint::controlled_runge_kutta<
    boost::numeric::odeint::runge_kutta_dopri5<S>,
    boost::numeric::odeint::default_error_checker<double, typename boost::numeric::odeint::runge_kutta_dopri5<S>::algebra_type,
                                                  typename boost::numeric::odeint::runge_kutta_dopri5<S>::operations_type>,
    StabilizedStepAdjuster, boost::numeric::odeint::initially_resizer,
    boost::numeric::odeint::explicit_error_stepper_fsal_tag>>;

// A StabilizedDenseDopri5<S> for abs_tol, rel_tol, step bound max_dt (0: none), counting rejected
// trial steps into *rejections (may be null).
template <class S>
StabilizedDenseDopri5<S> makeStabilizedDopri5(double abs_tol, double rel_tol, double max_dt, long* rejections) {
  namespace odeint = boost::numeric::odeint;
  using Stepper = odeint::runge_kutta_dopri5<S>;
  return StabilizedDenseDopri5<S>(typename StabilizedDenseDopri5<S>::controlled_stepper_type(
      odeint::default_error_checker<double, typename Stepper::algebra_type, typename Stepper::operations_type>(abs_tol, rel_tol),
      StabilizedStepAdjuster(max_dt, rejections)));
}

}  // namespace tailsim
