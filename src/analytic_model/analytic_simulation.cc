#include "analytic_model/analytic_simulation.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <boost/numeric/odeint.hpp>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "results/work_limits.h"
#include "robot/friction_law.h"

namespace tailsim {
namespace {

namespace odeint = boost::numeric::odeint;

// State: phi, phi_dot, x, y, vx, vy (world frame; x, y is the quadruped COM).
//
// Choice (paper-notes point 2): with the paper's coupling, the body and the frozen tail move as
// one rigid body; the tail's relative motion enters only through F_T and M_z,T. Its translation
// is tracked at the quadruped COM, m dv_Q/dt = F_T + F_F (the rigid system's rotation terms are
// dropped, as Eq. 9 drops dI_zz/dt), and friction resists v_Q (Eqs. 14-15). Rotation does not
// depend on translation in this model (everything in Eq. 13 is body-frame invariant).
using State = std::array<double, 6>;
enum { kPhi = 0, kPhiDot, kX, kY, kVx, kVy };

constexpr int kRot = 0, kTrans = 1;
using Margins = std::array<double, 2>;  // event margins g of rotation, translation
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Modes {
  bool stuck[2] = {false, false};  // rotation, translation (stiction law only)
  double rot_dir = 0.0;            // sign of phi_dot while slipping (friction opposes it)
};

// Everything the model computes at one instant.
struct Eval {
  SystemLoads loads;
  double L_F = kNaN;
  Vec2 FT_W = Vec2::Zero();   // tail force, world
  double MzF = 0.0;           // friction moment about the system COM
  Vec2 FF_W = Vec2::Zero();   // friction force, world
  double phi_ddot = 0.0;
  Vec2 a_Q = Vec2::Zero();
  double M_required = 0.0;    // friction moment a stuck rotation needs
  Vec2 F_required = Vec2::Zero();  // friction force a stuck translation needs
  double M_break = 0.0, F_break = 0.0;  // static limits (max(mu_s, mu_d) m g L_F, ... m g)
};

class Model {
 public:
  Model(const RobotParams& r, const TailTrajectory& tr, const AnalyticSettings& s, const Effects& e)
      : robot_(r), traj_(tr), s_(s), e_(e) {
    weight_ = r.systemMass() * (e.gravity ? r.gravity_mps2 : 0.0);
    mu_break_ = breakawayCoefficient(r.friction);
    // The fixed-step solver keeps plain Coulomb friction in translation (its per-step stop check
    // ends a slide); the adaptive one regularizes inside |v| < v_stop (see evaluate()).
    v_reg_ = s.solver == "fixed" ? 0.0 : s.v_stop_mps;
    if (e.foot_loads == FootLoadModel::kConstant && needsArm()) {
      std::vector<JointState> j0;
      traj_.evaluate(0.0, j0);
      SystemLoads sl;
      systemMassProperties(robot_, tailKinematics(robot_.tail, j0), sl);
      L_F_const_ = footLoads(robot_.quadruped, sl.p_QC).L_F;
    }
  }

  // Stuck states exist only with stiction and some friction to hold them (mu = 0: frictionless).
  bool stiction() const { return e_.friction == FrictionLaw::kStiction && weight_ > 0.0 && mu_break_ > 0.0; }
  double weight() const { return weight_; }
  bool translation() const { return e_.translation; }
  bool needsArm() const { return e_.friction != FrictionLaw::kNone && weight_ > 0.0; }
  const Effects& effects() const { return e_; }

  void joints(double t, std::vector<JointState>& js) const { traj_.evaluate(t, js); }

  // `decompose`: also the acceleration-/speed-driven parts of M_zT (two more recursions; only
  // the output rows need them, never the dynamics).
  Eval evaluate(double t, const State& y, const Modes& m, bool decompose = false) const {
    Eval ev;
    std::vector<JointState>& js = scratch_joints_;
    traj_.evaluate(t, js);
    systemLoads(robot_, js, decompose, ev.loads, scratch_);
    if (!std::isfinite(ev.loads.MzT) || !std::isfinite(ev.loads.F_T_Q.x()) || !std::isfinite(ev.loads.F_T_Q.y()) ||
        !std::isfinite(ev.loads.Izz_kgm2) || !std::isfinite(js.empty() ? 0.0 : js.front().theta))
      throw std::runtime_error("the tail loads became non-finite at t=" + std::to_string(t) +
                               " s (M_z,T = " + std::to_string(ev.loads.MzT) + " N m): check the trajectory values");
    if (needsArm())
      ev.L_F = e_.foot_loads == FootLoadModel::kConstant ? L_F_const_
                                                         : footLoads(robot_.quadruped, ev.loads.p_QC).L_F;
    const double phi = y[kPhi], w = y[kPhiDot];
    ev.FT_W = rotate(phi, ev.loads.F_T_Q);
    const Vec2 v(y[kVx], y[kVy]);
    ev.M_break = mu_break_ * weight_ * (needsArm() ? ev.L_F : 0.0);
    ev.F_break = mu_break_ * weight_;

    // Friction loads of the DOFs that slide (known); stuck DOFs get theirs from the solve.
    double MzF = 0.0;
    Vec2 FF = Vec2::Zero();
    const FrictionParams& fp = robot_.friction;
    if (needsArm()) {
      if (e_.friction == FrictionLaw::kStiction) {
        // Eq. (16), sliding. The direction is the slip mode's, fixed until the mode ends at a
        // located event (phi_dot reaching 0): taking it from the sign of phi_dot inside trial
        // steps would make the right-hand side jump wherever a trial state overshoots zero, and
        // the solver chatter there with ever smaller steps.
        MzF = -fp.mu_d * weight_ * ev.L_F * m.rot_dir;
        // Eq. (15), sliding; inside |v| < v_stop the direction is regularized (friction ~ v), so a
        // body creeping at a load just above the static limit does not chatter in direction.
        // The fixed-step solver keeps plain Coulomb friction (its per-step stop check ends the
        // slide); the ball's stiffness mu W / (m v_stop) would make coarse explicit steps unstable.
        const double speed = v.norm();
        if (speed > 0.0) FF = -fp.mu_d * weight_ * v / std::max(speed, v_reg_);
      } else {  // the ADAMS law: mu follows the slip speed, no stuck state
        const double mu_r = adamsFrictionCoefficient(std::abs(w), fp.phidot_s_radps, fp.phidot_d_radps, fp.mu_s, fp.mu_d);
        MzF = -mu_r * weight_ * ev.L_F * (w > 0 ? 1.0 : (w < 0 ? -1.0 : 0.0));
        const double speed = v.norm();
        if (speed > 0.0) FF = -adamsFrictionCoefficient(speed, fp.v_s_mps, fp.v_d_mps, fp.mu_s, fp.mu_d) * weight_ * v / speed;
      }
    }

    // Equations of motion  A z = r0 + E f,  z = (a_Qx, a_Qy, phi_ddot), f = (F_Fx, F_Fy, M_zF).
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero(), E = Eigen::Matrix3d::Identity();
    Eigen::Vector3d r0;
    const double mass = ev.loads.mass_kg;
    if (s_.coupling == Coupling::kPaper) {
      // Eq. (9): m a = F_T + F_F, I_zz phi_ddot = M_z,T + M_z,F.
      A.diagonal() << mass, mass, ev.loads.Izz_kgm2;
      r0 << ev.FT_W.x(), ev.FT_W.y(), ev.loads.MzT;
    } else {
      exactCoupling(js, phi, w, ev, A, E, r0);
    }
    const bool free_dof[3] = {translation() && !m.stuck[kTrans], translation() && !m.stuck[kTrans], !m.stuck[kRot]};
    const double f_known[3] = {FF.x(), FF.y(), MzF};
    if (s_.coupling == Coupling::kPaper) {  // diagonal: solve each DOF on its own
      double u[3];
      for (int j = 0; j < 3; ++j) u[j] = free_dof[j] ? (r0[j] + f_known[j]) / A(j, j) : -r0[j];
      return finish(ev, free_dof, u, FF, MzF);
    }
    Eigen::Matrix3d K;
    Eigen::Vector3d rhs = r0;
    for (int j = 0; j < 3; ++j) {
      if (free_dof[j]) {
        K.col(j) = A.col(j);
        rhs += E.col(j) * f_known[j];
      } else {
        K.col(j) = -E.col(j);
      }
    }
    const Eigen::Vector3d sol = K.partialPivLu().solve(rhs);
    const double u[3] = {sol[0], sol[1], sol[2]};
    return finish(ev, free_dof, u, FF, MzF);
  }

  // Unpacks the solve: accelerations of the sliding DOFs, friction loads of the stuck ones.
  Eval finish(Eval& ev, const bool free_dof[3], const double u[3], const Vec2& FF, double MzF) const {
    ev.a_Q = Vec2(free_dof[0] ? u[0] : 0.0, free_dof[1] ? u[1] : 0.0);
    ev.phi_ddot = free_dof[2] ? u[2] : 0.0;
    ev.FF_W = free_dof[0] ? FF : Vec2(u[0], u[1]);
    ev.MzF = free_dof[2] ? MzF : u[2];
    ev.F_required = free_dof[0] ? Vec2::Zero() : Vec2(u[0], u[1]);
    ev.M_required = free_dof[2] ? 0.0 : u[2];
    if (!translation()) ev.FF_W = Vec2::Zero();  // locked, not friction: no friction force reported
    return ev;
  }

  void derivative(double t, const State& y, const Modes& m, State& dy) const {
    const Eval ev = evaluate(t, y, m);
    dy[kPhi] = m.stuck[kRot] ? 0.0 : y[kPhiDot];
    dy[kPhiDot] = ev.phi_ddot;
    const bool moving = translation() && !m.stuck[kTrans];
    dy[kX] = moving ? y[kVx] : 0.0;
    dy[kY] = moving ? y[kVy] : 0.0;
    dy[kVx] = ev.a_Q.x();
    dy[kVy] = ev.a_Q.y();
  }

 private:
  // paper-notes point 3: the planar multibody with the base moving. Newton-Euler of every body
  // (quadruped + links) summed: linear momentum, and angular momentum about the quadruped COM.
  // Friction: F_F acts at the system COM (no moment about it, as in Eq. 9) plus the pure M_z,F.
  void exactCoupling(const std::vector<JointState>& js, double phi, double w, Eval& ev, Eigen::Matrix3d& A,
                     Eigen::Matrix3d& E, Eigen::Vector3d& r0) const {
    TailKinematics& kin = exact_kin_;
    tailKinematics(robot_.tail, js, kin);
    const Vec2 p_QB(-robot_.quadruped.d_Q2B_m, 0.0);
    Vec2 S = Vec2::Zero(), lin = Vec2::Zero();
    double J = robot_.quadruped.izz_kgm2, ang = 0.0;
    for (size_t i = 0; i < robot_.tail.size(); ++i) {
      const TailLink& l = robot_.tail[i];
      // Link COM relative to the quadruped COM, in Q, and its rates (R_Z(180 deg) flips B).
      const Vec2 rho = rotate(phi, Vec2(p_QB - kin.p_L[i]));
      const Vec2 rho_dot_rel = rotate(phi, Vec2(-kin.v_L[i]));
      const Vec2 rho_ddot_rel = rotate(phi, Vec2(-kin.a_L[i]));
      const Vec2 b = -w * w * rho + 2.0 * w * perp(rho_dot_rel) + rho_ddot_rel;  // a_i - a_Q - phi_ddot z x rho
      S += l.mass_kg * rho;
      J += l.izz_kgm2 + l.mass_kg * rho.squaredNorm();
      lin += l.mass_kg * b;
      ang += l.mass_kg * cross2(rho, b) + l.izz_kgm2 * kin.alpha[i];
    }
    const double m = ev.loads.mass_kg;
    A << m, 0, -S.y(), 0, m, S.x(), -S.y(), S.x(), J;
    r0 << -lin.x(), -lin.y(), -ang;
    const Vec2 c = S / m;  // system COM relative to the quadruped COM, world
    E.setIdentity();
    E(2, 0) = -c.y();
    E(2, 1) = c.x();
  }

  const RobotParams& robot_;
  const TailTrajectory& traj_;
  AnalyticSettings s_;
  Effects e_;
  double weight_ = 0, mu_break_ = 0, L_F_const_ = kNaN, v_reg_ = 0;
  // Reused buffers (one Model per run, never shared between threads).
  mutable std::vector<JointState> scratch_joints_;
  mutable LoadScratch scratch_;
  mutable TailKinematics exact_kin_;
};

// ---------------------------------------------------------------------------------------------
// Output rows.

class Recorder {
 public:
  // n_samples: rows on the grid 0, dt, ... <= t_end (outputRows(), bounded before any work).
  Recorder(const Model& model, int n_links, double dt, double t_end, long n_samples)
      : model_(model), n_(n_links), dt_(dt), t_end_(t_end), n_samples_(n_samples) {
    for (int i = 1; i <= n_; ++i) ts_.addColumn("theta" + std::to_string(i) + "_deg");
    for (int i = 1; i <= n_; ++i) ts_.addColumn("thetadot" + std::to_string(i) + "_dps");
    for (int i = 1; i <= n_; ++i) ts_.addColumn("thetaddot" + std::to_string(i) + "_dps2");
    for (const char* c : {"x_m", "y_m", "phi_deg", "phidot_dps", "phiddot_dps2", "MzT_Nm", "MzT_acc_Nm",
                          "MzT_speed_Nm", "MzT_tan_Nm", "MzT_cen_Nm", "MzF_Nm", "Izz_phiddot_Nm", "Izz_kgm2",
                          "LF_m", "FTx_N", "FTy_N", "FFx_N", "FFy_N", "rot_state", "trans_state"})
      ts_.addColumn(c);
    // t_s first: rebuild with it in front.
    TimeSeries withT;
    withT.addColumn("t_s");
    for (const auto& n : ts_.names()) withT.addColumn(n);
    ts_ = std::move(withT);
  }

  // Next sample time not yet written (or +inf when done).
  double nextTime() const { return next_ < n_samples_ ? next_ * dt_ : std::numeric_limits<double>::infinity(); }
  bool done() const { return next_ >= n_samples_; }

  void record(double t, const State& y, const Modes& m) {
    const Eval ev = model_.evaluate(t, y, m, model_.effects().load_decomposition);
    std::vector<JointState>& js = js_;
    model_.joints(t, js);
    row_.clear();
    row_.push_back(t);
    const double d = 180.0 / M_PI;
    for (const auto& j : js) row_.push_back(j.theta * d);
    for (const auto& j : js) row_.push_back(j.theta_dot * d);
    for (const auto& j : js) row_.push_back(j.theta_ddot * d);
    const bool decomp = model_.effects().load_decomposition;
    const bool stiction = model_.stiction();
    row_.insert(row_.end(), {y[kX], y[kY], y[kPhi] * d, y[kPhiDot] * d, ev.phi_ddot * d, ev.loads.MzT,
                             decomp ? ev.loads.MzT_acc : kNaN, decomp ? ev.loads.MzT_speed : kNaN,
                             decomp ? ev.loads.MzT_tan : kNaN, decomp ? ev.loads.MzT_cen : kNaN, ev.MzF,
                             ev.loads.Izz_kgm2 * ev.phi_ddot, ev.loads.Izz_kgm2, ev.L_F, ev.FT_W.x(), ev.FT_W.y(),
                             ev.FF_W.x(), ev.FF_W.y(), stiction ? (m.stuck[kRot] ? 0.0 : 1.0) : kNaN,
                             stiction && model_.translation() ? (m.stuck[kTrans] ? 0.0 : 1.0) : kNaN});
    ts_.appendRow(row_);
    ++next_;
  }

  // Once everything is at rest for good (tail stopped, body stuck), every remaining row is the
  // last one with a later time: copy it instead of re-evaluating the model.
  void repeatLastUntilDone() {
    if (ts_.numRows() == 0) return;
    while (!done()) {
      row_[0] = nextTime();
      ts_.appendRow(row_);
      ++next_;
    }
  }

  TimeSeries take() { return std::move(ts_); }

 private:
  const Model& model_;
  int n_;
  double dt_, t_end_;
  long n_samples_ = 0, next_ = 0;
  TimeSeries ts_;
  std::vector<double> row_;
  std::vector<JointState> js_;
};

// ---------------------------------------------------------------------------------------------
// Stick/slip events. g > 0: no switch; a switch happens where g reaches 0 from above.

struct Events {
  const Model& model;
  double v_stop;  // a slide below this speed may stick (fixed solver: at least one step's friction)

  // Both margins at (t, y) from one model evaluation (plus a probe for a slow sliding translation).
  // rotation: sliding -> rot_dir * phi_dot (the slip ends where it reaches 0);
  //           stuck   -> static limit minus the moment a stuck body needs.
  // translation: sliding -> max(|v| - v_stop, F_required - F_break): sticks once slower than
  //           v_stop with the load under the static limit (in 2-D the velocity need not pass
  //           through exactly zero, so "changes sign" has no direct analogue);
  //           stuck   -> static limit minus the force a stuck body needs.
  Margins g(double t, const State& y, const Modes& m) const {
    Margins out{1.0, 1.0};
    const bool trans = model.translation();
    Eval ev;
    if (m.stuck[kRot] || (trans && m.stuck[kTrans])) ev = model.evaluate(t, y, m);
    out[kRot] = m.stuck[kRot] ? ev.M_break - std::abs(ev.M_required) : m.rot_dir * y[kPhiDot];
    if (trans) {
      if (m.stuck[kTrans]) {
        out[kTrans] = ev.F_break - ev.F_required.norm();
      } else {
        const double fast = std::hypot(y[kVx], y[kVy]) - v_stop;
        if (fast > 0) {
          out[kTrans] = fast;  // same sign as the max below, without the probe's evaluation
        } else {
          Modes probe = m;
          probe.stuck[kTrans] = true;
          const Eval pe = model.evaluate(t, y, probe);
          out[kTrans] = std::max(fast, pe.F_required.norm() - pe.F_break);
        }
      }
    }
    return out;
  }
};

// Switches DOF `which` at time t (state y already at t). Returns the mode change made.
void applySwitch(int which, double t, State& y, Modes& m, const Model& model) {
  if (which == kRot) {
    if (!m.stuck[kRot]) {  // stopped sliding: stick, unless the load exceeds the static limit
      y[kPhiDot] = 0.0;
      Modes probe = m;
      probe.stuck[kRot] = true;
      const Eval e = model.evaluate(t, y, probe);
      if (std::abs(e.M_required) < e.M_break) {
        m.stuck[kRot] = true;
      } else {  // turns straight round: slide the other way (Eq. 16, second case)
        m.rot_dir = e.M_required < 0 ? 1.0 : -1.0;  // friction opposes the load: load = -required
      }
    } else {  // breakaway (Eq. 16, second case): slide in the load's direction
      const Eval e = model.evaluate(t, y, m);
      m.stuck[kRot] = false;
      m.rot_dir = e.M_required < 0 ? 1.0 : -1.0;
    }
  } else {
    // Stop (below v_stop with the load under the static limit) or breakaway (Eq. 15, second
    // case: the regularized friction lets it accelerate along the load).
    if (!m.stuck[kTrans]) y[kVx] = y[kVy] = 0.0;
    m.stuck[kTrans] = !m.stuck[kTrans];
  }
}

// The modes consistent with (t, y): a stuck DOF whose margin is at or below zero breaks away at
// once, a slide slower than v_stop under the static limit sticks, a rotation sliding against its
// own direction stops (and sticks or turns round). Switching one DOF can change the other's
// margin (exact coupling), so this repeats until nothing changes. Returns the switches made.
int settleModes(double t, State& y, Modes& m, const Model& model, const Events& events) {
  if (!model.stiction()) return 0;
  for (int n = 0;; ++n) {
    if (n > 8)
      throw std::runtime_error("stick/slip modes do not settle at t=" + std::to_string(t) +
                               " s (each switch undoes the other)");
    const Margins g = events.g(t, y, m);
    int which = -1;
    for (int w : {kRot, kTrans})
      if (m.stuck[w] && g[w] <= 0) which = w;
    if (which < 0 && model.translation() && !m.stuck[kTrans] && g[kTrans] < 0) which = kTrans;
    if (which < 0 && !m.stuck[kRot] && g[kRot] < 0) which = kRot;
    if (which < 0) return n;
    applySwitch(which, t, y, m, model);
  }
}

// Illinois (modified regula falsi) on g over [a, b] with g(a) > 0 >= g(b).
template <class G>
double illinois(const G& g, double a, double b, double ga, double gb, double tol) {
  if (!(ga > 0)) return a + std::min(tol, b - a);  // the switch is at a itself
  int side = 0;
  for (int it = 0; it < 100 && b - a > tol; ++it) {
    double c = (a * gb - b * ga) / (gb - ga);
    if (!(c > a && c < b)) c = 0.5 * (a + b);
    const double gc = g(c);
    if (gc > 0) {
      a = c; ga = gc;
      if (side == -1) gb *= 0.5;
      side = -1;
    } else {
      b = c; gb = gc;
      if (side == +1) ga *= 0.5;
      side = +1;
    }
  }
  return b;  // the first time known to be at or past the switch
}

// Golden-section minimum of g on [a, b].
template <class G>
std::pair<double, double> goldenMin(const G& g, double a, double b, double tol) {
  const double r = 0.5 * (std::sqrt(5.0) - 1.0);
  double c = b - r * (b - a), d = a + r * (b - a);
  double gc = g(c), gd = g(d);
  for (int it = 0; it < 60 && b - a > tol; ++it) {
    if (gc < gd) { b = d; d = c; gd = gc; c = b - r * (b - a); gc = g(c); }
    else { a = c; c = d; gc = gd; d = a + r * (b - a); gd = g(d); }
  }
  return gc < gd ? std::make_pair(c, gc) : std::make_pair(d, gd);
}

std::string notAtRestWarning(double t_end, double phidot_dps, double speed_mps) {
  std::ostringstream os;
  os.precision(4);
  os << "the body is still moving when the run ends at t = " << t_end << " s (|phi_dot| " << phidot_dps
     << " deg/s, speed " << speed_mps << " m/s; at rest means below " << limits::kAtRestPhidotDps << " deg/s and "
     << limits::kAtRestSpeedMps << " m/s): phi_net is not final, raise output.settle_s or duration_s";
  return os.str();
}

struct Found {
  bool hit = false;
  double t = 0;
  int which = 0;
};

// Searches [ta, tb] for the first switch of either DOF. Both margins are sampled together every
// h_scan (so a short load peak between two solver steps is not stepped over: paper-notes
// point 4); in the first sample interval where any margin reaches zero, every DOF that crosses
// there is located and the earliest wins, so no DOF's switch can hide behind another's. A dip of
// a stuck DOF's margin between samples (all samples positive) is refined by golden section.
template <class StateAt>
Found findSwitch(const Events& events, const Modes& m, double ta, double tb, double h_scan, double tol,
                 const StateAt& stateAt) {
  const int k = std::max(2, static_cast<int>(std::ceil((tb - ta) / h_scan)));
  State y;
  auto gAt = [&](double t) {
    stateAt(t, y);
    return events.g(t, y, m);
  };
  // A stuck margin reaching 0 from above, or a sliding one turning negative (a stop).
  auto crosses = [&](int w, double g0, double g1) { return (g0 > 0 && g1 <= 0) || (!m.stuck[w] && g0 >= 0 && g1 < 0); };
  Margins g_prev = gAt(ta), g_prev2 = g_prev;
  for (int w : {kRot, kTrans})  // already past the switch (settleModes normally resolves this)
    if ((m.stuck[w] && g_prev[w] <= 0) || (!m.stuck[w] && g_prev[w] < 0)) return {true, ta, w};
  double t_prev = ta, t_prev2 = ta;
  for (int i = 1; i <= k; ++i) {
    const double t = ta + (tb - ta) * i / k;
    const Margins gt = gAt(t);
    Found best;
    for (int w : {kRot, kTrans}) {
      auto gw = [&](double tt) { return gAt(tt)[w]; };
      double ts = 0;
      bool hit = false;
      if (crosses(w, g_prev[w], gt[w])) {
        ts = illinois(gw, t_prev, t, g_prev[w], gt[w], tol);
        hit = true;
      } else if (m.stuck[w] && i >= 2 && g_prev[w] < g_prev2[w] && g_prev[w] < gt[w] && g_prev[w] > 0) {
        const auto [tm, gm] = goldenMin(gw, t_prev2, t, tol * 1e3);
        if (gm <= 0) {
          ts = illinois(gw, t_prev2, tm, g_prev2[w], gm, tol);
          hit = true;
        }
      }
      if (hit && (!best.hit || ts < best.t)) best = {true, ts, w};
    }
    if (best.hit) return best;
    t_prev2 = t_prev; g_prev2 = g_prev;
    t_prev = t; g_prev = gt;
  }
  return {};
}

// Frictionless residual spin of the paper coupling (docs/accuracy.md "Paper coupling diagnostic").
// With the paper's coupling, I_zz phi_ddot = M_z,T depends on the joint trajectory alone, so the
// body rate it gives with mu = 0 is the quadrature of M_z,T / I_zz. The system starts at rest and
// the tail ends at rest: angular momentum conservation (exact coupling, MuJoCo) leaves the body
// with no spin after the motion; what the paper's rate keeps is its angular-momentum error.
// Returns the residual rate at the tail's end  [rad/s].
double paperResidualSpin(const RobotParams& robot, const TailTrajectory& traj) {
  std::vector<double> b = traj.breakpoints();
  std::vector<JointState> js;
  SystemLoads sl;
  LoadScratch scratch;
  auto f = [&](double t) {
    traj.evaluate(t, js);
    systemLoads(robot, js, false, sl, scratch);
    return sl.MzT / sl.Izz_kgm2;
  };
  double w = 0;
  constexpr int kPerSegment = 64;  // Simpson intervals between two breakpoints (the loads are smooth there)
  for (std::size_t s = 0; s + 1 < b.size(); ++s) {
    const double a = b[s], h = (b[s + 1] - b[s]) / kPerSegment;
    if (!(h > 0)) continue;
    double fa = f(a);
    for (int i = 0; i < kPerSegment; ++i) {
      const double t0 = a + i * h, fm = f(t0 + 0.5 * h), fb = f(t0 + h);
      w += h / 6.0 * (fa + 4.0 * fm + fb);
      fa = fb;
    }
  }
  return w;
}

bool needsFrictionArm(const Model& m) { return m.needsArm(); }

bool allFinite(const State& y) {
  for (double v : y)
    if (!std::isfinite(v)) return false;
  return true;
}

}  // namespace

RunResult simulateAnalytic(const RobotParams& robot, const TailTrajectory& trajectory, const AnalyticSettings& settings,
                           const Effects& effects, const OutputSettings& output) {
  if (settings.solver != "adaptive" && settings.solver != "fixed")
    throw std::invalid_argument("analytic.solver must be adaptive or fixed, got " + settings.solver);
  if (!(settings.rel_tol > 0) || !(settings.abs_tol > 0)) throw std::invalid_argument("analytic tolerances must be > 0");
  if (!(settings.fixed_dt_s > 0)) throw std::invalid_argument("analytic.fixed_dt_s must be > 0");
  if (!(output.sample_dt_s > 0)) throw std::invalid_argument("output.sample_dt_s must be > 0");
  const double t_end = output.duration_s > 0 ? output.duration_s : trajectory.endTime() + output.settle_s;
  if (output.sample_dt_s > t_end)
    throw std::invalid_argument("output.sample_dt_s = " + std::to_string(output.sample_dt_s) +
                                " s is longer than the run (" + std::to_string(t_end) +
                                " s): the time series needs at least 2 rows");
  // Checked as a double before it becomes a count (no float-to-integer overflow).
  const double rows = std::floor(t_end / output.sample_dt_s + 1e-9) + 1;
  if (!(rows <= limits::kMaxRowsPerRun))
    throw std::invalid_argument("the run (" + std::to_string(t_end) + " s / output.sample_dt_s " +
                                std::to_string(output.sample_dt_s) + " s) would write more than " +
                                std::to_string(static_cast<long>(limits::kMaxRowsPerRun)) + " rows");

  const auto wall0 = std::chrono::steady_clock::now();
  RunResult result;
  RunSummary& sum = result.summary;
  sum.model = "analytic";
  const double tail_end = trajectory.endTime();

  // Shortest acceleration or deceleration phase sets the event sampling and the step bound.
  double shortest = std::numeric_limits<double>::infinity();
  for (const auto& j : trajectory.joints)
    shortest = std::min({shortest, j.params().w_ss * j.params().dT_s, (1 - j.params().w_ss) * j.params().dT_s});
  const double h_scan = shortest / 32.0;
  const double h_max = settings.max_step_s > 0 ? settings.max_step_s : shortest / 8.0;
  const bool adaptive = settings.solver == "adaptive";

  try {
    const Model model(robot, trajectory, settings, effects);
    Recorder rec(model, robot.numLinks(), output.sample_dt_s, t_end, static_cast<long>(rows));
    // The fixed-step solver checks once per step: a slide slower than one step's friction
    // deceleration (mu_d g h) would reverse within the next step, so it counts as stopped.
    const double v_stop = adaptive ? settings.v_stop_mps
                                   : std::max(settings.v_stop_mps, robot.friction.mu_d * model.weight() /
                                                                       robot.systemMass() * settings.fixed_dt_s);
    const Events events{model, v_stop};
    Modes modes;
    State y{};
    double t = 0.0;
    int switches = 0;
    double t_stop = 0.0;
    bool ever_rotated = false;

    // Switches DOF `which` (or none, -1) at t, then settles the modes; keeps the summary counters.
    auto switchAt = [&](int which) {
      const Modes before = modes;
      if (which >= 0) {
        applySwitch(which, t, y, modes, model);
        ++switches;
      }
      switches += settleModes(t, y, modes, model, events);
      if (!before.stuck[kRot] && modes.stuck[kRot]) t_stop = t;
      if (!modes.stuck[kRot]) ever_rotated = true;
    };

    // Initially at rest: stuck wherever stiction holds (Eqs. 14-16, first cases); a load already
    // above the static limit breaks away at once.
    if (model.stiction()) {
      modes.stuck[kRot] = true;
      modes.stuck[kTrans] = model.translation();
      switchAt(-1);
    }

    auto rhs = [&](const State& x, State& dx, double tt) { model.derivative(tt, x, modes, dx); };
    std::vector<double> bps = trajectory.breakpoints();
    auto nextBreak = [&](double tt) {
      for (double b : bps)
        if (b > tt + 1e-14) return std::min(b, t_end);
      return t_end;
    };
    auto settled = [&](double tt) {  // nothing will change any more
      return tt >= tail_end && model.stiction() && modes.stuck[kRot] && (modes.stuck[kTrans] || !model.translation());
    };
    auto recordUpTo = [&](double t_hi, auto&& stateAt) {
      State ys;
      while (!rec.done() && rec.nextTime() <= t_hi + 1e-12) {
        const double ts = std::min(rec.nextTime(), t_end);
        stateAt(ts, ys);
        rec.record(ts, ys, modes);
      }
    };
    auto checkFinite = [&](const char* what) {
      if (!allFinite(y))
        throw std::runtime_error("state became non-finite at t=" + std::to_string(t) + " s: " + what);
    };

    long steps = 0;
    // Step budget: a run that needs more steps fails with this message instead of running on.
    const long max_steps = settings.max_steps;
    auto checkBudget = [&]() {
      if (steps > max_steps)
        throw std::runtime_error("step budget of " + std::to_string(max_steps) + " steps exhausted at t=" +
                                 std::to_string(t) + " s of " + std::to_string(t_end) +
                                 " s (docs/experiment-format.md \"Limits\"): loosen analytic.rel_tol/abs_tol, "
                                 "raise max_step_s or fixed_dt_s, or shorten the run");
    };
    while (t < t_end - 1e-15) {
      if (settled(t)) {
        if (!rec.done() && rec.nextTime() <= t_end + 1e-12) {  // one evaluated row at rest, then copies
          State ys = y;
          rec.record(std::min(rec.nextTime(), t_end), ys, modes);
          rec.repeatLastUntilDone();
        }
        t = t_end;
        break;
      }
      const double seg_end = nextBreak(t);
      const bool tail_moving = t < tail_end;
      if (adaptive) {
        const double max_dt = (tail_moving || modes.stuck[kRot] || modes.stuck[kTrans]) ? h_max : (t_end - t);
        auto stepper = odeint::make_dense_output(settings.abs_tol, settings.rel_tol, max_dt,
                                                 odeint::runge_kutta_dopri5<State>());
        stepper.initialize(y, t, std::min(max_dt, 1e-4));
        bool restart = false;
        while (!restart) {
          const auto [ta, tb_raw] = stepper.do_step(rhs);
          ++steps;
          checkBudget();
          const double tb = std::min(tb_raw, seg_end);
          auto stateAt = [&](double tt, State& ys) { stepper.calc_state(tt, ys); };
          Found f;
          if (model.stiction()) f = findSwitch(events, modes, ta, tb, h_scan, settings.event_tol_s, stateAt);
          const double t_cut = f.hit ? f.t : tb;
          recordUpTo(t_cut, stateAt);
          stepper.calc_state(t_cut, y);
          t = t_cut;
          checkFinite(("tighten analytic.rel_tol (" + std::to_string(settings.rel_tol) + ")").c_str());
          if (f.hit) {
            switchAt(f.which);
            restart = true;
          } else if (tb_raw >= seg_end - 1e-15) {
            restart = true;  // a breakpoint of the tail profile: restart the step there
          }
          if (t >= t_end - 1e-15 || settled(t)) restart = true;
          if (!restart && stepper.current_time() > t + 1e-15) {
            // The solver's internal state may lie beyond t (when tb was clipped): continue from t.
            restart = true;
          }
        }
      } else {
        // Fixed-step classic RK4; switches checked once per step, the way a fixed-step Simulink
        // model with a zero-crossing reset would: a margin at or below zero at the step's end
        // switches (for a slide, g < 0 means it stopped somewhere inside the step). The slip
        // direction is the mode's, fixed over the step's four stages, so a rotation that stops
        // inside a step overshoots zero and is caught, instead of its stages averaging the
        // Coulomb sign away into an endless creep.
        odeint::runge_kutta4<State> rk4;
        const double h = std::min(settings.fixed_dt_s, seg_end - t);
        const State y0 = y;
        rk4.do_step(rhs, y, t, h);
        ++steps;
        checkBudget();
        const double t1 = t + h;
        const State y1 = y;
        auto lerp = [&](double tt, State& ys) {
          const double a = (tt - t) / h;
          for (int i = 0; i < 6; ++i) ys[i] = y0[i] + a * (y1[i] - y0[i]);
        };
        recordUpTo(t1 - 1e-13, lerp);
        t = t1;
        checkFinite(("analytic.fixed_dt_s=" + std::to_string(settings.fixed_dt_s) + " is too large").c_str());
        if (model.stiction()) {
          // A 2-D slide whose velocity turned by more than 90 deg over the step stopped inside it.
          const bool reversed = model.translation() && !modes.stuck[kTrans] &&
                                y0[kVx] * y[kVx] + y0[kVy] * y[kVy] < 0;
          if (reversed) {
            Modes probe = modes;
            probe.stuck[kTrans] = true;
            const Eval e = model.evaluate(t, y, probe);
            if (e.F_required.norm() < e.F_break) switchAt(kTrans);
          }
          switchAt(-1);
        }
        recordUpTo(t, [&](double, State& ys) { ys = y; });
      }
    }

    result.series = rec.take();
    // Summaries from the simulated state at t_end, not from the sampled rows (phi(0) = 0).
    sum.phi_net_deg = y[kPhi] * 180.0 / M_PI;
    const bool still = !model.stiction() || !modes.stuck[kRot];
    sum.t_stop_s = still ? t_end : t_stop;
    sum.stick_slip_events = switches;
    sum.solver_steps = steps;
    sum.extra["final_x_m"] = y[kX];
    sum.extra["final_y_m"] = y[kY];
    sum.extra["final_phidot_dps"] = y[kPhiDot] * 180.0 / M_PI;
    sum.extra["final_speed_mps"] = std::hypot(y[kVx], y[kVy]);
    sum.extra["still_rotating_at_end"] = still && std::abs(y[kPhiDot]) > 0 ? 1.0 : 0.0;
    sum.extra["ever_rotated"] = ever_rotated || !model.stiction() ? 1.0 : 0.0;
    // At rest: both DOFs stuck (stiction), or rate and speed below the documented thresholds.
    const bool stuck_all = model.stiction() && modes.stuck[kRot] && (modes.stuck[kTrans] || !model.translation());
    const double phidot_dps = std::abs(y[kPhiDot]) * 180.0 / M_PI, speed = std::hypot(y[kVx], y[kVy]);
    sum.at_rest = stuck_all || (phidot_dps < limits::kAtRestPhidotDps && speed < limits::kAtRestSpeedMps);
    if (!sum.at_rest) sum.warnings.push_back(notAtRestWarning(t_end, phidot_dps, speed));
    if (settings.coupling == Coupling::kPaper) {
      // The turn the paper coupling's residual spin alone would cause before sliding friction
      // (deceleration mu_d m g L_F / I_zz at the final pose) stops it: w^2 / (2 alpha).
      const double w_res = paperResidualSpin(robot, trajectory);
      const Eval ev_end = model.evaluate(t_end, y, modes);
      const double alpha = needsFrictionArm(model) && std::isfinite(ev_end.L_F)
                               ? robot.friction.mu_d * model.weight() * ev_end.L_F / ev_end.loads.Izz_kgm2
                               : 0.0;
      const double turn_deg = w_res == 0.0 ? 0.0 : alpha > 0 ? w_res * w_res / (2.0 * alpha) * 180.0 / M_PI
                                                            : std::numeric_limits<double>::infinity();
      sum.extra["paper_residual_spin_dps"] = w_res * 180.0 / M_PI;
      sum.extra["paper_spurious_turn_deg"] = turn_deg;
      if (!(turn_deg <= limits::kMaxPaperSpuriousTurnDeg)) {
        std::ostringstream os;
        os.precision(3);
        os << "the paper coupling's angular-momentum error is large: with mu = 0 it would leave the body spinning at "
           << w_res * 180.0 / M_PI << " deg/s after the tail stops (the exact coupling: 0), enough to turn it by "
           << turn_deg << " deg against sliding friction (limit " << limits::kMaxPaperSpuriousTurnDeg
           << " deg); the paper's model is outside its validity here, compare analytic.coupling: exact";
        sum.warnings.push_back(os.str());
      }
    }
  } catch (const TippingError& e) {
    sum.ok = false;
    sum.error = e.what();
  } catch (const std::runtime_error& e) {
    sum.ok = false;
    sum.error = std::string("analytic model failed: ") + e.what();
  }
  sum.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return result;
}

RunResult evaluatePose(const RobotParams& robot, const std::vector<JointState>& joints, const Effects& effects) {
  RunResult r;
  r.summary.model = "analytic";
  const auto wall0 = std::chrono::steady_clock::now();
  TimeSeries& ts = r.series;
  const int n = robot.numLinks();
  std::vector<double> row;
  for (int i = 1; i <= n; ++i) ts.addColumn("theta" + std::to_string(i) + "_deg");
  for (int i = 1; i <= n; ++i) ts.addColumn("thetadot" + std::to_string(i) + "_dps");
  for (int i = 1; i <= n; ++i) ts.addColumn("thetaddot" + std::to_string(i) + "_dps2");
  const double d = 180.0 / M_PI;
  for (const auto& j : joints) row.push_back(j.theta * d);
  for (const auto& j : joints) row.push_back(j.theta_dot * d);
  for (const auto& j : joints) row.push_back(j.theta_ddot * d);
  const SystemLoads s = systemLoads(robot, joints, true);
  double LF = kNaN;
  std::array<double, 4> f{kNaN, kNaN, kNaN, kNaN};
  try {
    const FootLoads fl = footLoads(robot.quadruped, s.p_QC);
    LF = fl.L_F;
    f = fl.f_C;
  } catch (const TippingError& e) {
    r.summary.ok = false;
    r.summary.error = e.what();
  }
  const std::vector<std::pair<const char*, double>> cols = {
      {"MzT_Nm", s.MzT}, {"MzT_acc_Nm", s.MzT_acc}, {"MzT_speed_Nm", s.MzT_speed}, {"MzT_tan_Nm", s.MzT_tan},
      {"MzT_cen_Nm", s.MzT_cen}, {"MzT_tan_over_Izz_radps2", s.MzT_tan / s.Izz_kgm2},
      {"MzT_cen_over_Izz_radps2", s.MzT_cen / s.Izz_kgm2}, {"Izz_kgm2", s.Izz_kgm2}, {"mass_kg", s.mass_kg},
      {"comx_m", s.p_QC.x()}, {"comy_m", s.p_QC.y()}, {"FTx_N", s.F_T_Q.x()}, {"FTy_N", s.F_T_Q.y()}, {"LF_m", LF},
      {"fC1", f[0]}, {"fC2", f[1]}, {"fC3", f[2]}, {"fC4", f[3]}};
  for (const auto& [name, v] : cols) {
    ts.addColumn(name);
    row.push_back(v);
  }
  ts.appendRow(row);
  (void)effects;
  r.summary.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return r;
}

}  // namespace tailsim
