// The per-foot friction model in time (per_foot_model.h; docs/per-foot-model.md).
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "models/analytic/analytic_simulation.h"
#include "models/planar/at_rest.h"
#include "models/perfoot/per_foot_model.h"
#include "models/planar/row_columns.h"
#include "models/planar/stick_slip_driver.h"
#include "models/planar/stick_slip.h"
#include "models/planar/support_check.h"
#include "results/columns.h"
#include "robot/friction_law.h"
#include "common/units.h"

namespace tailsim {
namespace {

// State: x, y (quadruped COM, world), phi, and their rates.
using State = std::array<double, 6>;
enum { kX = 0, kY, kPhi, kVx, kVy, kW };
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Everything the model computes at one instant.
struct Eval {
  SystemLoads loads;
  Vec2 FT_W = Vec2::Zero();
  Vec2 c_W = Vec2::Zero();            // system COM relative to the quadruped COM, world
  FootDiscs discs;                    // feet relative to the system COM (world), c_i = mu N_i
  std::array<double, 4> N{};          // normal loads  [N]
  std::array<Vec2, 4> Ff = zeros4();   // per-foot friction, world  [N]
  Wrench2 friction;                   // their sum, moment about the system COM
  double L_F = kNaN;                  // the paper's arm at the system COM (Eq. 19), for comparison
  double load_factor = kNaN;          // stuck: s of the required wrench (held iff s <= 1)
  Vec2 a_Q = Vec2::Zero();
  double phi_ddot = 0.0;
  // Load transfer: the centre of pressure relative to the foot centroid (in Q) and its support
  // margin, the distance to the nearest edge of the rectangle footLoads accepts (>= 0 standing).
  Vec2 cop_CC = Vec2::Zero();
  double support = std::numeric_limits<double>::infinity();
};

class Model {
 public:
  Model(const RobotParams& r, const TailTrajectory& tr, const PerFootSettings& s, const Effects& e,
        const PrescribedNormalLoads* loads, double t_end = std::numeric_limits<double>::infinity())
      : robot_(r), traj_(tr), s_(s), e_(e), prescribed_(loads) {
    weight_ = r.systemMass() * (e.gravity ? r.gravity_mps2 : 0.0);
    mu_break_ = breakawayCoefficient(r.friction);
    const QuadrupedParams& q = r.quadruped;
    if (s.normal_loads == NormalLoadModel::kLoadTransfer && hasFriction() && !loads &&
        e.foot_loads != FootLoadModel::kConstant) {
      // The summed friction is at most max(mu_s, mu_d) m g (sliding: mu_d or the ADAMS mu, at most
      // the larger; held: capped at mu_break m g), so the centre of pressure lies within
      // h max(mu_s, mu_d) of the system COM. If the system COM keeps that far inside every edge
      // over the whole stroke (the pre-run search on the rectangle shrunk by it), the robot cannot
      // tip and nothing is scanned; otherwise the support margin is scanned along the solution.
      shift_max_ = q.com_height_m * std::max(r.friction.mu_s, r.friction.mu_d) * (1.0 + 1e-9);
      RobotParams shrunk = r;
      shrunk.quadruped.l_F_m -= 2.0 * shift_max_;
      shrunk.quadruped.w_F_m -= 2.0 * shift_max_;
      scan_support_ = !(shrunk.quadruped.l_F_m > 0 && shrunk.quadruped.w_F_m > 0) ||
                      firstSupportLoss(shrunk, tr, t_end).has_value();
    }
    static const double kXs[4] = {0.5, 0.5, -0.5, -0.5}, kYs[4] = {0.5, -0.5, -0.5, 0.5};
    for (int i = 0; i < 4; ++i) foot_Q_[i] = Vec2(q.d_Q2C_m + kXs[i] * q.l_F_m, kYs[i] * q.w_F_m);
    if (e.foot_loads == FootLoadModel::kConstant && hasFriction()) {
      std::vector<JointState> j0;
      traj_.evaluate(0.0, j0);
      SystemLoads sl;
      systemMassProperties(robot_, tailKinematics(robot_.tail, j0), sl);
      fC_const_ = footLoads(q, sl.p_QC).f_C;
    }
  }

  bool hasFriction() const { return e_.friction != FrictionLaw::kNone && weight_ > 0.0; }
  bool stiction() const { return e_.friction == FrictionLaw::kStiction && weight_ > 0.0 && mu_break_ > 0.0; }
  bool translation() const { return e_.translation; }
  double weight() const { return weight_; }
  const Effects& effects() const { return e_; }
  // loadTransferNewton calls are counted into *counter (it outlives the Model: a failed run reports it too).
  void countNewtonSolvesInto(long* counter) const { newton_counter_ = counter; }
  // The stick/slip scan's loadFactor calls (the held wrench's load factor, most of a held run's
  // cost) are counted into *counter; of them, those that ran loadFactor's start scan (near
  // breakaway, or no warm start yet) into *start_scans. Rows' calls are not counted (heldLoadFactor).
  void countLoadFactorsInto(long* counter, long* start_scans) const {
    load_factor_counter_ = counter;
    start_scan_counter_ = start_scans;
  }
  // Whether the load transfer's support margin must be scanned (see the constructor), and the
  // largest shift of the centre of pressure (h max(mu_s, mu_d))  [m].
  bool scansSupport() const { return scan_support_; }
  double shiftMax() const { return shift_max_; }
  void joints(double t, std::vector<JointState>& js) const { traj_.evaluate(t, js); }

  // stuck: the body is held (twist zero); the friction is the wrench that holds it and
  // load_factor says whether the discs can supply it (warm: warm-started, heldLoadFactor; else
  // from loadFactor's start scan). Otherwise per-foot sliding friction.
  // Stages: the tail's loads and the coupling, then held (pinned or free) or sliding.
  Eval evaluate(double t, const State& y, bool stuck, bool decompose = false, bool warm = false) const {
    Eval ev;
    Eigen::Matrix3d A;
    Eigen::Vector3d r0;
    const double phi = y[kPhi], w = stuck ? 0.0 : y[kW];
    const SinCos R = sinCos(phi);  // one rotation by phi, used below
    bodyAndTail(t, phi, w, R, decompose, ev, A, r0);
    if (stuck) {
      if (!translation())
        holdPinned(ev, t, phi, r0);
      else
        holdFree(ev, t, phi, r0, warm);
      return ev;
    }
    const std::array<Vec2, 4> dir = slidingDirections(y, w, R);
    slidingNormalLoads(ev, t, phi, dir);
    slidingAccelerations(ev, dir, A, r0);
    return ev;
  }

  // Fastest foot's slip speed at state y.
  double maxFootSpeed(const State& y) const {
    const Vec2 vQ = translation() ? Vec2(y[kVx], y[kVy]) : Vec2::Zero();
    const SinCos R = sinCos(y[kPhi]);
    double m = 0.0;
    for (int i = 0; i < 4; ++i) m = std::max(m, (vQ + y[kW] * perp(rotate(R.c, R.s, foot_Q_[i]))).norm());
    return m;
  }

  void derivative(double t, const State& y, State& dy) const {
    const Eval ev = evaluate(t, y, false);
    const bool tr = translation();
    dy[kX] = tr ? y[kVx] : 0.0;
    dy[kY] = tr ? y[kVy] : 0.0;
    dy[kPhi] = y[kW];
    dy[kVx] = ev.a_Q.x();
    dy[kVy] = ev.a_Q.y();
    dy[kW] = ev.phi_ddot;
  }

 private:
  // The tail's loads at t, the coupling A z = r0 + E f at (phi, w), the feet relative to the
  // system COM and the paper's arm L_F.
  void bodyAndTail(double t, double phi, double w, const SinCos& R, bool decompose, Eval& ev, Eigen::Matrix3d& A,
                   Eigen::Vector3d& r0) const {
    std::vector<JointState>& js = js_;
    traj_.evaluate(t, js);
    systemLoads(robot_, js, decompose, ev.loads, scratch_);
    if (!std::isfinite(ev.loads.MzT) || !std::isfinite(ev.loads.Izz_kgm2))
      throw std::runtime_error("the tail loads became non-finite at t=" + std::to_string(t) + " s");
    ev.FT_W = rotate(R.c, R.s, ev.loads.F_T_Q);
    exactCoupling(js, phi, w, ev, A, r0);
    for (int i = 0; i < 4; ++i) ev.discs.r[i] = rotate(R.c, R.s, foot_Q_[i]) - ev.c_W;
    if (hasFriction()) ev.L_F = footLoads(robot_.quadruped, ev.loads.p_QC).L_F;
  }

  // Held with x, y locked: a pin at the quadruped COM takes any force; the feet must supply the
  // moment about it, -r0_z, at most sum c_i |rho_i| (every foot tangential).
  void holdPinned(Eval& ev, double t, double phi, const Eigen::Vector3d& r0) const {
    normalLoads(ev, t, phi, Vec2::Zero());
    double D = 0.0;
    for (int i = 0; i < 4; ++i) {
      ev.discs.c[i] = mu_break_ * ev.N[i];
      D += ev.discs.c[i] * (ev.discs.r[i] + ev.c_W).norm();
    }
    const double MQ = -r0[2];
    ev.load_factor = D > 0 ? std::abs(MQ) / D : (MQ == 0 ? 0.0 : std::numeric_limits<double>::infinity());
    for (int i = 0; i < 4; ++i) {
      const Vec2 rho = ev.discs.r[i] + ev.c_W;
      if (D > 0 && rho.norm() > 0) ev.Ff[i] = MQ / D * ev.discs.c[i] * perp(rho) / rho.norm();
      ev.friction.M += cross2(ev.discs.r[i], ev.Ff[i]);
    }
  }

  // Held and free to translate: z = 0 in A z = r0 + E f, f = -E^-1 r0 (E: identity, plus c x F in
  // the moment row), the wrench the feet must supply. Load transfer: a held body's friction is at
  // most mu W (s >= |F| / (mu W) > 1 beyond, the loads cannot hold it anyway); the centre of
  // pressure takes the force capped there, so a probe of a fast slide's holding wrench neither
  // tips nor jumps.
  void holdFree(Eval& ev, double t, double phi, const Eigen::Vector3d& r0, bool warm) const {
    Wrench2 req;
    req.F = -Vec2(r0[0], r0[1]);
    req.M = -r0[2] - cross2(ev.c_W, req.F);
    const double F_cap = mu_break_ * weight_;
    const double Fn = req.F.norm();
    normalLoads(ev, t, phi, Fn > F_cap ? Vec2(req.F * (F_cap / Fn)) : req.F);
    for (int i = 0; i < 4; ++i) ev.discs.c[i] = mu_break_ * ev.N[i];
    ev.load_factor = heldLoadFactor(ev.discs, req, warm);
    ev.Ff = heldFootForces(ev.discs, req);
    ev.friction = req;
  }

  // Sliding: foot i's friction per unit normal load, F_i = N_i dir_i, dir_i = -mu_i v_i / |v_i|
  // (regularized below v_stop for stiction).
  std::array<Vec2, 4> slidingDirections(const State& y, double w, const SinCos& R) const {
    const Vec2 vQ = translation() ? Vec2(y[kVx], y[kVy]) : Vec2::Zero();
    std::array<Vec2, 4> dir = zeros4();
    const FrictionParams& fp = robot_.friction;
    if (hasFriction()) {
      for (int i = 0; i < 4; ++i) {
        const Vec2 vi = vQ + w * perp(rotate(R.c, R.s, foot_Q_[i]));
        const double sp = vi.norm();
        if (e_.friction == FrictionLaw::kStiction) {
          dir[i] = -fp.mu_d * vi / std::max(sp, s_.v_stop_mps);
        } else if (sp > 0.0) {
          dir[i] = -adamsFrictionCoefficient(sp, fp.v_s_mps, fp.v_d_mps, fp.mu_s, fp.mu_d) * vi / sp;
        }
      }
    }
    return dir;
  }

  // The sliding body's normal loads. Load transfer: N depends on the summed friction, which
  // depends on N: fixed point (a contraction of factor ~ mu h / l_F), else loadTransferNewton.
  void slidingNormalLoads(Eval& ev, double t, double phi, const std::array<Vec2, 4>& dir) const {
    Vec2 F = Vec2::Zero();
    normalLoads(ev, t, phi, F);
    if (s_.normal_loads == NormalLoadModel::kLoadTransfer && hasFriction() && !prescribed_) {
      bool converged = false;
      for (int it = 0; it <= 201 && !converged; ++it) {  // (the 202 iterations it always had)
        F.setZero();
        for (int i = 0; i < 4; ++i) F += ev.N[i] * dir[i];
        const std::array<double, 4> N_old = ev.N;
        normalLoads(ev, t, phi, F);
        double change = 0.0;
        for (int i = 0; i < 4; ++i) change = std::max(change, std::abs(ev.N[i] - N_old[i]));
        converged = change <= 1e-13 * weight_;
      }
      if (!converged) loadTransferNewton(ev, t, phi, dir, F);
    }
  }

  // The sliding feet's friction and its wrench about the system COM, and the accelerations from
  // A z = r0 + E f (x, y locked: the lock takes the force, rotation alone, A(2,2) w_dot = r0_2 + M_Q).
  void slidingAccelerations(Eval& ev, const std::array<Vec2, 4>& dir, const Eigen::Matrix3d& A,
                            const Eigen::Vector3d& r0) const {
    const double mu_d = robot_.friction.mu_d;
    for (int i = 0; i < 4; ++i) {
      ev.discs.c[i] = (e_.friction == FrictionLaw::kStiction ? mu_d : 0.0) * ev.N[i];
      ev.Ff[i] = ev.N[i] * dir[i];
      ev.friction.F += ev.Ff[i];
      ev.friction.M += cross2(ev.discs.r[i], ev.Ff[i]);
    }
    if (!translation()) {
      const double MQ = ev.friction.M + cross2(ev.c_W, ev.friction.F);
      ev.phi_ddot = (r0[2] + MQ) / A(2, 2);
      ev.friction.F.setZero();
      return;
    }
    Eigen::Vector3d rhs = r0;
    rhs[0] += ev.friction.F.x();
    rhs[1] += ev.friction.F.y();
    rhs[2] += ev.friction.M + cross2(ev.c_W, ev.friction.F);
    const Eigen::Vector3d z = A.ldlt().solve(rhs);
    ev.a_Q = Vec2(z[0], z[1]);
    ev.phi_ddot = z[2];
  }

  // Normal loads from the Appendix distribution at the system COM, or (load transfer) at the
  // centre of pressure shifted by -h F / W. Quasi-static: throws TippingError outside the support
  // rectangle (never after requireSupport). Load transfer: ev.support is the centre of pressure's
  // margin; outside, the loads are those of the nearest point of the rectangle (defined, so trial
  // stages and probes do not throw): the run's scan of ev.support decides whether it tips.
  void normalLoads(Eval& ev, double t, double phi, const Vec2& F_W) const {
    if (!hasFriction()) {
      ev.N.fill(0.0);
      return;
    }
    if (prescribed_) {
      ev.N = prescribed_->at(t);
      return;
    }
    std::array<double, 4> f;
    if (e_.foot_loads == FootLoadModel::kConstant) {
      f = fC_const_;
    } else {
      const QuadrupedParams& q = robot_.quadruped;
      Vec2 p = ev.loads.p_QC;
      if (s_.normal_loads == NormalLoadModel::kLoadTransfer) p += rotate(-phi, Vec2(-q.com_height_m * F_W / weight_));
      if (scan_support_) {  // (otherwise ruled out before the run: never outside)
        Vec2 c = comFromFootCentroid(q, p);
        ev.cop_CC = c;
        ev.support = supportMargin(q, c);  // footLoads' own test
        // Outside: the nearest point of the rectangle footLoads accepts (its edges plus
        // supportSlack), so the loads stay continuous across ev.support = 0. (Clamped to the bare
        // edges they jumped there by ~1e-10 m of the centre of pressure, and a load-transfer fixed
        // point on an edge cycled across the jump.) The loads are taken at c itself: turning it
        // back into p and subtracting d_Q2C again could land 1 ulp outside and throw.
        if (ev.support < 0) {
          const double hx = 0.5 * q.l_F_m + supportSlack(q), hy = 0.5 * q.w_F_m + supportSlack(q);
          c = Vec2(std::clamp(c.x(), -hx, hx), std::clamp(c.y(), -hy, hy));
        }
        f = footLoadFractions(q, c.x(), c.y());
      } else {
        f = footLoads(q, p).f_C;
      }
    }
    for (int i = 0; i < 4; ++i) ev.N[i] = weight_ * f[i];
  }

  // The load transfer's loads where the fixed-point iteration does not converge (its map is
  // expansive, or contracts too slowly for its iterations). A solution always exists: the centre
  // of pressure p_C - h sum_i f_i(p) dir_i stays in a bounded convex set and the f_i are
  // continuous in it (Brouwer). The map is piecewise affine, so Newton's method on G(F) =
  // sum_i N_i(F) dir_i - F (dir_i: foot i's friction per unit normal load), with its Jacobian by
  // differences inside the current piece and a backtracking line search on |G|, reaches a
  // solution; it polishes while |G| still falls. Where the map is expansive the solution need not
  // be unique: this is the one reached first (starts below). The run counts these calls
  // (extra.load_transfer_newton_solves). Throws if no start brings |G| to 1e-10 W (W = m g).
  void loadTransferNewton(Eval& ev, double t, double phi, const std::array<Vec2, 4>& dir, const Vec2& F_last) const {
    if (newton_counter_) ++*newton_counter_;
    auto G = [&](const Vec2& f) {
      normalLoads(ev, t, phi, f);
      Vec2 g = -f;
      for (int i = 0; i < 4; ++i) g += ev.N[i] * dir[i];
      return g;
    };
    const double tol = 1e-10 * weight_;
    // Starts: the iteration's last state, then no friction and all the weight on each foot in turn
    // (a start can end in a kink's local minimum of |G|; the solution is then found from another).
    const Vec2 starts[6] = {F_last, Vec2::Zero(), weight_ * dir[0], weight_ * dir[1], weight_ * dir[2], weight_ * dir[3]};
    double best = std::numeric_limits<double>::infinity();
    for (const Vec2& F0 : starts) {
      Vec2 F = F0, g = G(F);
      // Newton steps until |G| <= tol, then on while they still reduce |G| (at most 3 more): the
      // solution of the current affine piece to round-off, not just to the tolerance.
      int polish = 0;
      for (int it = 0; it < 60 && polish < 3; ++it) {
        if (g.norm() <= tol) ++polish;
        const double d = 1e-7 * std::max(F.norm(), 1e-3 * weight_);
        Eigen::Matrix2d J;
        J.col(0) = (G(F + Vec2(d, 0.0)) - g) / d;
        J.col(1) = (G(F + Vec2(0.0, d)) - g) / d;
        const Eigen::FullPivLU<Eigen::Matrix2d> lu(J);
        // A singular piece: the plain iteration's step (solve() would give a finite, useless one).
        const Vec2 step = lu.isInvertible() ? Vec2(-lu.solve(g)) : g;
        double a = 1.0;
        Vec2 F_new = F + step, g_new = G(F_new);
        while (!(g_new.norm() < (1.0 - 1e-4 * a) * g.norm()) && a > 1e-10) {
          a *= 0.5;
          F_new = F + a * step;
          g_new = G(F_new);
        }
        if (!(g_new.norm() < g.norm())) break;  // no descent: a kink's local minimum, or round-off
        F = F_new;
        g = g_new;
      }
      if (g.norm() <= tol) {
        normalLoads(ev, t, phi, F);  // ev's loads (and support margin) at the solution
        return;
      }
      best = std::min(best, g.norm());
    }
    std::ostringstream os;
    os.precision(3);
    os << "the load-transfer loads were not found at t = " << t << " s while sliding (fixed-point iteration, "
       << "then Newton's method from 6 starts; smallest residual " << best << " N): with com_height_m "
       << robot_.quadruped.com_height_m << " m the normal loads and the friction that shifts them are hard to "
       << "solve near the support's edge (docs/per-foot-model.md \"Normal loads\"); a lower COM or less friction runs";
    throw std::runtime_error(os.str());
  }

  // The held wrench's load factor. warm (the stick/slip scan's margins): warm-started from the
  // last one computed (the wrench changes continuously between the scan's samples); where that
  // gives s >= kColdLoadFactor (a margin 1 - s within 0.1 of 0, where the switches are decided) it
  // is computed again from the start scan, so those margins are the start scan's to the last bit,
  // and the warm ones further from 0 equal them to round-off (loadFactor, per_foot_model.h).
  // Not warm (rows, one-off evaluations, perFootHeldLoadFactor): the start scan alone, neither
  // counted nor kept as the warm start, so what a run computes and counts does not depend on
  // which rows its output asks for.
  double heldLoadFactor(const FootDiscs& discs, const Wrench2& req, bool warm) const {
    constexpr double kColdLoadFactor = 0.9;
    if (!warm) return loadFactor(discs, req).s;
    if (load_factor_counter_) ++*load_factor_counter_;
    LoadFactor lf = loadFactor(discs, req, &last_load_factor_);
    if (!lf.start_scan && lf.s >= kColdLoadFactor) lf = loadFactor(discs, req);
    if (lf.start_scan && start_scan_counter_) ++*start_scan_counter_;
    last_load_factor_ = lf;
    return lf.s;
  }

  // The planar multibody with the base moving (paper-notes point 3, as analytic.coupling: exact):
  // A z = r0 + E f with z = (a_Qx, a_Qy, phi_ddot), angular momentum about the quadruped COM.
  void exactCoupling(const std::vector<JointState>& js, double phi, double w, Eval& ev, Eigen::Matrix3d& A,
                     Eigen::Vector3d& r0) const {
    TailKinematics& kin = kin_;
    tailKinematics(robot_.tail, js, kin);
    const Vec2 p_QB(-robot_.quadruped.d_Q2B_m, 0.0);
    Vec2 S = Vec2::Zero(), lin = Vec2::Zero();
    double J = robot_.quadruped.izz_kgm2, ang = 0.0;
    const SinCos R = sinCos(phi);
    for (size_t i = 0; i < robot_.tail.size(); ++i) {
      const TailLink& l = robot_.tail[i];
      const Vec2 rho = rotate(R.c, R.s, Vec2(p_QB - kin.p_L[i]));
      const Vec2 rho_dot_rel = rotate(R.c, R.s, Vec2(-kin.v_L[i]));
      const Vec2 rho_ddot_rel = rotate(R.c, R.s, Vec2(-kin.a_L[i]));
      const Vec2 b = -w * w * rho + 2.0 * w * perp(rho_dot_rel) + rho_ddot_rel;
      S += l.mass_kg * rho;
      J += l.izz_kgm2 + l.mass_kg * rho.squaredNorm();
      lin += l.mass_kg * b;
      ang += l.mass_kg * cross2(rho, b) + l.izz_kgm2 * kin.alpha[i];
    }
    const double m = ev.loads.mass_kg;
    A << m, 0, -S.y(), 0, m, S.x(), -S.y(), S.x(), J;
    r0 << -lin.x(), -lin.y(), -ang;
    ev.c_W = S / m;
  }

  const RobotParams& robot_;
  const TailTrajectory& traj_;
  PerFootSettings s_;
  Effects e_;
  const PrescribedNormalLoads* prescribed_ = nullptr;  // diagnostic: loads given over time
  double weight_ = 0, mu_break_ = 0;
  bool scan_support_ = false;
  double shift_max_ = 0;
  std::array<Vec2, 4> foot_Q_ = zeros4();
  std::array<double, 4> fC_const_{};
  mutable std::vector<JointState> js_;
  mutable LoadScratch scratch_;
  mutable TailKinematics kin_;
  mutable long* newton_counter_ = nullptr;  // loadTransferNewton calls (summary extra), or null
  mutable long* load_factor_counter_ = nullptr;  // loadFactor calls (summary extra), or null
  mutable long* start_scan_counter_ = nullptr;  // of them, those from the start scan (not warm)
  mutable LoadFactor last_load_factor_;   // heldLoadFactor's warm start (sigma 0: none yet)
};

// Event margin: > 0 no switch. Stuck: 1 - s (the discs hold the required wrench while s < 1).
// Sliding: max(fastest foot - v_stop, s_probe - 1), s_probe of the wrench that would hold it now.
double margin(const Model& model, double t, const State& y, bool stuck, double v_stop) {
  if (stuck) return 1.0 - model.evaluate(t, y, true, false, true).load_factor;
  const double fast = model.maxFootSpeed(y) - v_stop;
  if (fast > 0) return fast;
  return std::max(fast, model.evaluate(t, y, true, false, true).load_factor - 1.0);
}

// First switch in [ta, tb], or +inf: the analytic model's scan (stick_slip.h findSwitch) on this
// model's one margin, as its rotation DOF (the other margin, held at 1, never switches): margins
// sampled every h_scan, a crossing located by Illinois, a dip of a stuck margin between samples by
// golden section. `prev` (the last scan's end, same mode, ending at ta; stateAt must answer before
// ta too) lets a dip across the boundary be found; `end` is set when nothing switches.
Modes scanModes(bool stuck) {
  Modes modes;
  modes.stuck[kRot] = stuck;
  modes.stuck[kTrans] = true;
  return modes;
}

// The load transfer's support margin (Eval::support) rides in the scan's second slot, as a stuck
// margin: it reaches zero from above where the centre of pressure leaves the rectangle, and a dip
// between samples is refined by golden section. It is capped at the largest shift of the centre
// of pressure (Model::shiftMax): samples farther inside are all equal, so no dip is refined there.
// Without the scan (Model::scansSupport false) the slot holds 1, as before.
constexpr int kSupport = kTrans;

Margins scanMargins(const Model& model, double t, const State& y, bool stuck, double v_stop) {
  const bool sup = model.scansSupport();
  auto capped = [&](const Eval& ev) { return sup ? std::min(ev.support, model.shiftMax()) : 1.0; };
  if (stuck) {
    const Eval ev = model.evaluate(t, y, true, false, true);
    return {1.0 - ev.load_factor, capped(ev)};
  }
  const double g_sup = sup ? capped(model.evaluate(t, y, false)) : 1.0;
  if (!model.stiction()) return {1.0, g_sup};  // the continuous law: no switches
  const double fast = model.maxFootSpeed(y) - v_stop;
  if (fast > 0) return {fast, g_sup};
  return {std::max(fast, model.evaluate(t, y, true, false, true).load_factor - 1.0), g_sup};
}

// The centre of pressure left the support at t (a located exit): the TippingError, with the time.
[[noreturn]] void throwTipping(const Model& model, const QuadrupedParams& q, double t, const State& y, bool stuck) {
  const Eval ev = model.evaluate(t, y, stuck);
  throw TippingError(supportLossMessage(q, SupportLoss{t, ev.cop_CC}, "centre of pressure (load transfer)"));
}

// What one output row is read from (its column table below): the planar models' row, and the
// feet's forces, normal loads and the held wrench's load factor.
struct PerFootRow : PlanarRow {
  const Eval& ev;
  bool stuck;
};

// The per-foot model's columns: name and value, in the CSV's order: the analytic model's columns,
// then each foot's friction force and normal load, and the load factor of the held wrench.
std::vector<RowColumn<PerFootRow>> perFootColumnTable(int links) {
  using R = const PerFootRow&;
  std::vector<RowColumn<PerFootRow>> t;
  addTimeAndJointColumns(t, links);
  addBodyColumns(t);
  for (int k = 1; k <= 4; ++k) {
    t.push_back({col::footFx(k), [](R r, int i) { return r.ev.Ff[i].x(); }, k - 1});
    t.push_back({col::footFy(k), [](R r, int i) { return r.ev.Ff[i].y(); }, k - 1});
  }
  for (int k = 1; k <= 4; ++k) t.push_back({col::footN(k), [](R r, int i) { return r.ev.N[i]; }, k - 1});
  t.push_back({col::kLoadFactor, [](R r, int) { return r.stuck ? r.ev.load_factor : kNaN; }});
  return t;
}

// The per-foot model as the planar driver runs it (stick_slip_driver.h): one stick/slip mode
// (the body held or sliding), its margin in the scan's first slot and the load transfer's support
// margin in the second; a located exit of the support ends the run (TippingError).
class PerFootStickSlip {
 public:
  using State = std::array<double, 6>;
  static constexpr bool kDefersRowsInSteps = false;  // a sliding step's rows are written at once
  static constexpr bool kHitOnlyWithinStep = true;   // a switch located past tb by round-off ends nothing
  static constexpr bool kFillsGridToEnd = true;      // every row of the grid, one past t_end at its state

  PerFootStickSlip(const Model& m, const RobotParams& robot, const PerFootSettings& s, int links)
      : model_(m), robot_(robot), s_(s), table_(perFootColumnTable(links)), names_(columnNames(table_)) {}

  int switches = 0, breakaways = 0;
  double t_stop = 0.0;           // the body last stuck
  double max_load_factor = 0.0;  // of the held wrench, over the held chunks

  const std::vector<std::string>& columns() const { return names_; }
  void fillRow(double t, const State& y, const Modes& modes, double* out) {
    const bool stuck = modes.stuck[kRot];
    const bool decomp = model_.effects().load_decomposition;
    const Eval ev = model_.evaluate(t, y, stuck, decomp);
    model_.joints(t, js_);
    const double state = stickSlipState(model_.stiction(), stuck);
    const PerFootRow row{{t, js_, y[kX], y[kY], y[kPhi], stuck ? 0.0 : y[kW], ev.phi_ddot, ev.loads, decomp,
                          ev.friction.M, ev.L_F, ev.FT_W, ev.friction.F, state,
                          model_.translation() ? state : kNaN},
                         ev,
                         stuck};
    fillColumns(table_, row, out);
  }
  static double phi(const State& y) { return y[kPhi]; }
  bool stiction() const { return model_.stiction(); }
  bool translation() const { return model_.translation(); }
  const PerFootSettings& settings() const { return s_; }

  // The body's one mode as the planar Modes: both DOFs held or both sliding.
  static Modes modesOf(bool stuck) {
    Modes m;
    m.stuck[kRot] = m.stuck[kTrans] = stuck;
    return m;
  }
  static bool held(const Modes& modes) { return modes.stuck[kRot]; }
  // The whole run's shortest tail phase (RunPlan) in every segment.
  static SegmentScales scales(const RunPlan& plan, double, double) { return {plan.h_scan, plan.h_max}; }
  bool scansSteps() const { return model_.stiction() || model_.scansSupport(); }
  bool keepsScanEnd() const { return model_.scansSupport(); }
  static Modes scanModes(const Modes& modes) { return tailsim::scanModes(modes.stuck[kRot]); }
  Margins margins(double t, const State& y, const Modes& modes) const {
    return scanMargins(model_, t, y, modes.stuck[kRot], s_.v_stop_mps);
  }
  void onHit(const Found& f, const State& y, const Modes& modes) const {
    if (f.which == kSupport) throwTipping(model_, robot_.quadruped, f.t, y, modes.stuck[kRot]);
  }
  // The load factor at the chunk's end (the scan's last sample), or where it broke away (about
  // 1): not at tb then, where the held body no longer exists (that read up to 60 on random runs).
  void onHeldScan(const Found& f, bool hit, const State& y, const Modes&, const ScanEnd& end) {
    max_load_factor =
        std::max(max_load_factor, 1.0 - (hit ? margin(model_, f.t, y, true, s_.v_stop_mps) : end.g_end[kRot]));
  }

  // Makes the mode consistent with (t, y): a held wrench outside the limit surface breaks away, a
  // slide slower than v_stop whose holding wrench is inside sticks (twist set to zero).
  void switchAt(double t, State& y, Modes& modes, int /*which*/) {
    if (!model_.stiction()) return;
    bool stuck = modes.stuck[kRot];
    for (int n = 0;; ++n) {
      if (n > 8) throw std::runtime_error("stick/slip modes do not settle at t=" + std::to_string(t) + " s");
      const double g = margin(model_, t, y, stuck, s_.v_stop_mps);
      if (stuck && g <= 0) {
        stuck = false;
        ++breakaways;
      } else if (!stuck && g < 0) {
        stuck = true;
        y[kVx] = y[kVy] = y[kW] = 0.0;
        t_stop = t;
      } else {
        break;
      }
      ++switches;
      modes = modesOf(stuck);
    }
  }
  static double firstStep(double dt0, const State&, const Modes&) { return dt0; }
  void derivative(double t, const State& y, const Modes&, State& dy) const { model_.derivative(t, y, dy); }

  std::string stepBudgetMessage(double t, double, bool held) const {
    if (held) return "step budget exhausted";
    return "step budget of " + std::to_string(s_.max_steps) + " steps exhausted at t=" + std::to_string(t) + " s";
  }
  static std::string nonFiniteMessage(double t) {
    return "state became non-finite at t=" + std::to_string(t) + " s";
  }

 private:
  const Model& model_;
  const RobotParams& robot_;
  const PerFootSettings& s_;
  std::vector<RowColumn<PerFootRow>> table_;
  std::vector<std::string> names_;
  std::vector<JointState> js_;
};

}  // namespace

std::array<double, 4> PrescribedNormalLoads::at(double t) const {
  if (t <= t_s.front()) return N.front();
  if (t >= t_s.back()) return N.back();
  const size_t j = static_cast<size_t>(std::upper_bound(t_s.begin(), t_s.end(), t) - t_s.begin());  // t_s[j-1] <= t < t_s[j]
  const double a = (t - t_s[j - 1]) / (t_s[j] - t_s[j - 1]);
  std::array<double, 4> out;
  for (int k = 0; k < 4; ++k) out[k] = (1 - a) * N[j - 1][k] + a * N[j][k];
  return out;
}

namespace {

// The run's settings checked (std::invalid_argument) and its plan: the end, the rows, and the
// scan and step lengths from the tail's shortest phase.
RunPlan perFootRunPlan(const RobotParams& robot, const TailTrajectory& trajectory, const PerFootSettings& settings,
                       const OutputSettings& output) {
  requireOneJointPerLink(trajectory.joints.size(), robot.tail.size());
  if (!(settings.rel_tol > 0) || !(settings.abs_tol > 0)) throw std::invalid_argument("perfoot tolerances must be > 0");
  if (!(settings.event_tol_s > 0)) throw std::invalid_argument("perfoot event_tol_s must be > 0");
  if (!(settings.v_stop_mps > 0)) throw std::invalid_argument("perfoot v_stop_mps must be > 0");
  if (!(settings.max_step_s >= 0)) throw std::invalid_argument("perfoot max_step_s must be >= 0");
  for (double v : settings.initial_velocity)
    if (!std::isfinite(v)) throw std::invalid_argument("perfoot initial_velocity must be finite");
  if (!(output.sample_dt_s > 0)) throw std::invalid_argument("output.sample_dt_s must be > 0");
  const double t_end = output.runEnd(trajectory.endTime());
  if (output.sample_dt_s > t_end) throw std::invalid_argument("output.sample_dt_s is longer than the run");
  const double rows = output.rows(t_end);
  if (!(rows <= limits::kMaxRowsPerRun)) throw std::invalid_argument("the run would write too many rows");
  RunPlan plan;
  plan.t_end = t_end;
  plan.rows = static_cast<long>(rows);
  plan.tail_end = trajectory.endTime();
  double shortest = trajectory.shortestPhase();
  if (!std::isfinite(shortest)) shortest = t_end;
  plan.h_scan = shortest / 32.0;
  plan.h_max = settings.max_step_s > 0 ? settings.max_step_s : shortest / 8.0;
  return plan;
}

// The finished run's series and summary: the final state, the counts, and whether it came to rest.
void recordPerFootRun(PlanarRun<PerFootStickSlip>& run, const PerFootStickSlip& ss, const Model& model, double t_end,
                      RunResult& result) {
  RunSummary& sum = result.summary;
  const State& y = run.y;
  result.series = run.rec.take();
  result.series_thinned = run.rec.thinned();
  const bool stuck = run.modes.stuck[kRot];
  sum.phi_net_deg = units::degrees(y[kPhi]);
  sum.t_stop_s = stuck ? ss.t_stop : t_end;
  sum.stick_slip_events = ss.switches;
  sum.solver_steps = run.steps;
  const double phidot_dps = units::degrees(std::abs(y[kW])), speed = std::hypot(y[kVx], y[kVy]);
  sum.extra["final_x_m"] = y[kX];
  sum.extra["final_y_m"] = y[kY];
  sum.extra["final_phidot_dps"] = units::degrees(y[kW]);
  sum.extra["final_speed_mps"] = speed;
  sum.extra["breakaways"] = ss.breakaways;
  sum.extra["rhs_evaluations"] = static_cast<double>(run.rhs);
  sum.extra["rejected_steps"] = static_cast<double>(run.rejected);
  if (model.stiction()) sum.extra["max_load_factor_stuck"] = ss.max_load_factor;
  sum.at_rest = stuck || (phidot_dps < limits::kAtRestPhidotDps && speed < limits::kAtRestSpeedMps);
  if (!sum.at_rest) sum.warnings.push_back(notAtRestWarning(t_end, phidot_dps, speed));
}

// Stages: the plan, the support checked along the trajectory, the stick/slip run from the initial
// velocity, its record; a failure ends it with the summary's error, the counts kept.
RunResult simulatePerFootImpl(const RobotParams& robot, const TailTrajectory& trajectory, const PerFootSettings& settings,
                              const Effects& effects, const OutputSettings& output, const PrescribedNormalLoads* loads) {
  const RunPlan plan = perFootRunPlan(robot, trajectory, settings, output);
  const double t_end = plan.t_end;
  const auto wall0 = std::chrono::steady_clock::now();
  RunResult result;
  RunSummary& sum = result.summary;
  sum.model = "perfoot";
  long newton_solves = 0, load_factors = 0, start_scans = 0;
  try {
    // Every evaluation with friction takes the paper's arm L_F at the system COM, which fails outside
    // the support rectangle: checked along the whole trajectory first (support_check.h). The load
    // transfer's shifted centre of pressure depends on the state: unless the Model rules it out
    // before the run, its margin is scanned with the stick/slip margins (scanMargins), between
    // samples too, and an exit is located as an event.
    if (effects.friction != FrictionLaw::kNone && effects.gravity && robot.systemMass() * robot.gravity_mps2 > 0.0)
      requireSupport(robot, trajectory, t_end);
    const Model model(robot, trajectory, settings, effects, loads, t_end);
    model.countNewtonSolvesInto(&newton_solves);
    model.countLoadFactorsInto(&load_factors, &start_scans);
    PerFootStickSlip ss(model, robot, settings, robot.numLinks());
    PlanarRun<PerFootStickSlip> run(ss, plan, trajectory.breakpoints(), output.sample_dt_s,
                                    output.time_series == TimeSeriesOutput::kThin);
    State& y = run.y;
    y[kVx] = settings.initial_velocity[0];
    y[kVy] = settings.initial_velocity[1];
    y[kW] = settings.initial_velocity[2];
    run.modes = PerFootStickSlip::modesOf(model.stiction() && model.maxFootSpeed(y) == 0.0);
    planar_driver::switchAt(run, -1);
    integrate(run);
    recordPerFootRun(run, ss, model, t_end, result);
  } catch (const TippingError& e) {
    sum.ok = false;
    sum.error = e.what();
  } catch (const std::runtime_error& e) {
    sum.ok = false;
    sum.error = std::string("perfoot model failed: ") + e.what();
  }
  if (settings.normal_loads == NormalLoadModel::kLoadTransfer)
    sum.extra["load_transfer_newton_solves"] = static_cast<double>(newton_solves);
  sum.extra["load_factor_evaluations"] = static_cast<double>(load_factors);
  sum.extra["load_factor_start_scans"] = static_cast<double>(start_scans);
  sum.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return result;
}

}  // namespace

RunResult simulatePerFoot(const RobotParams& robot, const TailTrajectory& trajectory, const PerFootSettings& settings,
                          const Effects& effects, const OutputSettings& output) {
  return simulatePerFootImpl(robot, trajectory, settings, effects, output, nullptr);
}

std::vector<double> perFootHeldLoadFactor(const RobotParams& robot, const TailTrajectory& trajectory,
                                          const Effects& effects, const std::vector<double>& times) {
  requireOneJointPerLink(trajectory.joints.size(), robot.tail.size());
  const Model model(robot, trajectory, PerFootSettings{}, effects, nullptr);
  std::vector<double> s;
  s.reserve(times.size());
  const State at_rest{};
  for (double t : times) s.push_back(model.evaluate(t, at_rest, true).load_factor);
  return s;
}

RunResult simulatePerFoot(const RobotParams& robot, const TailTrajectory& trajectory, const PerFootSettings& settings,
                          const Effects& effects, const OutputSettings& output, const PrescribedNormalLoads& loads) {
  if (loads.t_s.empty() || loads.t_s.size() != loads.N.size())
    throw std::invalid_argument("prescribed normal loads: need as many times as load rows, at least one");
  for (size_t j = 0; j < loads.t_s.size(); ++j) {
    if (!std::isfinite(loads.t_s[j]) || (j > 0 && !(loads.t_s[j] > loads.t_s[j - 1])))
      throw std::invalid_argument("prescribed normal loads: times must be finite and strictly ascending");
    for (double n : loads.N[j])
      if (!std::isfinite(n) || n < 0) throw std::invalid_argument("prescribed normal loads must be finite and >= 0");
  }
  return simulatePerFootImpl(robot, trajectory, settings, effects, output, &loads);
}

std::vector<std::string> perFootColumns(int links) { return columnNames(perFootColumnTable(links)); }

}  // namespace tailsim
