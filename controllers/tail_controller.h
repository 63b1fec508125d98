// Tail joint position control for the MuJoCo model: the joints follow theta_ref(t) of a
// TailTrajectory (split-cycle profiles, paper Eqs. 20-23). See docs/mujoco-model.md.
//
// Each tail joint has a MuJoCo <general> PD servo (gain kp, bias -kp theta - kv theta_dot; the
// implicit integrator treats its kv implicitly). Per step, between mj_step1 and mj_step2:
//   ctrl_i           = theta_ref,i + (kv_i / kp_i) theta_dot_ref,i    (velocity feed-forward:
//                      the servo torque becomes kp e + kv e_dot)
//   qfrc_applied[i]  = [M qacc_des + qfrc_bias]_i                    (inverse-dynamics feed-forward)
// qacc_des holds the reference joint accelerations for the tail dofs and zero for the
// quadruped's dofs (the base treated as inertial, as in the paper's Eqs. 5-8). M and qfrc_bias
// come from mj_step1 at the current state, so this equals MuJoCo's own mj_inverse torque
// (qfrc_inverse) for the tail rows at that qacc (the tail carries no constraints and no passive
// forces), at the cost of one sparse M*v product instead of a second mj_inverse pass.
// Measured: feeding the previous step's body accelerations instead closes an algebraic loop
// through the body (tail torque -> body acceleration -> tail torque) that diverges within
// ~0.02 s for the 1- and 6-link tails; the base-inertial form is stable.
#pragma once

#include <vector>

#include <mujoco/mujoco.h>

#include "trajectory/split_cycle_profile.h"

namespace tailsim {

struct TailControllerOptions {
  bool velocity_feedforward = true;
  bool inverse_dynamics_feedforward = true;
};

// Per-joint tracking error theta - theta_ref over the recorded steps.
struct TrackingStats {
  std::vector<double> max_abs_rad;  // max |e|  [rad]
  std::vector<double> rms_rad;      // sqrt(mean e^2), the mean over time  [rad]
  long samples = 0;
};

class TailController {
 public:
  // tail_qposadr / tail_dofadr / actuators: per tail joint i = 1..n (index i-1). kp, kv: the servo
  // gains in the model (used only for the velocity feed-forward).
  TailController(const mjModel* m, TailTrajectory trajectory, std::vector<int> tail_qposadr,
                 std::vector<int> tail_dofadr, std::vector<int> actuators, TailControllerOptions options);

  // Call between mj_step1 and mj_step2 (or after mj_forward): reference at time t_ref, writes
  // d->ctrl and d->qfrc_applied of the tail dofs; records the tracking error at the current
  // state when `record` is set, weighted by `weight` in the RMS (a step k times as long as the
  // others counts k times, so that the RMS is over time).
  void apply(const mjModel* m, mjData* d, double t_ref, bool record, double weight = 1.0);

  // Replaces the reference (same number of joints; throws std::invalid_argument otherwise). For a
  // trajectory decided stroke by stroke (MujocoTrajectoryHook): the new one should continue the old
  // one's reference at the switch time, or the servo sees a step.
  void setTrajectory(TailTrajectory trajectory);
  const TailTrajectory& trajectory() const { return traj_; }

  const std::vector<JointState>& reference() const { return ref_; }  // the last evaluated reference
  // theta - theta_ref of joint i (0-based) at the last apply()  [rad]
  double lastError(int i) const { return err_[i]; }
  TrackingStats stats() const;
  void resetStats();
  int numJoints() const { return static_cast<int>(qposadr_.size()); }

 private:
  TailTrajectory traj_;
  std::vector<int> qposadr_, dofadr_, act_;
  std::vector<double> kv_over_kp_;
  TailControllerOptions opt_;
  std::vector<JointState> ref_;
  std::vector<double> err_, max_abs_, sum_sq_;
  std::vector<mjtNum> qacc_des_, tau_;
  long n_ = 0;
  double weight_sum_ = 0.0;
};

}  // namespace tailsim
