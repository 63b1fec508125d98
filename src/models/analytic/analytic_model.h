// The analytic model at one instant, split the MuJoCo way (mj_fn(m, d)): an AnalyticModel holds
// what does not change during a run (robot, trajectory, settings, effects and the constants
// derived from them), an AnalyticWorkspace the scratch buffers one run reuses. evaluate() is the
// right-hand side; eventMargins(), applySwitch() and settleModes() drive the stick/slip modes
// (stick_slip.h has the model-free part).
#pragma once

#include <array>
#include <limits>
#include <vector>

#include "models/analytic/analytic_settings.h"
#include "models/planar/stick_slip.h"
#include "models/planar/system_loads.h"
#include "robot/scene_effects.h"
#include "trajectory/split_cycle_profile.h"

namespace tailsim {

// State: phi, phi_dot, x, y, vx, vy (world frame; x, y is the quadruped COM).
//
// Choice (paper-notes point 2): with the paper's coupling, the body and the frozen tail move as
// one rigid body; the tail's relative motion enters only through F_T and M_z,T. Its translation
// is tracked at the quadruped COM, m dv_Q/dt = F_T + F_F (the rigid system's rotation terms are
// dropped, as Eq. 9 drops dI_zz/dt), and friction resists v_Q (Eqs. 14-15). Rotation does not
// depend on translation in this model (everything in Eq. 13 is body-frame invariant).
using State = std::array<double, 6>;
enum StateIndex { kPhi = 0, kPhiDot, kX, kY, kVx, kVy };

// What does not change during a run. Holds references: robot and trajectory must outlive it.
struct AnalyticModel {
  AnalyticModel(const RobotParams& r, const TailTrajectory& tr, const AnalyticSettings& s, const Effects& e);

  const RobotParams& robot;
  const TailTrajectory& traj;
  AnalyticSettings settings;
  Effects effects;
  double weight = 0;      // m g (0 without gravity)  [N]
  double mu_break = 0;    // breakawayCoefficient()
  double v_reg = 0;       // translation friction regularized inside |v| < v_reg (adaptive solver)  [m/s]
  double L_F_const = std::numeric_limits<double>::quiet_NaN();  // foot_loads: constant, at t = 0  [m]

  // Stuck states exist only with stiction and some friction to hold them (mu = 0: frictionless).
  bool stiction() const { return effects.friction == FrictionLaw::kStiction && weight > 0.0 && mu_break > 0.0; }
  bool translation() const { return effects.translation; }
  bool needsArm() const { return effects.friction != FrictionLaw::kNone && weight > 0.0; }
};

// Scratch buffers of one run (never shared between threads, never shared between two models).
struct AnalyticWorkspace {
  std::vector<JointState> joints;  // at the last evaluated time
  LoadScratch loads;
  // The tail loads and friction arm at the last evaluated time: they depend on t alone (the
  // trajectory), and the solver asks for the same t more than once (Dormand-Prince's last two
  // stages, an event scan at a step's end). Once every joint has finished its motion they no
  // longer depend on t at all (TailTrajectory::finished): one evaluation serves the rest of the
  // run. Valid while the model is the same.
  struct TailCache {
    bool valid = false, decomposed = false, finished = false;
    double t = 0.0;
    SystemLoads loads;
    double L_F = 0.0;
  } tail_cache;
  // cos and sin of the last yaw angle rotate() was asked for: while the rotation is stuck (and
  // in a probe at the same state) the angle repeats, and so would their sincos call.
  struct YawCache {
    bool valid = false;
    double phi = 0.0, c = 1.0, s = 0.0;
  } yaw;
};

// What the model computes at one instant besides the tail's loads: the motion they cause.
struct Motion {
  Vec2 FT_W = Vec2::Zero();   // tail force, world
  double MzF = 0.0;           // friction moment about the system COM
  Vec2 FF_W = Vec2::Zero();   // friction force, world
  double phi_ddot = 0.0;
  Vec2 a_Q = Vec2::Zero();
  double M_required = 0.0;    // friction moment a stuck rotation needs
  Vec2 F_required = Vec2::Zero();  // friction force a stuck translation needs
  double M_break = 0.0, F_break = 0.0;  // static limits (max(mu_s, mu_d) m g L_F, ... m g)
};

// Everything the model computes at one instant.
struct Eval : Motion {
  SystemLoads loads;
  double L_F = std::numeric_limits<double>::quiet_NaN();
};

// Loads, friction and accelerations at (t, y) in modes m. `decompose`: also the acceleration-/
// speed-driven parts of M_zT (two more recursions; only the output rows need them). Leaves the
// joint states at t in w.joints.
Eval evaluate(const AnalyticModel& m, AnalyticWorkspace& w, double t, const State& y, const Modes& modes,
              bool decompose = false);

// dy/dt at (t, y) in modes m.
void derivative(const AnalyticModel& m, AnalyticWorkspace& w, double t, const State& y, const Modes& modes, State& dy);

// Both event margins at (t, y) (plus a probe for a slow sliding translation).
// rotation: sliding -> rot_dir * phi_dot (the slip ends where it reaches 0);
//           stuck   -> static limit minus the moment a stuck body needs.
// translation: sliding -> max(|v| - v_stop, F_required - F_break): sticks once slower than
//           v_stop with the load under the static limit (in 2-D the velocity need not pass
//           through exactly zero, so "changes sign" has no direct analogue);
//           stuck   -> static limit minus the force a stuck body needs.
Margins eventMargins(const AnalyticModel& m, AnalyticWorkspace& w, double v_stop, double t, const State& y,
                     const Modes& modes);

// Switches DOF `which` (kRot, kTrans) at time t (state y already at t).
void applySwitch(const AnalyticModel& m, AnalyticWorkspace& w, int which, double t, State& y, Modes& modes);

// The modes consistent with (t, y): a stuck DOF whose margin is at or below zero breaks away at
// once, a slide slower than v_stop under the static limit sticks, a rotation sliding against its
// own direction stops (and sticks or turns round). Switching one DOF can change the other's
// margin (exact coupling), so this repeats until nothing changes. Returns the switches made.
int settleModes(const AnalyticModel& m, AnalyticWorkspace& w, double v_stop, double t, State& y, Modes& modes);

}  // namespace tailsim
