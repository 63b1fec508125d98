// Settings of the MuJoCo contact ("ADAMS") model. See README "Friction in MuJoCo".
#pragma once

#include <array>
#include <string>

#include "common/work_limits.h"
#include "settings/fields.h"

namespace tailsim {

enum class MujocoIntegrator { kEuler, kRK4, kImplicit };
enum class MujocoSolver { kNewton, kCG, kPGS };
enum class MujocoCone { kPyramidal, kElliptic };
// Contact geometry of each foot (docs/mujoco-model.md "Contact fidelity"). Every shape's lowest
// point or face is at z = 0 with the body at body_height_m, its centre foot_radius_m above the floor:
//   sphere:  radius foot_radius_m (one contact point);
//   capsule: radius foot_radius_m, half-length foot_half_length_m of its cylinder, axis along the
//            body x (up to two contact points, one per end cap, 2 foot_half_length_m apart);
//   box:     a cube of half-size foot_radius_m, bottom face flat on the floor (up to four contact
//            points, the bottom corners).
enum class MujocoFootShape { kSphere, kCapsule, kBox };

// Their names, as in YAML and in MJCF's <option> attributes.
inline const settings::EnumNames<MujocoIntegrator>& integratorNames() {
  static const settings::EnumNames<MujocoIntegrator> k = {
      {MujocoIntegrator::kEuler, "Euler"}, {MujocoIntegrator::kRK4, "RK4"}, {MujocoIntegrator::kImplicit, "implicit"}};
  return k;
}
inline const settings::EnumNames<MujocoSolver>& solverNames() {
  static const settings::EnumNames<MujocoSolver> k = {
      {MujocoSolver::kNewton, "Newton"}, {MujocoSolver::kCG, "CG"}, {MujocoSolver::kPGS, "PGS"}};
  return k;
}
inline const settings::EnumNames<MujocoCone>& coneNames() {
  static const settings::EnumNames<MujocoCone> k = {{MujocoCone::kPyramidal, "pyramidal"},
                                                     {MujocoCone::kElliptic, "elliptic"}};
  return k;
}
inline const settings::EnumNames<MujocoFootShape>& footShapeNames() {
  static const settings::EnumNames<MujocoFootShape> k = {
      {MujocoFootShape::kSphere, "sphere"}, {MujocoFootShape::kCapsule, "capsule"}, {MujocoFootShape::kBox, "box"}};
  return k;
}
inline const char* name(MujocoIntegrator v) { return settings::nameOf(integratorNames(), v); }
inline const char* name(MujocoSolver v) { return settings::nameOf(solverNames(), v); }
inline const char* name(MujocoCone v) { return settings::nameOf(coneNames(), v); }
inline const char* name(MujocoFootShape v) { return settings::nameOf(footShapeNames(), v); }

struct MujocoSettings {
  // Contact and integration defaults: docs/mujoco-model.md "Contact settings: the rule and its
  // evidence" (measured on the random-robot corpus of tests/bench_trust.cc).
  double timestep_s = 1e-4;             // physics step  [s]
  MujocoIntegrator integrator = MujocoIntegrator::kImplicit;
  MujocoSolver solver = MujocoSolver::kNewton;
  int iterations = 100;                 // constraint solver iterations
  double tolerance = 1e-10;             // constraint solver tolerance
  MujocoCone cone = MujocoCone::kElliptic;
  int noslip_iterations = 0;            // MuJoCo noslip post-processing iterations
  int condim = 3;                       // 1 (frictionless), 3 (sliding), 4 (+torsional), 6
  double impratio = 100.0;              // frictional-to-normal impedance ratio (100: friction holds, no creep)
  // Contact time constant [s] and damping ratio: 2 damps the soft first millimetre (impedance ~0.2
  // there, effective damping ratio ~2 sqrt(0.2) ~ 0.9).
  std::array<double, 2> solref = {0.002, 2.0};
  // Contact impedance: 0.015 at first touch rising to 0.99 over 1 mm of penetration. A sliding foot
  // in MuJoCo's convex contact is pushed off the floor at ~ mu |v_slip| times the impedance; a low
  // impedance where the foot carries its share of the weight (~0.15 mm deep) keeps it on the floor.
  std::array<double, 5> solimp = {0.015, 0.99, 0.001, 0.5, 2.0};
  double mu = -1.0;                     // contact friction; < 0: max(mu_s, mu_d)
  // Torsional friction of each foot (MuJoCo friction[1], a length: the largest torsional moment
  // is this times the normal force); acts with condim 4 or 6 only. 0: point feet, as the per-foot
  // model (docs/per-foot-model.md "What holds the per-foot model and MuJoCo apart")  [m]
  double torsional_friction_m = 0.0;
  double kp = 0.0;                      // tail position gain [N m/rad]; 0 = chosen from the link inertia
  double kv = 0.0;                      // tail velocity gain [N m s/rad]; 0 = critically damped
  bool velocity_feedforward = true;     // add kv * theta_dot_ref
  bool inverse_dynamics_feedforward = true;  // add MuJoCo's inverse-dynamics joint torque
  // Added by the MuJoCo model (docs/mujoco-model.md):
  double servo_wn_dt = 0.1;             // kp = 0: servo natural frequency * timestep (w_n = servo_wn_dt / timestep_s = 1000 rad/s)
  double body_height_m = 0.15;          // quadruped COM (= tail plane) height above the ground  [m]
  double foot_radius_m = 0.01;          // foot sphere / capsule radius, box half-size  [m]
  MujocoFootShape foot_shape = MujocoFootShape::kSphere;  // contact geometry of the feet (see the enum)
  double foot_half_length_m = 0.01;     // capsule feet: half-length of the cylinder along body x  [m]
  double settle_s = 0.1;                // pre-roll with the tail held at theta(0) so the feet settle; then t = 0  [s]
  // Once the tail's motion has ended and the body rests (common/work_limits.h kRest*), the run
  // steps at rest_step_factor * timestep_s: nothing moves, so the finer step buys nothing there
  // (docs/mujoco-model.md "Step schedule"). 1 = every step at timestep_s.
  int rest_step_factor = 5;
  double stop_phidot_radps = 1e-3;      // t_stop: |phi_dot| below this from then on  [rad/s]
  // Tipping over (docs/mujoco-model.md "Tipping over"): with gravity and ground contact on, the run
  // fails when the quadruped body tilts beyond max_tilt_deg (angle between its z axis and the
  // vertical; the paper's cases stay below 0.33 deg, a robot tipping over passes 12 deg) or no
  // foot carries load for longer than max_all_feet_off_s (paper cases: up to 0.022 s of contact
  // chatter). 0 = that check off.
  double max_tilt_deg = 5.0;            // [deg]
  double max_all_feet_off_s = 0.1;      // [s]
  // The run's own error estimate (docs/mujoco-model.md "Uncertainty of a run"): a second run at
  // twice the timestep (servo w_n kept) gives phi_net_uncertainty_deg = 2 |phi_h - phi_2h| + 0.5 %
  // of max(|phi_net|, 0.5 deg); it has its own pre-roll and stops once the body rests after the
  // stroke (the pre-roll and the stroke's steps at 2 h). A result whose uncertainty
  // exceeds uncertainty_warn_share of max(|phi_net|, 0.5 deg) carries a warning.
  bool uncertainty = true;
  double uncertainty_warn_share = 0.1;  // [1]
  // Step budget of the main loop: a run needing more mj_step calls fails (not a loader key).
  long max_steps = static_cast<long>(limits::kMaxMujocoSteps);
};

// The YAML/JSON keys of MujocoSettings (settings/fields.h), declared once.
template <class V, class S>
settings::For<S, MujocoSettings> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  v.number(Field{"timestep_s", "physics step [s]"}, s.timestep_s, Limits::positive());
  v.choice(Field{"integrator", "MuJoCo integrator"}, s.integrator, integratorNames());
  v.choice(Field{"solver", "constraint solver"}, s.solver, solverNames());
  v.integer(Field{"iterations", "constraint solver iterations"}, s.iterations, Limits::atLeast(1));
  v.number(Field{"tolerance", "constraint solver tolerance"}, s.tolerance, Limits::nonNegative());
  v.choice(Field{"cone", "friction cone"}, s.cone, coneNames());
  v.integer(Field{"noslip_iterations", "noslip post-processing iterations"}, s.noslip_iterations, Limits::atLeast(0));
  v.integer(Field{"condim", "contact dimensionality: 1 frictionless, 3 sliding, 4 +torsional, 6 +rolling"}, s.condim,
            Limits::closed(1, 6), settings::IntSet{1, 3, 4, 6});
  v.number(Field{"impratio", "frictional-to-normal impedance ratio"}, s.impratio, Limits::positive());
  v.numbers(Field{"solref", "[timeconst > 0, dampratio > 0] or direct [-stiffness, -damping]"}, s.solref);
  v.numbers(Field{"solimp", "[dmin, dmax, width, midpoint, power]: dmin, dmax, midpoint in (0, 1), width > 0, power >= 1"},
            s.solimp);
  v.number(Field{"mu", "contact friction; absent (-1 in the resolved case) = max(mu_s, mu_d)"}, s.mu,
           Limits::nonNegative());
  v.number(Field{"torsional_friction_m", "feet's torsional friction (moment / normal force; condim 4 or 6 only) [m]"},
           s.torsional_friction_m, Limits::nonNegative());
  v.number(Field{"kp", "tail position gain [N m/rad]; 0 = from servo_wn_dt and the link inertia"}, s.kp,
           Limits::nonNegative());
  v.number(Field{"kv", "tail velocity gain [N m s/rad]; 0 = critically damped"}, s.kv, Limits::nonNegative());
  v.boolean(Field{"velocity_feedforward", "add kv * theta_dot_ref"}, s.velocity_feedforward);
  v.boolean(Field{"inverse_dynamics_feedforward", "add MuJoCo's inverse-dynamics joint torque"},
            s.inverse_dynamics_feedforward);
  v.number(Field{"servo_wn_dt", "kp = 0: servo natural frequency * timestep"}, s.servo_wn_dt, Limits::positive());
  v.internal(Field{"body_height_m", "quadruped COM (= tail plane) height above the ground, = quadruped.com_height_m; "
                                   "not a YAML key [m]"},
             s.body_height_m);
  v.number(Field{"foot_radius_m", "foot sphere / capsule radius, box half-size [m]"}, s.foot_radius_m,
           Limits::positive());
  v.choice(Field{"foot_shape", "feet's contact geometry: sphere, capsule (axis along body x) or box (cube, flat bottom)"},
           s.foot_shape, footShapeNames());
  v.number(Field{"foot_half_length_m", "capsule feet: half-length of the cylinder along body x [m]"},
           s.foot_half_length_m, Limits::positive());
  v.number(Field{"settle_s", "pre-roll with the tail held at theta(0) so the feet settle [s]"}, s.settle_s,
           Limits::nonNegative());
  v.integer(Field{"rest_step_factor",
                  "after the tail stops, once the body rests, step at this multiple of timestep_s; 1 = never"},
            s.rest_step_factor, Limits::closed(1, 16));
  v.number(Field{"stop_phidot_radps", "t_stop: |phi_dot| below this from then on [rad/s]"}, s.stop_phidot_radps,
           Limits::positive());
  v.number(Field{"max_tilt_deg", "tipping over: largest body tilt; 0 = off [deg]"}, s.max_tilt_deg,
           Limits::nonNegative());
  v.number(Field{"max_all_feet_off_s", "tipping over: longest time with no foot loaded; 0 = off [s]"},
           s.max_all_feet_off_s, Limits::nonNegative());
  v.boolean(Field{"uncertainty", "estimate phi_net_uncertainty_deg with a second run at 2 timestep_s"}, s.uncertainty);
  v.number(Field{"uncertainty_warn_share",
                 "warn when phi_net_uncertainty_deg exceeds this share of max(abs(phi_net), 0.5 deg)"},
           s.uncertainty_warn_share, Limits::positive());
  v.internal(Field{"max_steps", "step budget (common/work_limits.h); not a YAML key"}, s.max_steps);
}

}  // namespace tailsim
