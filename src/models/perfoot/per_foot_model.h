// The per-foot friction model ("perfoot", docs/per-foot-model.md): the quadruped
// as a planar rigid body (x, y, phi) on four point feet, each carrying one Coulomb friction force
// limited by mu N_i and opposing that foot's own slip velocity, with the tail coupled exactly
// (the planar multibody of `analytic.coupling: exact`).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "models/planar/foot_loads.h"
#include "results/output_settings.h"
#include "results/time_series.h"
#include "common/work_limits.h"
#include "robot/scene_effects.h"
#include "settings/fields.h"

namespace tailsim {

enum class NormalLoadModel {
  kQuasiStatic,   // Appendix (A1)-(A5) at the system COM: the same code as L_F
  kLoadTransfer,  // the same, at the centre of pressure shifted by -h F / (m g) (friction at the ground)
};

// Settings of the per-foot model. Friction law, gravity, translation and the foot-load freeze come
// from Effects (kStiction: event-located stick/slip; kContinuous: the ADAMS law per foot; kNone).
struct PerFootSettings {
  double rel_tol = 1e-8;       // dense-output Dormand-Prince relative tolerance
  double abs_tol = 1e-10;      // absolute tolerance
  double event_tol_s = 1e-12;  // breakaway / re-stick location tolerance in time  [s]
  double max_step_s = 0.0;     // step bound while the tail moves; 0 = shortest tail phase / 8  [s]
  // Stiction: a slide whose fastest foot is slower than this may re-stick; below it each foot's
  // friction is regularized (~ its velocity) so the slip direction cannot chatter  [m/s].
  double v_stop_mps = 1e-4;
  NormalLoadModel normal_loads = NormalLoadModel::kQuasiStatic;
  // Body velocity at t = 0: (vx, vy) of the quadruped COM [m/s], phi_dot [rad/s]; the paper's
  // runs start at rest (a slide test starts moving). A stuck start needs a zero twist.
  std::array<double, 3> initial_velocity = {0.0, 0.0, 0.0};
  long max_steps = static_cast<long>(limits::kMaxAnalyticSteps);
};

// The YAML/JSON section `perfoot:` (settings/fields.h), declared once.
template <class V, class S>
settings::For<S, PerFootSettings> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  static const settings::EnumNames<NormalLoadModel> kLoads = {{NormalLoadModel::kQuasiStatic, "quasi_static"},
                                                              {NormalLoadModel::kLoadTransfer, "load_transfer"}};
  v.number(Field{"rel_tol", "dense-output Dormand-Prince relative tolerance"}, s.rel_tol, Limits::positive());
  v.number(Field{"abs_tol", "absolute tolerance"}, s.abs_tol, Limits::positive());
  v.number(Field{"event_tol_s", "breakaway / re-stick location tolerance in time [s]"}, s.event_tol_s,
           Limits::positive());
  v.number(Field{"max_step_s", "step bound while the tail moves; 0 = shortest tail phase / 8 [s]"}, s.max_step_s,
           Limits::nonNegative());
  v.number(Field{"v_stop_mps", "stiction: fastest-foot speed below which a slide may re-stick; friction "
                               "regularized below it [m/s]"},
           s.v_stop_mps, Limits::positive());
  v.choice(Field{"normal_loads", "quasi_static: the Appendix's foot loads (as L_F); load_transfer: the same at "
                                 "the centre of pressure shifted by -h F/(m g), h = quadruped.com_height_m"},
           s.normal_loads, kLoads);
  v.internal(Field{"initial_velocity", "body (vx, vy, phidot) at t = 0 [m/s, rad/s]; not a YAML key"},
             s.initial_velocity);
  v.internal(Field{"max_steps", "step budget (common/work_limits.h); not a YAML key"}, s.max_steps);
}

// Integrates from t = 0 (tail at rest at theta_0, body at rest) to the output duration, as
// simulateAnalytic does, and writes its columns where they exist plus F<k>x_N, F<k>y_N (foot k's
// friction force, world) and N<k>_N (its normal load), k = 1 front-left .. 4 rear-left.
// summary.model = "perfoot". Never throws for physics failures (summary.ok = false, e.g. tipping);
// throws std::invalid_argument for settings it cannot run with.
RunResult simulatePerFoot(const RobotParams& robot, const TailTrajectory& trajectory, const PerFootSettings& settings,
                          const Effects& effects, const OutputSettings& output);

// The per-foot model's columns for an n-link tail, in its CSV's order.
std::vector<std::string> perFootColumns(int links);

// How close a body held at rest is to breaking away: the load factor s of the wrench that holds it
// at each time in `times` (held iff s <= 1; s scales as 1 / mu, the discs' radii being mu N_i, so
// the largest s over a stroke at mu = 1 is the stroke's critical coefficient). The tail follows
// `trajectory`; the body stays at its initial pose. Throws TippingError where the robot tips.
std::vector<double> perFootHeldLoadFactor(const RobotParams& robot, const TailTrajectory& trajectory,
                                          const Effects& effects, const std::vector<double>& times);

// Diagnostic input, not a setting: the four feet's normal loads prescribed over time instead of
// computed (`normal_loads` and `effects.foot_loads` are then unused), e.g. MuJoCo's recorded
// foot<k>_Fn_N, to isolate the load distribution in the gap between the two models
// (tests/bench_gap_attribution.cc, docs/per-foot-model.md "What holds the per-foot model and MuJoCo
// apart"). t_s strictly ascending, N[j][k] foot k+1's load at t_s[j] [N]; linear in between, held
// beyond the ends.
struct PrescribedNormalLoads {
  std::vector<double> t_s;
  std::vector<std::array<double, 4>> N;
  std::array<double, 4> at(double t) const;
};
RunResult simulatePerFoot(const RobotParams& robot, const TailTrajectory& trajectory, const PerFootSettings& settings,
                          const Effects& effects, const OutputSettings& output, const PrescribedNormalLoads& loads);

// ---------------------------------------------------------------------------------------------
// The planar limit surface of four friction discs (Goyal, Ruina & Papadopoulos 1991).

// Eigen vectors are not zeroed by {}: every array of them starts from this.
inline std::array<Vec2, 4> zeros4() { return {Vec2::Zero(), Vec2::Zero(), Vec2::Zero(), Vec2::Zero()}; }

// Four point contacts about a reference point: foot positions r_i and disc radii c_i = mu N_i.
struct FootDiscs {
  std::array<Vec2, 4> r = zeros4();
  std::array<double, 4> c{};
};

// A planar twist (v of the reference point, w) and a wrench (F, M about the reference point).
struct Twist2 {
  Vec2 v = Vec2::Zero();
  double w = 0.0;
};
struct Wrench2 {
  Vec2 F = Vec2::Zero();
  double M = 0.0;
};

// Support function h(xi) = sum c_i |v_i(xi)|, v_i = v + w z x r_i: the most power the discs can
// dissipate at twist xi; a wrench W can be held iff W . xi <= h(xi) for every xi.
double limitSupport(const FootDiscs& d, const Twist2& xi);

// The maximum-dissipation wrench at twist xi: sum over feet of c_i v_i / |v_i| (force and moment);
// friction is minus this. A foot with v_i = 0 contributes nothing (its force is indeterminate).
Wrench2 maxDissipationWrench(const FootDiscs& d, const Twist2& xi);

// The load factor s = max_xi W . xi / h(xi) (the gauge of W in the friction set): W can be held
// iff s <= 1, and it breaks away along `direction` (unit twist, the maximizer: the slip that
// Coulomb's law at every foot and maximum dissipation give). Exact up to round-off: the maximum is
// at a pure translation, at a rotation about one foot (checked by its subgradient), or at a smooth
// instantaneous centre found by Dinkelbach's method with Newton steps, from the best of a scan of
// candidate centres, or (`warm`: the result for a nearby wrench, e.g. the previous time sample)
// from that result's centre. The maximum does not depend on the start: R is quasi-concave where
// it is positive (its superlevel sets are convex), and each Dinkelbach round minimizes a convex
// function globally, so every start reaches the same maximum, up to round-off (about 1e-15 of s).
struct LoadFactor {
  double s = 0.0;
  Twist2 direction;
  int pivot_foot = -1;  // 0..3: the breakaway twist turns about that foot; -1: it does not
  Vec2 centre = Vec2::Zero();  // the breakaway twist's instantaneous centre (when sigma != 0)
  double sigma = 0.0;          // its sense of rotation, +1 or -1; 0: a pure translation
  bool start_scan = false;     // this call scanned the candidate centres (it was not warm-started)
};
LoadFactor loadFactor(const FootDiscs& d, const Wrench2& W, const LoadFactor* warm = nullptr);

// Per-foot forces of a held (stuck) wrench: statically indeterminate, written as the distribution
// sum |F_i|^2 / c_i minimal (F_i = c_i (a + b z x r_i): a rigid viscous twist, the limit of the
// regularized friction below v_stop).
std::array<Vec2, 4> heldFootForces(const FootDiscs& d, const Wrench2& W);

}  // namespace tailsim
