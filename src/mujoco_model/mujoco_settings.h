// Settings of the MuJoCo contact ("ADAMS") model. See README "Friction in MuJoCo".
#pragma once

#include <array>
#include <string>

#include "results/work_limits.h"

namespace tailsim {

struct MujocoSettings {
  double timestep_s = 2e-4;             // physics step  [s]
  std::string integrator = "implicit";  // Euler | RK4 | implicit
  std::string solver = "Newton";        // Newton | CG | PGS
  int iterations = 100;                 // constraint solver iterations
  double tolerance = 1e-10;             // constraint solver tolerance
  std::string cone = "elliptic";        // pyramidal | elliptic
  int noslip_iterations = 0;            // MuJoCo noslip post-processing iterations
  int condim = 3;                       // 1 (frictionless), 3 (sliding), 4 (+torsional), 6
  double impratio = 1.0;                // frictional-to-normal impedance ratio
  std::array<double, 2> solref = {0.002, 1.0};                  // contact time constant [s], damping ratio
  std::array<double, 5> solimp = {0.95, 0.99, 0.001, 0.5, 2.0};  // contact impedance
  double mu = -1.0;                     // contact friction; < 0: max(mu_s, mu_d)
  double kp = 0.0;                      // tail position gain [N m/rad]; 0 = chosen from the link inertia
  double kv = 0.0;                      // tail velocity gain [N m s/rad]; 0 = critically damped
  bool velocity_feedforward = true;     // add kv * theta_dot_ref
  bool inverse_dynamics_feedforward = true;  // add MuJoCo's inverse-dynamics joint torque
  // Added by the MuJoCo model (docs/mujoco-model.md):
  double servo_wn_dt = 0.2;             // kp = 0: servo natural frequency * timestep (w_n = servo_wn_dt / timestep_s)
  double body_height_m = 0.15;          // quadruped COM (= tail plane) height above the ground  [m]
  double foot_radius_m = 0.01;          // foot spheres  [m]
  double settle_s = 0.1;                // pre-roll with the tail held at theta(0) so the feet settle; then t = 0  [s]
  double stop_phidot_radps = 1e-3;      // t_stop: |phi_dot| below this from then on  [rad/s]
  // Tipping over (docs/mujoco-model.md "Tipping over"): with gravity and ground contact on, the run
  // fails when the quadruped body tilts beyond max_tilt_deg (angle between its z axis and the
  // vertical; the paper's cases stay below 0.33 deg, a robot tipping over passes 12 deg) or no
  // foot carries load for longer than max_all_feet_off_s (paper cases: up to 0.022 s of contact
  // chatter). 0 = that check off.
  double max_tilt_deg = 5.0;            // [deg]
  double max_all_feet_off_s = 0.1;      // [s]
  // Step budget of the main loop: a run needing more mj_step calls fails (not a loader key).
  long max_steps = static_cast<long>(limits::kMaxMujocoSteps);
};

}  // namespace tailsim
