#include "models/analytic/analytic_model.h"

#include <Eigen/Dense>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "models/planar/foot_loads.h"
#include "numerics/sin_cos.h"

namespace tailsim {

AnalyticModel::AnalyticModel(const RobotParams& r, const TailTrajectory& tr, const AnalyticSettings& s,
                             const Effects& e)
    : robot(r), traj(tr), settings(s), effects(e) {
  weight = r.systemMass() * (e.gravity ? r.gravity_mps2 : 0.0);
  mu_break = breakawayCoefficient(r.friction);
  // The fixed-step solver keeps plain Coulomb friction in translation (its per-step stop check
  // ends a slide); the adaptive one regularizes inside |v| < v_stop (see slidingFriction()).
  v_reg = s.solver == AnalyticSolver::kFixed ? 0.0 : s.v_stop_mps;
  if (e.foot_loads == FootLoadModel::kConstant && needsArm()) {
    std::vector<JointState> j0;
    traj.evaluate(0.0, j0);
    SystemLoads sl;
    systemMassProperties(robot, tailKinematics(robot.tail, j0), sl);
    L_F_const = footLoads(robot.quadruped, sl.p_QC).L_F;
  }
}

namespace {

// Tail loads, mass properties and the friction arm at the joint states w.joints, into `loads`
// and `L_F` (NaN without friction). Without `decompose` the decomposition's fields are zero.
void tailLoadsAndArm(const AnalyticModel& m, AnalyticWorkspace& w, double t, bool decompose, SystemLoads& loads,
                     double& L_F) {
  const std::vector<JointState>& js = w.joints;
  systemLoads(m.robot, js, decompose, loads, w.loads);
  if (!decompose) loads.MzT_acc = loads.MzT_speed = loads.MzT_tan = loads.MzT_cen = 0.0;
  if (!std::isfinite(loads.MzT) || !std::isfinite(loads.F_T_Q.x()) || !std::isfinite(loads.F_T_Q.y()) ||
      !std::isfinite(loads.Izz_kgm2) || !std::isfinite(js.empty() ? 0.0 : js.front().theta))
    throw std::runtime_error("the tail loads became non-finite at t=" + std::to_string(t) +
                             " s (M_z,T = " + std::to_string(loads.MzT) + " N m): check the trajectory values");
  L_F = !m.needsArm() ? std::numeric_limits<double>::quiet_NaN()
        : m.effects.foot_loads == FootLoadModel::kConstant ? m.L_F_const
                                                           : frictionArm(m.robot.quadruped, loads.p_QC);
}

// The tail's loads and friction arm at t, from the cache when it holds them (it does afterwards).
// w.joints are then those at t: the same time, or both times after the tail's motion.
[[gnu::always_inline]] inline const AnalyticWorkspace::TailCache& tailAt(const AnalyticModel& m, AnalyticWorkspace& w, double t, bool decompose) {
  AnalyticWorkspace::TailCache& c = w.tail_cache;
  if (c.valid && (c.t == t || (c.finished && m.traj.finished(t))) && (c.decomposed || !decompose)) return c;
  c.valid = false;  // until tailLoadsAndArm returns (it throws when the robot tips)
  m.traj.evaluate(t, w.joints);
  tailLoadsAndArm(m, w, t, decompose, c.loads, c.L_F);
  c.valid = true;
  c.decomposed = decompose;
  c.finished = m.traj.finished(t);
  c.t = t;
  return c;
}

// rotate(phi, a) with cos and sin of phi from w.yaw when phi is the same (bit for bit) as last time.
[[gnu::always_inline]] inline Vec2 rotateYaw(AnalyticWorkspace& w, double phi, const Vec2& a) {
  AnalyticWorkspace::YawCache& yc = w.yaw;
  if (!yc.valid || std::memcmp(&yc.phi, &phi, sizeof phi) != 0) {
    const SinCos sc = sinCos(phi);
    yc.c = sc.c;
    yc.s = sc.s;
    yc.phi = phi;
    yc.valid = true;
  }
  return rotate(yc.c, yc.s, a);
}

// paper-notes point 3: the planar multibody with the base moving. Newton-Euler of every body
// (quadruped + links) summed: linear momentum, and angular momentum about the quadruped COM.
// Friction: F_F acts at the system COM (no moment about it, as in Eq. 9) plus the pure M_z,F.
void exactCoupling(const AnalyticModel& m, AnalyticWorkspace& w, double phi, double phi_dot, const SystemLoads& loads,
                   Eigen::Matrix3d& A, Eigen::Matrix3d& E, Eigen::Vector3d& r0) {
  const RobotParams& robot = m.robot;
  // The kinematics systemLoads computed from w.joints for ev.loads (the same joint states: both
  // are refreshed together whenever the tail cache misses).
  const TailKinematics& kin = w.loads.kin;
  const double wz = phi_dot;
  const Vec2 p_QB(-robot.quadruped.d_Q2B_m, 0.0);
  Vec2 S = Vec2::Zero(), lin = Vec2::Zero();
  double J = robot.quadruped.izz_kgm2, ang = 0.0;
  const SinCos R = sinCos(phi);  // one rotation by phi for every link
  for (size_t i = 0; i < robot.tail.size(); ++i) {
    const TailLink& l = robot.tail[i];
    // Link COM relative to the quadruped COM, in Q, and its rates (R_Z(180 deg) flips B).
    const Vec2 rho = rotate(R.c, R.s, Vec2(p_QB - kin.p_L[i]));
    const Vec2 rho_dot_rel = rotate(R.c, R.s, Vec2(-kin.v_L[i]));
    const Vec2 rho_ddot_rel = rotate(R.c, R.s, Vec2(-kin.a_L[i]));
    const Vec2 b = -wz * wz * rho + 2.0 * wz * perp(rho_dot_rel) + rho_ddot_rel;  // a_i - a_Q - phi_ddot z x rho
    S += l.mass_kg * rho;
    J += l.izz_kgm2 + l.mass_kg * rho.squaredNorm();
    lin += l.mass_kg * b;
    ang += l.mass_kg * cross2(rho, b) + l.izz_kgm2 * kin.alpha[i];
  }
  const double mass = loads.mass_kg;
  A << mass, 0, -S.y(), 0, mass, S.x(), -S.y(), S.x(), J;
  r0 << -lin.x(), -lin.y(), -ang;
  const Vec2 c = S / mass;  // system COM relative to the quadruped COM, world
  E.setIdentity();
  E(2, 0) = -c.y();
  E(2, 1) = c.x();
}

// Unpacks the solve: accelerations of the sliding DOFs, friction loads of the stuck ones.
[[gnu::always_inline]] inline void unpackSolve(const AnalyticModel& m, const bool free_dof[3], const double u[3], const SlidingFriction& f, Motion& ev) {
  ev.a_Q = Vec2(free_dof[0] ? u[0] : 0.0, free_dof[1] ? u[1] : 0.0);
  ev.phi_ddot = free_dof[2] ? u[2] : 0.0;
  ev.FF_W = free_dof[0] ? f.FF : Vec2(u[0], u[1]);
  ev.MzF = free_dof[2] ? f.MzF : u[2];
  ev.F_required = free_dof[0] ? Vec2::Zero() : Vec2(u[0], u[1]);
  ev.M_required = free_dof[2] ? 0.0 : u[2];
  if (!m.translation()) ev.FF_W = Vec2::Zero();  // locked, not friction: no friction force reported
}

// Equations of motion  A z = r0 + E f,  z = (a_Qx, a_Qy, phi_ddot), f = (F_Fx, F_Fy, M_zF): the
// accelerations of the sliding DOFs and the friction loads of the stuck ones.
[[gnu::always_inline]] inline void solveMotion(const AnalyticModel& m, AnalyticWorkspace& w, const State& y, const Modes& modes,
                 const SlidingFriction& f, const SystemLoads& loads, Motion& ev) {
  const bool free_dof[3] = {m.translation() && !modes.stuck[kTrans], m.translation() && !modes.stuck[kTrans],
                            !modes.stuck[kRot]};
  const double f_known[3] = {f.FF.x(), f.FF.y(), f.MzF};
  if (m.settings.coupling == Coupling::kPaper) {
    // Eq. (9): m a = F_T + F_F, I_zz phi_ddot = M_z,T + M_z,F; diagonal: each DOF on its own.
    const double A[3] = {loads.mass_kg, loads.mass_kg, loads.Izz_kgm2};
    const double r0[3] = {ev.FT_W.x(), ev.FT_W.y(), loads.MzT};
    double u[3];
    for (int j = 0; j < 3; ++j) u[j] = free_dof[j] ? (r0[j] + f_known[j]) / A[j] : -r0[j];
    unpackSolve(m, free_dof, u, f, ev);
    return;
  }
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero(), E = Eigen::Matrix3d::Identity();
  Eigen::Vector3d r0;
  exactCoupling(m, w, y[kPhi], y[kPhiDot], loads, A, E, r0);
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
  unpackSolve(m, free_dof, u, f, ev);
}

// The motion at (t, y) in modes `modes` caused by the tail's loads and arm c (tailAt at t).
[[gnu::always_inline]] inline void motionAt(const AnalyticModel& m, AnalyticWorkspace& w, const AnalyticWorkspace::TailCache& c, const State& y,
              const Modes& modes, Motion& ev) {
  ev.FT_W = rotateYaw(w, y[kPhi], c.loads.F_T_Q);
  ev.M_break = m.mu_break * m.weight * (m.needsArm() ? c.L_F : 0.0);
  ev.F_break = m.mu_break * m.weight;
  // Friction loads of the DOFs that slide (known); stuck DOFs get theirs from the solve.
  const SlidingFriction f = m.needsArm() ? slidingFriction(m.effects.friction, m.robot.friction, m.weight, c.L_F,
                                                           modes.rot_dir, y[kPhiDot], y[kVx], y[kVy], m.v_reg)
                                         : SlidingFriction{};
  solveMotion(m, w, y, modes, f, c.loads, ev);
}

}  // namespace

Eval evaluate(const AnalyticModel& m, AnalyticWorkspace& w, double t, const State& y, const Modes& modes,
              bool decompose) {
  Eval ev;
  const AnalyticWorkspace::TailCache& c = tailAt(m, w, t, decompose);
  ev.loads = c.loads;
  ev.L_F = c.L_F;
  motionAt(m, w, c, y, modes, ev);
  return ev;
}

void derivative(const AnalyticModel& m, AnalyticWorkspace& w, double t, const State& y, const Modes& modes, State& dy) {
  Motion ev;  // evaluate() without the copy of the loads
  motionAt(m, w, tailAt(m, w, t, false), y, modes, ev);
  dy[kPhi] = modes.stuck[kRot] ? 0.0 : y[kPhiDot];
  dy[kPhiDot] = ev.phi_ddot;
  const bool moving = m.translation() && !modes.stuck[kTrans];
  dy[kX] = moving ? y[kVx] : 0.0;
  dy[kY] = moving ? y[kVy] : 0.0;
  dy[kVx] = ev.a_Q.x();
  dy[kVy] = ev.a_Q.y();
}

Margins eventMargins(const AnalyticModel& m, AnalyticWorkspace& w, double v_stop, double t, const State& y,
                     const Modes& modes) {
  Margins out{1.0, 1.0};
  const bool trans = m.translation();
  Motion ev;
  if (modes.stuck[kRot] || (trans && modes.stuck[kTrans])) motionAt(m, w, tailAt(m, w, t, false), y, modes, ev);
  out[kRot] = modes.stuck[kRot] ? ev.M_break - std::abs(ev.M_required) : modes.rot_dir * y[kPhiDot];
  if (!trans) return out;
  if (modes.stuck[kTrans]) {
    out[kTrans] = ev.F_break - ev.F_required.norm();
    return out;
  }
  const double fast = std::sqrt(y[kVx] * y[kVx] + y[kVy] * y[kVy]) - v_stop;  // m/s: no overflow to guard
  if (fast > 0) {
    out[kTrans] = fast;  // same sign as the max below, without the probe's evaluation
  } else {
    Modes probe = modes;
    probe.stuck[kTrans] = true;
    Motion pe;
    motionAt(m, w, tailAt(m, w, t, false), y, probe, pe);
    out[kTrans] = std::max(fast, pe.F_required.norm() - pe.F_break);
  }
  return out;
}

void applySwitch(const AnalyticModel& m, AnalyticWorkspace& w, int which, double t, State& y, Modes& modes) {
  if (which == kRot) {
    if (!modes.stuck[kRot]) {  // stopped sliding: stick, unless the load exceeds the static limit
      y[kPhiDot] = 0.0;
      Modes probe = modes;
      probe.stuck[kRot] = true;
      const Eval e = evaluate(m, w, t, y, probe);
      if (std::abs(e.M_required) < e.M_break) {
        modes.stuck[kRot] = true;
      } else {  // turns straight round: slide the other way (Eq. 16, second case)
        modes.rot_dir = e.M_required < 0 ? 1.0 : -1.0;  // friction opposes the load: load = -required
      }
    } else {  // breakaway (Eq. 16, second case): slide in the load's direction
      const Eval e = evaluate(m, w, t, y, modes);
      modes.stuck[kRot] = false;
      modes.rot_dir = e.M_required < 0 ? 1.0 : -1.0;
    }
  } else {
    // Stop (below v_stop with the load under the static limit) or breakaway (Eq. 15, second
    // case: the regularized friction lets it accelerate along the load).
    if (!modes.stuck[kTrans]) y[kVx] = y[kVy] = 0.0;
    modes.stuck[kTrans] = !modes.stuck[kTrans];
  }
}

int settleModes(const AnalyticModel& m, AnalyticWorkspace& w, double v_stop, double t, State& y, Modes& modes) {
  if (!m.stiction()) return 0;
  for (int n = 0;; ++n) {
    if (n > 8)
      throw std::runtime_error("stick/slip modes do not settle at t=" + std::to_string(t) +
                               " s (each switch undoes the other)");
    const int which = dofToSwitch(modes, eventMargins(m, w, v_stop, t, y, modes), m.translation());
    if (which < 0) return n;
    applySwitch(m, w, which, t, y, modes);
  }
}

}  // namespace tailsim
