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
#include <optional>
#include <sstream>
#include <stdexcept>

#include "models/analytic/analytic_model.h"
#include "models/analytic/analytic_recorder.h"
#include "models/planar/foot_loads.h"
#include "models/planar/step_control.h"
#include "models/planar/support_check.h"
#include "results/work_limits.h"

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

bool allFinite(const State& y) {
  for (double v : y)
    if (!std::isfinite(v)) return false;
  return true;
}

using DenseDopri5 = StabilizedDenseDopri5<State>;

// What a run needs to know before it starts: its end, its rows, its step sizes.
struct RunPlan {
  double t_end = 0;     // [s]
  long rows = 0;        // output rows
  double tail_end = 0;  // the tail stops moving  [s]
  double h_scan = 0;    // event sampling interval, the shortest phase of all / 32  [s] (segmentScales: per segment)
  double h_max = 0;     // adaptive step bound while the tail moves, the shortest phase of all / 8  [s] (idem)
  bool adaptive = true;
};

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

// One run in progress: the constant model and plan, the workspace, the output and the state.
struct Run {
  // thin: output.time_series thin (the recorder evaluates only the rows that thinning keeps).
  Run(const AnalyticModel& m, const RunPlan& p, double sample_dt_s, double v_stop_mps, bool thin)
      : model(m), plan(p), breakpoints(m.traj.breakpoints()),
        rec(m.robot.numLinks(), sample_dt_s, p.rows, thin ? &breakpoints : nullptr), v_stop(v_stop_mps) {}

  const AnalyticModel& model;
  const RunPlan& plan;
  AnalyticWorkspace ws;
  std::vector<double> breakpoints;  // of the tail profile (also thinning's marks)
  AnalyticRecorder rec;
  double v_stop;  // a slide below this speed may stick (fixed solver: at least one step's friction)
  State y{};
  Modes modes;
  double t = 0.0;
  int switches = 0;       // stick/slip events
  double t_stop = 0.0;    // the rotation last stuck
  bool ever_rotated = false;
  long steps = 0;         // accepted solver steps
  long rhs = 0;           // right-hand sides the solver evaluated (accepted and rejected trial steps)
  long rejected = 0;      // adaptive: trial steps the error control rejected
  long held = 0;          // adaptive: steps with every DOF stuck (heldChunk: scanned, not integrated)
  double dt_resume = 0.0;  // the step to restart with after a tail breakpoint (0: after a switch)
  double held_dt = 0.0;    // heldChunk: the chunk to go on with (0: after a switch, start small)
  // The last step's scan, kept while the modes stay (adaptiveSegment): its end margins start the
  // next scan; when a stuck margin was still falling there (dipMayCross), its last two samples
  // and its dense output too, and the rows after its second-last sample wait for the next step.
  struct Carry {
    bool have = false;    // end holds the scan of the step that ended at t_end
    bool across = false;  // and stepper its dense output: the next scan looks across t_end
    double t_end = 0;
    ScanEnd end;
    std::optional<DenseDopri5> stepper;
  } carry;
};

// The fixed-step solver checks once per step: a slide slower than one step's friction
// deceleration (mu_d g h) would reverse within the next step, so it counts as stopped.
double stopSpeed(const AnalyticModel& m, const RunPlan& plan) {
  const AnalyticSettings& s = m.settings;
  return plan.adaptive ? s.v_stop_mps
                       : std::max(s.v_stop_mps, m.robot.friction.mu_d * m.weight / m.robot.systemMass() * s.fixed_dt_s);
}

// Switches DOF `which` (or none, -1) at run.t, then settles the modes; keeps the summary counters.
void switchAt(Run& run, int which) {
  const Modes before = run.modes;
  run.held_dt = 0.0;
  if (which >= 0) {
    applySwitch(run.model, run.ws, which, run.t, run.y, run.modes);
    ++run.switches;
  }
  run.switches += settleModes(run.model, run.ws, run.v_stop, run.t, run.y, run.modes);
  if (!before.stuck[kRot] && run.modes.stuck[kRot]) run.t_stop = run.t;
  if (!run.modes.stuck[kRot]) run.ever_rotated = true;
}

// Initially at rest: stuck wherever stiction holds (Eqs. 14-16, first cases); a load already
// above the static limit breaks away at once.
void startAtRest(Run& run) {
  if (!run.model.stiction()) return;
  run.modes.stuck[kRot] = true;
  run.modes.stuck[kTrans] = run.model.translation();
  switchAt(run, -1);
}

// Both DOFs stuck with the tail still: nothing will change any more.
bool stuckForGood(const Run& run) {
  const AnalyticModel& m = run.model;
  return m.stiction() && run.modes.stuck[kRot] && (run.modes.stuck[kTrans] || !m.translation());
}
bool settled(const Run& run, double t) { return t >= run.plan.tail_end && stuckForGood(run); }

// The next breakpoint of the tail profile after t (or the end of the run).
double nextBreak(const Run& run, double t) {
  for (double b : run.breakpoints)
    if (b > t + 1e-14) return std::min(b, run.plan.t_end);
  return run.plan.t_end;
}

// Records every sample up to t_hi, with stateAt(t, y) the state there.
template <class StateAt>
void recordUpTo(Run& run, double t_hi, const StateAt& stateAt) {
  State ys;
  while (!run.rec.done() && run.rec.nextTime() <= t_hi + 1e-12) {
    const double ts = std::min(run.rec.nextTime(), run.plan.t_end);
    stateAt(ts, ys);
    run.rec.record(run.model, run.ws, ts, ys, run.modes);
  }
}

bool allFinite(const State& y);

// `advice` is called only to word the error.
template <class Advice>
void checkFinite(const Run& run, const Advice& advice) {
  if (!allFinite(run.y))
    throw std::runtime_error("state became non-finite at t=" + std::to_string(run.t) + " s: " + advice());
}

// Step budget: a run that needs more steps fails with this message instead of running on.
void countStep(Run& run) {
  ++run.steps;
  const long max_steps = run.model.settings.max_steps;
  if (run.steps > max_steps)
    throw std::runtime_error("step budget of " + std::to_string(max_steps) + " steps exhausted at t=" +
                             std::to_string(run.t) + " s of " + std::to_string(run.plan.t_end) +
                             " s (docs/experiment-format.md \"Limits\"): loosen analytic.rel_tol/abs_tol, "
                             "raise max_step_s or fixed_dt_s, or shorten the run");
}

// Event sampling interval and step bound over [t, seg_end], which lies between two breakpoints of
// the tail profile: each joint is in one phase there. Both follow the shortest phase of the joints
// that move (planRun's rules restricted to what moves: a joint at rest adds no load variation, and
// a load peak is as wide as the phase that makes it): step bound 1/8 of it, sampling 1/32. A
// margin's dip is found when it spans at most two sample intervals, also across a step's end
// (docs/accuracy.md "A dip across a step boundary"; the sampling followed the whole run's shortest
// phase until that fix was in, docs/scale.md "Analytic hot path"). With the whole tail at rest its
// loads vanish (no joint speed or acceleration); with the paper coupling every margin is then
// monotone in time (constant friction decelerations, no tail force), so a step's midpoint and end
// suffice. With the exact coupling the rotation and the translation still exchange momentum: the
// run's sampling stays.
struct SegmentScales {
  double h_scan, h_max;
};
SegmentScales segmentScales(const Run& run, double t, double seg_end) {
  const double shortest = run.model.traj.shortestActivePhase(0.5 * (t + seg_end));
  if (!std::isfinite(shortest)) {
    const bool paper = run.model.settings.coupling == Coupling::kPaper;
    return {paper ? shortest : run.plan.h_scan, run.plan.h_max};
  }
  const double max_step = run.model.settings.max_step_s;
  return {shortest / 32.0, max_step > 0 ? max_step : shortest / 8.0};
}

// While every DOF is stuck (both, or the rotation with the translation locked) the body does not
// move: its state is constant and there is nothing to integrate. The margins are scanned chunk by
// chunk as a solver step's would be, with the state held; a margin still falling at the chunk's
// end carries into the next chunk's scan (a dip across the boundary), and the rows after its
// second-last sample wait for that scan. The chunks grow as the solver's steps would with no error
// to control: 1e-4 s after a switch, then 10 times the last one, up to the step bound (across a
// tail breakpoint too). So a margin's dip right after a switch is sampled finely: a chunk has no
// sample before its start to show a dip whose lowest sample is that start. One chunk counts as
// one solver step and costs no right-hand side.
void heldChunk(Run& run, double seg_end) {
  const AnalyticModel& m = run.model;
  const double t_end = run.plan.t_end;
  const SegmentScales scales = segmentScales(run, run.t, seg_end);
  const double dt = std::min(run.held_dt > 0.0 ? run.held_dt : 1e-4, scales.h_max);
  const double ta = run.t, tb = std::min(seg_end, ta + dt);
  const State y = run.y;
  auto stateAt = [&](double, State& ys) { ys = y; };
  auto gAt = [&](double tt) { return eventMargins(m, run.ws, run.v_stop, tt, y, run.modes); };
  Run::Carry& carry = run.carry;
  const bool have = carry.have && carry.t_end == ta;
  ScanEnd end;
  const Found f = findSwitch(gAt, run.modes, ta, tb, scales.h_scan, m.settings.event_tol_s, have ? &carry.end : nullptr,
                             &end, have && carry.across);
  countStep(run);
  ++run.held;
  run.dt_resume = 0.0;
  run.held_dt = 10.0 * (tb - ta);  // (switchAt below resets it)
  const double t_cut = f.hit ? f.t : tb;
  const bool defer = !f.hit && dipMayCross(run.modes, end) && tb < t_end - 1e-15 && !(tb >= run.plan.tail_end);
  recordUpTo(run, defer ? end.t_before : t_cut, stateAt);
  run.t = t_cut;
  carry.stepper.reset();
  if (f.hit) {
    carry.have = carry.across = false;
    switchAt(run, f.which);
    return;
  }
  carry.have = true;
  carry.across = defer;
  carry.t_end = tb;
  carry.end = end;
}

// Adaptive dense-output Dormand-Prince from run.t until a located switch, a breakpoint of the
// tail profile (seg_end), the end, or rest: the stepper restarts there.
void adaptiveSegment(Run& run, double seg_end) {
  const AnalyticModel& m = run.model;
  const AnalyticSettings& s = m.settings;
  const double t_end = run.plan.t_end;
  const bool tail_moving = run.t < run.plan.tail_end;
  const SegmentScales scales = segmentScales(run, run.t, seg_end);
  const double max_dt = (tail_moving || run.modes.stuck[kRot] || run.modes.stuck[kTrans]) ? scales.h_max : (t_end - run.t);
  auto rhs = [&](const State& x, State& dx, double tt) {
    ++run.rhs;
    derivative(m, run.ws, tt, x, run.modes, dx);
  };
  DenseDopri5 stepper = makeStabilizedDopri5<State>(s.abs_tol, s.rel_tol, max_dt, &run.rejected);
  // After a switch the dynamics change: start small. After a tail breakpoint they continue with
  // a jump in the tail acceleration only: go on with the step size the solver had reached.
  double dt0 = std::min(max_dt, run.dt_resume > 0 ? run.dt_resume : 1e-4);
  // A translation that has just broken away starts inside the friction's regularization band
  // (|v| < v_reg), where the friction relaxes v at the rate mu_d W / (m v_reg): the first step
  // resolves a fifth of that time instead of being rejected down to it from 1e-4 s.
  if (run.dt_resume == 0.0 && m.stiction() && m.translation() && !run.modes.stuck[kTrans] && m.v_reg > 0.0 &&
      std::hypot(run.y[kVx], run.y[kVy]) < m.v_reg && m.robot.friction.mu_d > 0.0)
    dt0 = std::min(dt0, 0.2 * m.v_reg * m.robot.systemMass() / (m.robot.friction.mu_d * m.weight));
  run.dt_resume = 0.0;
  stepper.initialize(run.y, run.t, dt0);
  for (;;) {
    // A step that would cross the next breakpoint (where the tail acceleration jumps) ends on it
    // instead: across it the error estimate fails and the step is rejected over and over.
    const double t_now = stepper.current_time(), dt_now = stepper.current_time_step();
    if (t_now + dt_now > seg_end && seg_end - t_now > 1e-12)
      stepper.initialize(stepper.current_state(), t_now, seg_end - t_now);
    const auto [ta, tb_raw] = stepper.do_step(rhs);
    countStep(run);
    const double tb = std::min(tb_raw, seg_end);
    Run::Carry& carry = run.carry;
    const bool have = carry.have && carry.t_end == ta, across = have && carry.across;
    // Before ta (a dip looked for across the boundary): the previous step's dense output.
    auto stateAt = [&](double tt, State& ys) {
      if (across && tt < ta)
        carry.stepper->calc_state(tt, ys);
      else
        stepper.calc_state(tt, ys);
    };
    Found f;
    ScanEnd end;
    if (m.stiction()) {
      State yg;
      auto gAt = [&](double tt) {
        stateAt(tt, yg);
        return eventMargins(m, run.ws, run.v_stop, tt, yg, run.modes);
      };
      f = findSwitch(gAt, run.modes, ta, tb, scales.h_scan, s.event_tol_s, have ? &carry.end : nullptr, &end, across);
    }
    const double t_cut = f.hit ? f.t : tb;
    // A margin still falling at tb may dip below zero just after it: the rows after the last
    // sample before tb wait until the next step's scan has looked (the switch may come first).
    const bool defer = !f.hit && m.stiction() && dipMayCross(run.modes, end) && tb < t_end - 1e-15 &&
                       !(tb >= run.plan.tail_end && stuckForGood(run));
    recordUpTo(run, defer ? end.t_before : t_cut, stateAt);
    stateAt(t_cut, run.y);
    run.t = t_cut;
    checkFinite(run, [&] { return "tighten analytic.rel_tol (" + std::to_string(s.rel_tol) + ")"; });
    if (f.hit) {
      carry.have = carry.across = false;
      switchAt(run, f.which);
      return;
    }
    carry.have = m.stiction();
    carry.across = defer;
    carry.t_end = tb;
    carry.end = end;
    if (defer) carry.stepper = stepper;
    if (tb_raw >= seg_end - 1e-15) {  // a breakpoint of the tail profile: restart the step there
      if (tb_raw <= seg_end + 1e-12) run.dt_resume = std::max(stepper.current_time_step(), tb_raw - ta);
      return;
    }
    if (run.t >= t_end - 1e-15 || settled(run, run.t)) return;
    // The solver's internal state may lie beyond t (when tb was clipped): continue from t.
    if (stepper.current_time() > run.t + 1e-15) return;
  }
}

// Fixed-step classic RK4; switches checked once per step, the way a fixed-step Simulink model
// with a zero-crossing reset would: a margin at or below zero at the step's end switches (for a
// slide, g < 0 means it stopped somewhere inside the step). The slip direction is the mode's,
// fixed over the step's four stages, so a rotation that stops inside a step overshoots zero and
// is caught, instead of its stages averaging the Coulomb sign away into an endless creep.
void fixedStep(Run& run, double seg_end) {
  const AnalyticModel& m = run.model;
  const double dt = m.settings.fixed_dt_s;
  auto rhs = [&](const State& x, State& dx, double tt) {
    ++run.rhs;
    derivative(m, run.ws, tt, x, run.modes, dx);
  };
  odeint::runge_kutta4<State> rk4;
  const double t0 = run.t, h = std::min(dt, seg_end - t0);
  const State y0 = run.y;
  rk4.do_step(rhs, run.y, t0, h);
  countStep(run);
  const double t1 = t0 + h;
  const State y1 = run.y;
  auto lerp = [&](double tt, State& ys) {
    const double a = (tt - t0) / h;
    for (int i = 0; i < 6; ++i) ys[i] = y0[i] + a * (y1[i] - y0[i]);
  };
  recordUpTo(run, t1 - 1e-13, lerp);
  run.t = t1;
  checkFinite(run, [&] { return "analytic.fixed_dt_s=" + std::to_string(dt) + " is too large"; });
  if (m.stiction()) {
    // A 2-D slide whose velocity turned by more than 90 deg over the step stopped inside it.
    const State& y = run.y;
    const bool reversed =
        m.translation() && !run.modes.stuck[kTrans] && y0[kVx] * y[kVx] + y0[kVy] * y[kVy] < 0;
    if (reversed) {
      Modes probe = run.modes;
      probe.stuck[kTrans] = true;
      const Eval e = evaluate(m, run.ws, run.t, run.y, probe);
      if (e.F_required.norm() < e.F_break) switchAt(run, kTrans);
    }
    switchAt(run, -1);
  }
  recordUpTo(run, run.t, [&](double, State& ys) { ys = run.y; });
}

// Once at rest for good: one evaluated row, then copies of it to the end.
void finishAtRest(Run& run) {
  if (!run.rec.done() && run.rec.nextTime() <= run.plan.t_end + 1e-12) {
    State ys = run.y;
    run.rec.record(run.model, run.ws, std::min(run.rec.nextTime(), run.plan.t_end), ys, run.modes);
    run.rec.repeatLastUntilDone();
  }
  run.t = run.plan.t_end;
}

// From t = 0 to the end of the run, segment by segment (breakpoints, switches).
void integrate(Run& run) {
  const double t_end = run.plan.t_end;
  while (run.t < t_end - 1e-15) {
    if (settled(run, run.t)) {
      finishAtRest(run);
      break;
    }
    const double seg_end = nextBreak(run, run.t);
    if (run.plan.adaptive && stuckForGood(run))
      heldChunk(run, seg_end);
    else if (run.plan.adaptive)
      adaptiveSegment(run, seg_end);
    else
      fixedStep(run, seg_end);
  }
}

// Summaries from the simulated state at t_end, not from the sampled rows (phi(0) = 0).
void summarize(const Run& run, RunSummary& sum) {
  const State& y = run.y;
  const AnalyticModel& m = run.model;
  sum.phi_net_deg = y[kPhi] * 180.0 / M_PI;
  const bool still = !m.stiction() || !run.modes.stuck[kRot];
  sum.t_stop_s = still ? run.plan.t_end : run.t_stop;
  sum.stick_slip_events = run.switches;
  sum.solver_steps = run.steps;
  sum.extra["rhs_evaluations"] = static_cast<double>(run.rhs);
  sum.extra["rejected_steps"] = static_cast<double>(run.rejected);
  sum.extra["held_steps"] = static_cast<double>(run.held);
  sum.extra["final_x_m"] = y[kX];
  sum.extra["final_y_m"] = y[kY];
  sum.extra["final_phidot_dps"] = y[kPhiDot] * 180.0 / M_PI;
  sum.extra["final_speed_mps"] = std::hypot(y[kVx], y[kVy]);
  sum.extra["still_rotating_at_end"] = still && std::abs(y[kPhiDot]) > 0 ? 1.0 : 0.0;
  sum.extra["ever_rotated"] = run.ever_rotated || !m.stiction() ? 1.0 : 0.0;
  // At rest: both DOFs stuck (stiction), or rate and speed below the documented thresholds.
  const double phidot_dps = std::abs(y[kPhiDot]) * 180.0 / M_PI, speed = std::hypot(y[kVx], y[kVy]);
  sum.at_rest = stuckForGood(run) || (phidot_dps < limits::kAtRestPhidotDps && speed < limits::kAtRestSpeedMps);
  if (!sum.at_rest) sum.warnings.push_back(notAtRestWarning(run.plan.t_end, phidot_dps, speed));
}

// The paper coupling's angular-momentum error: the turn its residual spin alone would cause
// before sliding friction (deceleration mu_d m g L_F / I_zz at the final pose) stops it,
// w^2 / (2 alpha); a warning above limits::kMaxPaperSpuriousTurnDeg.
void paperCouplingDiagnostic(Run& run, RunSummary& sum) {
  const AnalyticModel& m = run.model;
  const double w_res = paperResidualSpin(m.robot, m.traj);
  const Eval ev_end = evaluate(m, run.ws, run.plan.t_end, run.y, run.modes);
  const double alpha = m.needsArm() && std::isfinite(ev_end.L_F)
                           ? m.robot.friction.mu_d * m.weight * ev_end.L_F / ev_end.loads.Izz_kgm2
                           : 0.0;
  const double turn_deg = w_res == 0.0 ? 0.0 : alpha > 0 ? w_res * w_res / (2.0 * alpha) * 180.0 / M_PI
                                                        : std::numeric_limits<double>::infinity();
  sum.extra["paper_residual_spin_dps"] = w_res * 180.0 / M_PI;
  sum.extra["paper_spurious_turn_deg"] = turn_deg;
  if (turn_deg <= limits::kMaxPaperSpuriousTurnDeg) return;
  std::ostringstream os;
  os.precision(3);
  os << "the paper coupling's angular-momentum error is large: with mu = 0 it would leave the body spinning at "
     << w_res * 180.0 / M_PI << " deg/s after the tail stops (the exact coupling: 0), enough to turn it by "
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
    Run run(model, plan, output.sample_dt_s, stopSpeed(model, plan), output.time_series == TimeSeriesOutput::kThin);
    startAtRest(run);
    integrate(run);
    result.series = run.rec.take(model, run.ws);
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
