// The stick/slip run both planar models (analytic, per-foot) share, in stages: the model plans the
// run and starts it (its modes at t = 0), then integrate() goes segment by segment between the
// breakpoints of the tail profile: a body stiction holds is scanned, not integrated (heldChunk);
// otherwise adaptive dense-output Dormand-Prince steps (adaptiveSegment), every step's event
// margins scanned for the first switch (findSwitch, stick_slip.h); the rows are recorded on the
// sample grid as the run passes them (PlanarRecorder) and copied once it is at rest for good
// (finishAtRest). The model summarizes the run.
//
// The models differ only in the `Model` the driver is instantiated with (its right-hand side,
// margins, switches and columns):
//   using State;  static constexpr bool kDefersRowsInSteps, kHitOnlyWithinStep, kFillsGridToEnd;
//   columns(), fillRow(t, y, modes, out), phi(y): the rows (PlanarRecorder);
//   stiction(), translation();
//   held(modes): every DOF stuck, nothing moves (scanned in held chunks, not integrated);
//   scales(plan, t, seg_end) -> SegmentScales: event sampling and step bound over a segment;
//   scansSteps(): a solver step's margins are scanned; keepsScanEnd(): its scan's end starts the next;
//   scanModes(modes), margins(t, y, modes) -> Margins: what findSwitch scans;
//   onHit(f, y_at_f, modes): a located event that ends the run (throws), else nothing;
//   onHeldScan(f, hit, y, modes, end): a held chunk was scanned;
//   switchAt(t, y, modes, which): switches DOF `which` (-1: none) and settles the modes;
//   firstStep(dt0, y, modes): the first trial step after a switch;
//   derivative(t, y, modes, dy);  settings(): abs_tol, rel_tol, event_tol_s, max_steps;
//   stepBudgetMessage(t, t_end, held), nonFiniteMessage(t).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "models/planar/planar_recorder.h"
#include "models/planar/step_control.h"
#include "models/planar/stick_slip.h"

namespace tailsim {

// What a run needs to know before it starts: its end, its rows, its step sizes.
struct RunPlan {
  double t_end = 0;     // [s]
  long rows = 0;        // output rows
  double tail_end = 0;  // the tail stops moving  [s]
  double h_scan = 0;    // event sampling interval, the shortest phase of all / 32  [s]
  double h_max = 0;     // adaptive step bound while the tail moves, the shortest phase of all / 8  [s]
  bool adaptive = true;
};

// Event sampling interval and step bound over one segment between two tail breakpoints.
struct SegmentScales {
  double h_scan, h_max;
};

// One run in progress: the model, the plan, the output and the state.
template <class Model>
struct PlanarRun {
  using State = typename Model::State;
  using Stepper = StabilizedDenseDopri5<State>;

  PlanarRun(Model& m, const RunPlan& p, const std::vector<double>& breaks, double sample_dt_s, bool thin)
      : model(m), plan(p), breakpoints(breaks), rec(m, sample_dt_s, p.rows, thin ? &breakpoints : nullptr) {}

  Model& model;
  const RunPlan& plan;
  std::vector<double> breakpoints;  // of the tail profile (also thinning's marks)
  PlanarRecorder<Model> rec;
  State y{};
  Modes modes;
  double t = 0.0;
  long steps = 0;          // accepted solver steps (and held chunks)
  long rhs = 0;            // right-hand sides the solver evaluated (accepted and rejected trial steps)
  long rejected = 0;       // trial steps the error control rejected
  long held = 0;           // held chunks (scanned, not integrated)
  double dt_resume = 0.0;  // the step to restart with after a tail breakpoint (0: after a switch)
  double held_dt = 0.0;    // heldChunk: the chunk to go on with (0: after a switch, start small)
  // The last step's scan, kept while the modes stay: its end margins start the next scan; when
  // the next scan must look across its end (a stuck margin still falling there, dipMayCross),
  // its last two samples and its dense output too.
  struct Carry {
    bool have = false;    // end holds the scan of the step that ended at t_end
    bool across = false;  // and stepper its dense output: the next scan looks across t_end
    double t_end = 0;
    ScanEnd end;
    std::optional<Stepper> stepper;
  } carry;
};

namespace planar_driver {

// Switches DOF `which` (or none, -1) at run.t, then settles the modes.
template <class Model>
void switchAt(PlanarRun<Model>& run, int which) {
  run.held_dt = 0.0;
  run.model.switchAt(run.t, run.y, run.modes, which);
}

// At rest with the tail still: nothing will change any more.
template <class Model>
bool settled(const PlanarRun<Model>& run, double t) {
  return t >= run.plan.tail_end && run.model.held(run.modes);
}

// The next breakpoint of the tail profile after t (or the end of the run).
template <class Model>
double nextBreak(const PlanarRun<Model>& run, double t) {
  for (double b : run.breakpoints)
    if (b > t + 1e-14) return std::min(b, run.plan.t_end);
  return run.plan.t_end;
}

// Records every sample up to t_hi, with stateAt(t, y) the state there.
template <class Model, class StateAt>
void recordUpTo(PlanarRun<Model>& run, double t_hi, const StateAt& stateAt) {
  typename Model::State ys;
  while (!run.rec.done() && run.rec.nextTime() <= t_hi + 1e-12) {
    const double ts = std::min(run.rec.nextTime(), run.plan.t_end);
    stateAt(ts, ys);
    run.rec.record(ts, ys, run.modes);
  }
}

template <class Model>
void checkFinite(const PlanarRun<Model>& run) {
  for (double v : run.y)
    if (!std::isfinite(v)) throw std::runtime_error(run.model.nonFiniteMessage(run.t));
}

// Step budget: a run that needs more steps fails with the model's message instead of running on.
template <class Model>
void countStep(PlanarRun<Model>& run, bool held) {
  ++run.steps;
  if (run.steps > run.model.settings().max_steps)
    throw std::runtime_error(run.model.stepBudgetMessage(run.t, run.plan.t_end, held));
}

// The first switch in [ta, tb] of the margins at stateAt's states (stick_slip.h findSwitch).
template <class Model, class StateAt>
Found scan(PlanarRun<Model>& run, const StateAt& stateAt, double ta, double tb, double h_scan, const ScanEnd* prev,
           ScanEnd* end, bool across) {
  typename Model::State ys;
  auto gAt = [&](double tt) {
    stateAt(tt, ys);
    return run.model.margins(tt, ys, run.modes);
  };
  return findSwitch(gAt, run.model.scanModes(run.modes), ta, tb, h_scan, run.model.settings().event_tol_s, prev, end,
                    across);
}

// Whether a located switch f ends the step at tb.
template <class Model>
bool isHit(const Found& f, double tb) {
  return f.hit && (!Model::kHitOnlyWithinStep || f.t <= tb);
}

// While every DOF is stuck the body does not move: its state is constant and there is nothing
// to integrate. The margins are scanned chunk by chunk as a solver step's would be, with the
// state held; a margin still falling at the chunk's end carries into the next chunk's scan (a
// dip across the boundary), and the rows after its second-last sample wait for that scan. The
// chunks grow as the solver's steps would with no error to control: 1e-4 s after a switch, then
// 10 times the last one, up to the step bound (across a tail breakpoint too). So a margin's dip
// right after a switch is sampled finely: a chunk has no sample before its start to show a dip
// whose lowest sample is that start. One chunk counts as one solver step and costs no
// right-hand side.
template <class Model>
void heldChunk(PlanarRun<Model>& run, double seg_end) {
  using State = typename Model::State;
  const double t_end = run.plan.t_end;
  const SegmentScales scales = run.model.scales(run.plan, run.t, seg_end);
  const double dt = std::min(run.held_dt > 0.0 ? run.held_dt : 1e-4, scales.h_max);
  const double ta = run.t, tb = std::min(seg_end, ta + dt);
  const State y = run.y;
  auto stateAt = [&](double, State& ys) { ys = y; };
  auto& carry = run.carry;
  const bool have = carry.have && carry.t_end == ta;
  ScanEnd end;
  const Found f = scan(run, stateAt, ta, tb, scales.h_scan, have ? &carry.end : nullptr, &end, have && carry.across);
  if (f.hit) run.model.onHit(f, y, run.modes);
  const bool hit = isHit<Model>(f, tb);
  run.model.onHeldScan(f, hit, y, run.modes, end);
  countStep(run, true);
  ++run.held;
  run.dt_resume = 0.0;
  run.held_dt = 10.0 * (tb - ta);  // (switchAt below resets it)
  const double t_cut = hit ? f.t : tb;
  const bool defer = !hit && dipMayCross(run.model.scanModes(run.modes), end) && tb < t_end - 1e-15 &&
                     !settled(run, tb);
  recordUpTo(run, defer ? end.t_before : t_cut, stateAt);
  run.t = t_cut;
  carry.stepper.reset();
  if (hit) {
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
template <class Model>
void adaptiveSegment(PlanarRun<Model>& run, double seg_end) {
  using State = typename Model::State;
  Model& m = run.model;
  const auto& s = m.settings();
  const double t_end = run.plan.t_end;
  const bool tail_moving = run.t < run.plan.tail_end;
  const SegmentScales scales = m.scales(run.plan, run.t, seg_end);
  const double max_dt =
      (tail_moving || run.modes.stuck[kRot] || run.modes.stuck[kTrans]) ? scales.h_max : (t_end - run.t);
  auto rhs = [&](const State& x, State& dx, double tt) {
    ++run.rhs;
    m.derivative(tt, x, run.modes, dx);
  };
  auto stepper = makeStabilizedDopri5<State>(s.abs_tol, s.rel_tol, max_dt, &run.rejected);
  // After a switch the dynamics change: start small. After a tail breakpoint they continue with
  // a jump in the tail acceleration only: go on with the step size the solver had reached.
  double dt0 = std::min(max_dt, run.dt_resume > 0 ? run.dt_resume : 1e-4);
  if (run.dt_resume == 0.0) dt0 = m.firstStep(dt0, run.y, run.modes);
  run.dt_resume = 0.0;
  stepper.initialize(run.y, run.t, dt0);
  for (;;) {
    // A step that would cross the next breakpoint (where the tail acceleration jumps) ends on it
    // instead: across it the error estimate fails and the step is rejected over and over.
    const double t_now = stepper.current_time(), dt_now = stepper.current_time_step();
    if (t_now + dt_now > seg_end && seg_end - t_now > 1e-12)
      stepper.initialize(stepper.current_state(), t_now, seg_end - t_now);
    // (two names, not a structured binding: C++17 lambdas cannot capture those; clang refuses)
    const std::pair<double, double> step = stepper.do_step(rhs);
    const double ta = step.first, tb_raw = step.second;
    countStep(run, false);
    const double tb = std::min(tb_raw, seg_end);
    auto& carry = run.carry;
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
    if (m.scansSteps()) {
      f = scan(run, stateAt, ta, tb, scales.h_scan, have ? &carry.end : nullptr, &end, across);
      if (f.hit) {
        State yf;
        stateAt(f.t, yf);
        m.onHit(f, yf, run.modes);
      }
    }
    const bool hit = isHit<Model>(f, tb);
    const double t_cut = hit ? f.t : tb;
    // A margin still falling at tb may dip below zero just after it: the rows after the last
    // sample before tb wait until the next step's scan has looked (the switch may come first).
    const bool defer = Model::kDefersRowsInSteps && !hit && m.scansSteps() &&
                       dipMayCross(m.scanModes(run.modes), end) && tb < t_end - 1e-15 && !settled(run, tb);
    recordUpTo(run, defer ? end.t_before : t_cut, stateAt);
    stateAt(t_cut, run.y);
    run.t = t_cut;
    checkFinite(run);
    if (hit) {
      carry.have = carry.across = false;
      switchAt(run, f.which);
      return;
    }
    carry.have = m.keepsScanEnd() && !f.hit;
    carry.across = Model::kDefersRowsInSteps ? defer : carry.have;
    carry.t_end = tb;
    carry.end = end;
    if (carry.across) carry.stepper = stepper;
    if (tb_raw >= seg_end - 1e-15) {  // a breakpoint of the tail profile: restart the step there
      if (tb_raw <= seg_end + 1e-12) run.dt_resume = std::max(stepper.current_time_step(), tb_raw - ta);
      return;
    }
    if (run.t >= t_end - 1e-15 || settled(run, run.t)) return;
    // The solver's internal state may lie beyond t (when tb was clipped): continue from t.
    if (stepper.current_time() > run.t + 1e-15) return;
  }
}

// Once at rest for good: one evaluated row, then copies of it to the end.
template <class Model>
void finishAtRest(PlanarRun<Model>& run) {
  if (!run.rec.done() && (Model::kFillsGridToEnd || run.rec.nextTime() <= run.plan.t_end + 1e-12)) {
    const typename Model::State ys = run.y;
    run.rec.record(std::min(run.rec.nextTime(), run.plan.t_end), ys, run.modes);
    run.rec.repeatLastUntilDone();
  }
  run.t = run.plan.t_end;
}

}  // namespace planar_driver

// From run.t (the model has set the starting state and modes) to the end of the run, segment by
// segment (breakpoints, switches). fixedStep(run, seg_end): the step of a fixed-step solver
// (run.plan.adaptive false); nullptr where the model has none.
template <class Model, class FixedStep = std::nullptr_t>
void integrate(PlanarRun<Model>& run, const FixedStep& fixedStep = nullptr) {
  using namespace planar_driver;
  const double t_end = run.plan.t_end;
  while (run.t < t_end - 1e-15) {
    if (settled(run, run.t)) {
      finishAtRest(run);
      break;
    }
    const double seg_end = nextBreak(run, run.t);
    if (run.plan.adaptive && run.model.held(run.modes)) {
      heldChunk(run, seg_end);
    } else if (run.plan.adaptive) {
      adaptiveSegment(run, seg_end);
    } else {
      if constexpr (std::is_same_v<FixedStep, std::nullptr_t>)
        throw std::logic_error("planar run: a fixed-step plan for a model without a fixed-step solver");
      else
        fixedStep(run, seg_end);
    }
  }
  if constexpr (Model::kFillsGridToEnd) {
    const typename Model::State y = run.y;
    recordUpTo(run, t_end, [&](double, typename Model::State& ys) { ys = y; });
  }
}

}  // namespace tailsim
