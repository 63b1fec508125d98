#include "models/analytic/analytic_simulation.h"
#include "models/planar/at_rest.h"

#include "results/columns.h"

#include <algorithm>
#include <array>
#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <boost/numeric/odeint.hpp>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "models/analytic/analytic_model.h"
#include "models/analytic/analytic_rows.h"
#include "models/planar/foot_loads.h"
#include "models/planar/stick_slip_driver.h"
#include "models/planar/support_check.h"
#include "common/work_limits.h"
#include "common/units.h"

namespace tailsim {
namespace {

namespace odeint = boost::numeric::odeint;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The integral of f over [a, b], where f is smooth (between two breakpoints of the tail profile):
// 21-point Gauss-Kronrod (Boost.Math), exact for polynomials of degree 31. The interval is halved
// while the embedded 10-point Gauss rule differs by more than 1e-12 of the integral of |f| (at
// most 5 times). A Simpson rule of 64 intervals did this before: 129 evaluations of the tail loads
// per segment, 22 % of a random sweep's instructions, and relative errors up to 8e-5
// (docs/scale.md "Work no result needed").
template <class F>
double integrateSmooth(const F& f, double a, double b, int depth = 0) {
  const double mid = 0.5 * (a + b), half = 0.5 * (b - a);
  double err = 0.0, L1 = 0.0;
  // On [-1, 1] itself: Boost reports err and L1 there without one consistent interval scaling.
  const double q = boost::math::quadrature::gauss_kronrod<double, 21>::integrate(
      [&](double x) { return f(mid + half * x); }, -1.0, 1.0, 0, 0.0, &err, &L1);
  if (err <= 1e-12 * L1 || depth >= 5) return half * q;
  return integrateSmooth(f, a, mid, depth + 1) + integrateSmooth(f, mid, b, depth + 1);
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
  for (std::size_t s = 0; s + 1 < b.size(); ++s)
    if (b[s + 1] > b[s]) w += integrateSmooth(f, b[s], b[s + 1]);
  return w;
}

// Checks the settings (std::invalid_argument) and plans the run.
RunPlan planRun(const TailTrajectory& trajectory, const AnalyticSettings& settings, const OutputSettings& output) {
  if (settings.solver != AnalyticSolver::kAdaptive && settings.solver != AnalyticSolver::kFixed)
    throw std::invalid_argument("analytic.solver must be adaptive or fixed");
  if (!(settings.rel_tol > 0) || !(settings.abs_tol > 0)) throw std::invalid_argument("analytic tolerances must be > 0");
  if (!(settings.fixed_dt_s > 0)) throw std::invalid_argument("analytic.fixed_dt_s must be > 0");
  if (!(output.sample_dt_s > 0)) throw std::invalid_argument("output.sample_dt_s must be > 0");
  RunPlan plan;
  const double t_end = output.runEnd(trajectory.endTime());
  plan.t_end = t_end;
  if (output.sample_dt_s > t_end)
    throw std::invalid_argument("output.sample_dt_s = " + std::to_string(output.sample_dt_s) +
                                " s is longer than the run (" + std::to_string(t_end) +
                                " s): the time series needs at least 2 rows");
  // Checked as a double before it becomes a count (no float-to-integer overflow).
  const double rows = output.rows(t_end);
  if (!(rows <= limits::kMaxRowsPerRun))
    throw std::invalid_argument("the run (" + std::to_string(t_end) + " s / output.sample_dt_s " +
                                std::to_string(output.sample_dt_s) + " s) would write more than " +
                                std::to_string(static_cast<long>(limits::kMaxRowsPerRun)) + " rows");
  plan.rows = static_cast<long>(rows);
  plan.tail_end = trajectory.endTime();
  // Shortest acceleration or deceleration phase sets the event sampling and the step bound.
  const double shortest = trajectory.shortestPhase();
  plan.h_scan = shortest / 32.0;
  plan.h_max = settings.max_step_s > 0 ? settings.max_step_s : shortest / 8.0;
  plan.adaptive = settings.solver == AnalyticSolver::kAdaptive;
  return plan;
}

// The analytic model as the planar driver runs it (stick_slip_driver.h): its right-hand side,
// event margins (both DOFs), mode switches and rows, with the workspace and the switch counters.
class AnalyticStickSlip {
 public:
  using State = tailsim::State;
  static constexpr bool kDefersRowsInSteps = true;   // a step's rows wait while a stuck margin falls at its end
  static constexpr bool kHitOnlyWithinStep = false;  // a switch located past tb by round-off still ends the step
  static constexpr bool kFillsGridToEnd = false;     // rows more than 1e-12 s past t_end are not written

  AnalyticStickSlip(const AnalyticModel& m, double v_stop) : model(m), v_stop_(v_stop), rows_(m.robot.numLinks()) {}

  const AnalyticModel& model;
  AnalyticWorkspace ws;
  int switches = 0;         // stick/slip events
  double t_stop = 0.0;      // the rotation last stuck
  bool ever_rotated = false;

  const std::vector<std::string>& columns() const { return rows_.names(); }
  void fillRow(double t, const State& y, const Modes& modes, double* out) { rows_.fill(model, ws, t, y, modes, out); }
  static double phi(const State& y) { return y[kPhi]; }
  bool stiction() const { return model.stiction(); }
  bool translation() const { return model.translation(); }
  const AnalyticSettings& settings() const { return model.settings; }
  double vStop() const { return v_stop_; }

  // Both DOFs stuck (the translation stuck or locked): nothing will change until a margin says so.
  bool held(const Modes& modes) const {
    return model.stiction() && modes.stuck[kRot] && (modes.stuck[kTrans] || !model.translation());
  }

  // Event sampling interval and step bound over [t, seg_end], which lies between two breakpoints
  // of the tail profile: each joint is in one phase there. Both follow the shortest phase of the
  // joints that move (planRun's rules restricted to what moves: a joint at rest adds no load
  // variation, and a load peak is as wide as the phase that makes it): step bound 1/8 of it,
  // sampling 1/32. A margin's dip is found when it spans at most two sample intervals, also
  // across a step's end (docs/accuracy.md "A dip across a step boundary"; docs/scale.md
  // "Analytic hot path"). With the whole tail at rest its loads vanish (no joint speed or
  // acceleration); with the paper coupling every margin is then monotone in time (constant
  // friction decelerations, no tail force), so a step's midpoint and end suffice. With the exact
  // coupling the rotation and the translation still exchange momentum: the run's sampling stays.
  SegmentScales scales(const RunPlan& plan, double t, double seg_end) const {
    const double shortest = model.traj.shortestActivePhase(0.5 * (t + seg_end));
    if (!std::isfinite(shortest)) {
      const bool paper = model.settings.coupling == Coupling::kPaper;
      return {paper ? shortest : plan.h_scan, plan.h_max};
    }
    const double max_step = model.settings.max_step_s;
    return {shortest / 32.0, max_step > 0 ? max_step : shortest / 8.0};
  }

  bool scansSteps() const { return model.stiction(); }
  bool keepsScanEnd() const { return model.stiction(); }
  static const Modes& scanModes(const Modes& modes) { return modes; }
  Margins margins(double t, const State& y, const Modes& modes) {
    return eventMargins(model, ws, v_stop_, t, y, modes);
  }
  void onHit(const Found&, const State&, const Modes&) const {}
  void onHeldScan(const Found&, bool, const State&, const Modes&, const ScanEnd&) const {}

  void switchAt(double t, State& y, Modes& modes, int which) {
    const Modes before = modes;
    if (which >= 0) {
      applySwitch(model, ws, which, t, y, modes);
      ++switches;
    }
    switches += settleModes(model, ws, v_stop_, t, y, modes);
    if (!before.stuck[kRot] && modes.stuck[kRot]) t_stop = t;
    if (!modes.stuck[kRot]) ever_rotated = true;
  }

  // A translation that has just broken away starts inside the friction's regularization band
  // (|v| < v_reg), where the friction relaxes v at the rate mu_d W / (m v_reg): the first step
  // resolves a fifth of that time instead of being rejected down to it from 1e-4 s.
  double firstStep(double dt0, const State& y, const Modes& modes) const {
    const AnalyticModel& m = model;
    if (m.stiction() && m.translation() && !modes.stuck[kTrans] && m.v_reg > 0.0 &&
        std::hypot(y[kVx], y[kVy]) < m.v_reg && m.robot.friction.mu_d > 0.0)
      return std::min(dt0, 0.2 * m.v_reg * m.robot.systemMass() / (m.robot.friction.mu_d * m.weight));
    return dt0;
  }

  void derivative(double t, const State& y, const Modes& modes, State& dy) {
    tailsim::derivative(model, ws, t, y, modes, dy);
  }

  std::string stepBudgetMessage(double t, double t_end, bool /*held*/) const {
    return "step budget of " + std::to_string(model.settings.max_steps) + " steps exhausted at t=" +
           std::to_string(t) + " s of " + std::to_string(t_end) +
           " s (docs/experiment-format.md \"Limits\"): loosen analytic.rel_tol/abs_tol, "
           "raise max_step_s or fixed_dt_s, or shorten the run";
  }
  std::string nonFiniteMessage(double t) const {
    const std::string advice = model.settings.solver == AnalyticSolver::kFixed
                                   ? "analytic.fixed_dt_s=" + std::to_string(model.settings.fixed_dt_s) + " is too large"
                                   : "tighten analytic.rel_tol (" + std::to_string(model.settings.rel_tol) + ")";
    return "state became non-finite at t=" + std::to_string(t) + " s: " + advice;
  }

 private:
  double v_stop_;  // a slide below this speed may stick (fixed solver: at least one step's friction)
  AnalyticRows rows_;
};

using Run = PlanarRun<AnalyticStickSlip>;

// The fixed-step solver checks once per step: a slide slower than one step's friction
// deceleration (mu_d g h) would reverse within the next step, so it counts as stopped.
double stopSpeed(const AnalyticModel& m, const RunPlan& plan) {
  const AnalyticSettings& s = m.settings;
  return plan.adaptive ? s.v_stop_mps
                       : std::max(s.v_stop_mps, m.robot.friction.mu_d * m.weight / m.robot.systemMass() * s.fixed_dt_s);
}

// Initially at rest: stuck wherever stiction holds (Eqs. 14-16, first cases); a load already
// above the static limit breaks away at once.
void startAtRest(Run& run) {
  if (!run.model.stiction()) return;
  run.modes.stuck[kRot] = true;
  run.modes.stuck[kTrans] = run.model.translation();
  planar_driver::switchAt(run, -1);
}

// Fixed-step classic RK4; switches checked once per step, the way a fixed-step Simulink model
// with a zero-crossing reset would: a margin at or below zero at the step's end switches (for a
// slide, g < 0 means it stopped somewhere inside the step). The slip direction is the mode's,
// fixed over the step's four stages, so a rotation that stops inside a step overshoots zero and
// is caught, instead of its stages averaging the Coulomb sign away into an endless creep.
void fixedStep(Run& run, double seg_end) {
  using namespace planar_driver;
  AnalyticStickSlip& ss = run.model;
  const AnalyticModel& m = ss.model;
  const double dt = m.settings.fixed_dt_s;
  auto rhs = [&](const State& x, State& dx, double tt) {
    ++run.rhs;
    ss.derivative(tt, x, run.modes, dx);
  };
  odeint::runge_kutta4<State> rk4;
  const double t0 = run.t, h = std::min(dt, seg_end - t0);
  const State y0 = run.y;
  rk4.do_step(rhs, run.y, t0, h);
  countStep(run, false);
  const double t1 = t0 + h;
  const State y1 = run.y;
  auto lerp = [&](double tt, State& ys) {
    const double a = (tt - t0) / h;
    for (int i = 0; i < 6; ++i) ys[i] = y0[i] + a * (y1[i] - y0[i]);
  };
  recordUpTo(run, t1 - 1e-13, lerp);
  run.t = t1;
  checkFinite(run);
  if (m.stiction()) {
    // A 2-D slide whose velocity turned by more than 90 deg over the step stopped inside it.
    const State& y = run.y;
    const bool reversed =
        m.translation() && !run.modes.stuck[kTrans] && y0[kVx] * y[kVx] + y0[kVy] * y[kVy] < 0;
    if (reversed) {
      Modes probe = run.modes;
      probe.stuck[kTrans] = true;
      const Eval e = evaluate(m, ss.ws, run.t, run.y, probe);
      if (e.F_required.norm() < e.F_break) switchAt(run, kTrans);
    }
    switchAt(run, -1);
  }
  recordUpTo(run, run.t, [&](double, State& ys) { ys = run.y; });
}

// Summaries from the simulated state at t_end, not from the sampled rows (phi(0) = 0).
void summarize(const Run& run, RunSummary& sum) {
  const State& y = run.y;
  const AnalyticStickSlip& ss = run.model;
  const AnalyticModel& m = ss.model;
  sum.phi_net_deg = units::degrees(y[kPhi]);
  const bool still = !m.stiction() || !run.modes.stuck[kRot];
  sum.t_stop_s = still ? run.plan.t_end : ss.t_stop;
  sum.stick_slip_events = ss.switches;
  sum.solver_steps = run.steps;
  sum.extra["rhs_evaluations"] = static_cast<double>(run.rhs);
  sum.extra["rejected_steps"] = static_cast<double>(run.rejected);
  sum.extra["held_steps"] = static_cast<double>(run.held);
  sum.extra["final_x_m"] = y[kX];
  sum.extra["final_y_m"] = y[kY];
  sum.extra["final_phidot_dps"] = units::degrees(y[kPhiDot]);
  sum.extra["final_speed_mps"] = std::hypot(y[kVx], y[kVy]);
  sum.extra["still_rotating_at_end"] = still && std::abs(y[kPhiDot]) > 0 ? 1.0 : 0.0;
  sum.extra["ever_rotated"] = ss.ever_rotated || !m.stiction() ? 1.0 : 0.0;
  // At rest: both DOFs stuck (stiction), or rate and speed below the documented thresholds.
  const double phidot_dps = units::degrees(std::abs(y[kPhiDot])), speed = std::hypot(y[kVx], y[kVy]);
  sum.at_rest = ss.held(run.modes) || (phidot_dps < limits::kAtRestPhidotDps && speed < limits::kAtRestSpeedMps);
  if (!sum.at_rest) sum.warnings.push_back(notAtRestWarning(run.plan.t_end, phidot_dps, speed));
}

// The paper coupling's angular-momentum error: the turn its residual spin alone would cause
// before sliding friction (deceleration mu_d m g L_F / I_zz at the final pose) stops it,
// w^2 / (2 alpha); a warning above limits::kMaxPaperSpuriousTurnDeg.
void paperCouplingDiagnostic(Run& run, RunSummary& sum) {
  const AnalyticModel& m = run.model.model;
  const double w_res = paperResidualSpin(m.robot, m.traj);
  const Eval ev_end = evaluate(m, run.model.ws, run.plan.t_end, run.y, run.modes);
  const double alpha = m.needsArm() && std::isfinite(ev_end.L_F)
                           ? m.robot.friction.mu_d * m.weight * ev_end.L_F / ev_end.loads.Izz_kgm2
                           : 0.0;
  const double turn_deg = w_res == 0.0 ? 0.0 : alpha > 0 ? units::degrees(w_res * w_res / (2.0 * alpha))
                                                        : std::numeric_limits<double>::infinity();
  sum.extra["paper_residual_spin_dps"] = units::degrees(w_res);
  sum.extra["paper_spurious_turn_deg"] = turn_deg;
  if (turn_deg <= limits::kMaxPaperSpuriousTurnDeg) return;
  std::ostringstream os;
  os.precision(3);
  os << "the paper coupling's angular-momentum error is large: with mu = 0 it would leave the body spinning at "
     << units::degrees(w_res) << " deg/s after the tail stops (the exact coupling: 0), enough to turn it by "
     << turn_deg << " deg against sliding friction (limit " << limits::kMaxPaperSpuriousTurnDeg
     << " deg); the paper's model is outside its validity here, compare analytic.coupling: exact";
  sum.warnings.push_back(os.str());
}

}  // namespace

RunResult simulateAnalytic(const RobotParams& robot, const TailTrajectory& trajectory, const AnalyticSettings& settings,
                           const Effects& effects, const OutputSettings& output) {
  requireOneJointPerLink(trajectory.joints.size(), robot.tail.size());
  const RunPlan plan = planRun(trajectory, settings, output);
  const auto wall0 = std::chrono::steady_clock::now();
  RunResult result;
  RunSummary& sum = result.summary;
  sum.model = "analytic";
  try {
    const AnalyticModel model(robot, trajectory, settings, effects);
    // Tipping over depends on the trajectory alone: checked along all of it before the run, not
    // only where the loads happen to be evaluated (docs/paper-notes.md point 5).
    if (model.needsArm() && effects.foot_loads == FootLoadModel::kDistributed) requireSupport(robot, trajectory, plan.t_end);
    AnalyticStickSlip ss(model, stopSpeed(model, plan));
    Run run(ss, plan, trajectory.breakpoints(), output.sample_dt_s, output.time_series == TimeSeriesOutput::kThin);
    startAtRest(run);
    integrate(run, fixedStep);
    result.series = run.rec.take();
    result.series_thinned = run.rec.thinned();
    summarize(run, sum);
    if (settings.coupling == Coupling::kPaper) paperCouplingDiagnostic(run, sum);
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
  requireOneJointPerLink(joints.size(), robot.tail.size());
  RunResult r;
  r.summary.model = "analytic";
  const auto wall0 = std::chrono::steady_clock::now();
  TimeSeries& ts = r.series;
  const int n = robot.numLinks();
  std::vector<double> row;
  for (int i = 1; i <= n; ++i) ts.addColumn(col::theta(i));
  for (int i = 1; i <= n; ++i) ts.addColumn(col::thetadot(i));
  for (int i = 1; i <= n; ++i) ts.addColumn(col::thetaddot(i));
  const double d = units::kDegPerRad;
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
