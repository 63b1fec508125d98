#include "controllers/tail_controller.h"

#include <cmath>
#include <stdexcept>

namespace tailsim {

TailController::TailController(const mjModel* m, TailTrajectory trajectory, std::vector<int> tail_qposadr,
                               std::vector<int> tail_dofadr, std::vector<int> actuators,
                               TailControllerOptions options)
    : traj_(std::move(trajectory)),
      qposadr_(std::move(tail_qposadr)),
      dofadr_(std::move(tail_dofadr)),
      act_(std::move(actuators)),
      opt_(options) {
  const size_t n = qposadr_.size();
  if (dofadr_.size() != n || act_.size() != n || traj_.joints.size() != n)
    throw std::invalid_argument("TailController: trajectory has " + std::to_string(traj_.joints.size()) +
                                " joints, model tail has " + std::to_string(n));
  for (size_t i = 0; i < n; ++i) {
    // Affine PD servo: force = gain * ctrl + b1 * q + b2 * qdot with gain = kp, b1 = -kp, b2 = -kv.
    const double kp = m->actuator_gainprm[act_[i] * mjNGAIN];
    const double kv = -m->actuator_biasprm[act_[i] * mjNBIAS + 2];
    if (!(kp > 0.0)) throw std::invalid_argument("TailController: actuator kp must be > 0");
    kv_over_kp_.push_back(kv / kp);
  }
  ref_.resize(n);
  err_.assign(n, 0.0);
  qacc_des_.assign(m->nv, 0.0);
  tau_.assign(m->nv, 0.0);
  resetStats();
}

void TailController::setTrajectory(TailTrajectory trajectory) {
  if (trajectory.joints.size() != qposadr_.size())
    throw std::invalid_argument("TailController: trajectory has " + std::to_string(trajectory.joints.size()) +
                                " joints, model tail has " + std::to_string(qposadr_.size()));
  traj_ = std::move(trajectory);
}

void TailController::apply(const mjModel* m, mjData* d, double t_ref, bool record, double weight) {
  traj_.evaluate(t_ref, ref_);
  const size_t n = ref_.size();
  for (size_t i = 0; i < n; ++i) {
    d->ctrl[act_[i]] = ref_[i].theta + (opt_.velocity_feedforward ? kv_over_kp_[i] * ref_[i].theta_dot : 0.0);
    err_[i] = d->qpos[qposadr_[i]] - ref_[i].theta;
  }
  if (opt_.inverse_dynamics_feedforward) {
    // qacc_des: zero for the quadruped's dofs (the tail's base taken as inertial, as in the
    // paper's Eqs. 5-8), the reference for the tail; the servo corrects the rest.
    for (size_t i = 0; i < n; ++i) qacc_des_[dofadr_[i]] = ref_[i].theta_ddot;  // body dofs stay 0
    mj_mulM(m, d, tau_.data(), qacc_des_.data());
    for (size_t i = 0; i < n; ++i) d->qfrc_applied[dofadr_[i]] = tau_[dofadr_[i]] + d->qfrc_bias[dofadr_[i]];
  }
  if (record) {
    for (size_t i = 0; i < n; ++i) {
      max_abs_[i] = std::max(max_abs_[i], std::abs(err_[i]));
      sum_sq_[i] += weight * err_[i] * err_[i];
    }
    ++n_;
    weight_sum_ += weight;
  }
}

TrackingStats TailController::stats() const {
  TrackingStats s;
  s.samples = n_;
  s.max_abs_rad = max_abs_;
  for (double q : sum_sq_) s.rms_rad.push_back(weight_sum_ > 0.0 ? std::sqrt(q / weight_sum_) : 0.0);
  return s;
}

void TailController::resetStats() {
  max_abs_.assign(qposadr_.size(), 0.0);
  sum_sq_.assign(qposadr_.size(), 0.0);
  n_ = 0;
  weight_sum_ = 0.0;
}

}  // namespace tailsim
