#include "experiments/work_estimate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "results/work_limits.h"

namespace tailsim {
namespace {

bool has(const std::vector<std::string>& v, const char* s) { return std::find(v.begin(), v.end(), s) != v.end(); }

std::string g(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

// Output columns per model run (analytic_simulation.cc Recorder, mujoco_simulation.cc makeColumns).
double analyticColumns(int n) { return 1 + 3 * n + 20; }
double mujocoColumns(int n) { return 1 + 3 * n + 14 + 8 + n; }

// The keys that set the simulated time, most likely culprit first.
std::vector<std::string> timeKeys(const ExperimentCase& c) {
  if (c.output.duration_s > 0) return {"output.duration_s"};
  double t0 = 0;
  for (const JointProfile& j : c.trajectory().joints) t0 = std::max(t0, j.params().t0_s);
  if (t0 > c.output.settle_s) return {"trajectory.t0_s", "output.settle_s", "trajectory.dT_s"};
  return {"output.settle_s", "trajectory.t0_s", "trajectory.dT_s"};
}

void append(std::vector<std::string>& a, const std::vector<std::string>& b) { a.insert(a.end(), b.begin(), b.end()); }

}  // namespace

WorkEstimate estimateWork(const ExperimentCase& c) {
  WorkEstimate w;
  if (c.kind != CaseKind::kSimulate) return w;
  const int n = c.robot.numLinks();
  const TailTrajectory traj = c.trajectory();
  const double tail_end = traj.endTime();
  w.sim_time_s = c.simDuration();
  w.rows = std::floor(w.sim_time_s / c.output.sample_dt_s) + 1;
  double cols = 0;
  if (has(c.models, "analytic")) {
    cols = std::max(cols, analyticColumns(n));
    // While the tail moves (t0 delay included) the adaptive step is at most max_step_s, by default
    // 1/8 of the shortest phase of the joints moving in each segment between two breakpoints
    // (analytic_simulation.cc segmentScales); the fixed step is fixed_dt_s.
    const double moving_until = std::min(tail_end, w.sim_time_s);
    if (c.analytic.solver == AnalyticSolver::kFixed || c.analytic.max_step_s > 0) {
      const double h = c.analytic.solver == AnalyticSolver::kFixed ? c.analytic.fixed_dt_s : c.analytic.max_step_s;
      w.analytic_steps = moving_until / h;
    } else {
      // A segment where no joint moves before the tail's end (a start delay) keeps the run's bound.
      const double shortest = traj.shortestPhase();
      std::vector<double> b = traj.breakpoints();
      b.insert(b.begin(), 0.0);
      for (std::size_t k = 0; k + 1 < b.size() && b[k] < moving_until; ++k) {
        const double lo = b[k], hi = std::min(b[k + 1], moving_until);
        const double phase = traj.shortestActivePhase(0.5 * (lo + hi));
        if (hi > lo) w.analytic_steps += (hi - lo) / ((std::isfinite(phase) ? phase : shortest) / 8.0);
      }
    }
  }
  if (has(c.models, "mujoco")) {
    cols = std::max(cols, mujocoColumns(n));
    w.mujoco_steps = (c.mujoco.settle_s + w.sim_time_s) / c.mujoco.timestep_s;
  }
  // A video replays the time series of whichever models ran, so it counts for every model set.
  if (c.render.enabled) {
    const double shown = c.render.duration_s > 0 ? std::min(c.render.duration_s, w.sim_time_s) : w.sim_time_s;
    w.render_frames = std::floor(shown * c.render.fps * c.render.slowmo) + 1;
    w.render_samples = w.render_frames * c.render.width * c.render.height * std::max(1, c.render.msaa);
  }
  w.csv_bytes = w.rows * cols * limits::kCsvBytesPerValue;
  return w;
}

WorkExcess checkWork(const ExperimentCase& c) {
  WorkExcess x;
  if (c.kind != CaseKind::kSimulate) return x;
  const WorkEstimate w = estimateWork(c);
  const std::string see = " (docs/experiment-format.md \"Limits\")";
  const std::string span = g(w.sim_time_s) + " s simulated";
  // !(a <= b): an infinite or NaN estimate fails too.
  if (!(w.rows <= limits::kMaxRowsPerRun) || !(w.csv_bytes <= limits::kMaxCsvBytesPerRun)) {
    x.keys = c.output.sample_dt_s < OutputSettings{}.sample_dt_s ? std::vector<std::string>{"output.sample_dt_s"}
                                                                  : std::vector<std::string>{};
    append(x.keys, timeKeys(c));
    x.keys.push_back("output.sample_dt_s");
    x.what = "the run would write " + g(w.rows) + " rows per model (" + span + " / sample_dt_s " +
             g(c.output.sample_dt_s) + " s, about " + g(w.csv_bytes) + " bytes of CSV); the limits are " +
             g(limits::kMaxRowsPerRun) + " rows and " + g(limits::kMaxCsvBytesPerRun) +
             " bytes per model run" + see + ": raise sample_dt_s or shorten the run";
    return x;
  }
  if (!(w.analytic_steps <= limits::kMaxAnalyticSteps)) {
    const bool fixed = c.analytic.solver == AnalyticSolver::kFixed;
    x.keys = {fixed ? "analytic.fixed_dt_s" : "analytic.max_step_s", "trajectory.t0_s", "trajectory.dT_s"};
    x.what = "the analytic model would take at least " + g(w.analytic_steps) + " steps (tail motion until t = " +
             g(std::min(c.trajectory().endTime(), w.sim_time_s)) + " s / step " +
             (fixed ? g(c.analytic.fixed_dt_s) : g(c.analytic.max_step_s > 0 ? c.analytic.max_step_s : 0.0)) +
             " s), more than the limit " + g(limits::kMaxAnalyticSteps) + see;
    if (!fixed && !(c.analytic.max_step_s > 0))
      x.what = "the analytic model would take at least " + g(w.analytic_steps) +
               " steps (its step is at most 1/8 of the shortest acceleration or deceleration phase of the joints "
               "moving at each time), more "
               "than the limit " + g(limits::kMaxAnalyticSteps) + see;
    return x;
  }
  if (!(w.mujoco_steps <= limits::kMaxMujocoSteps)) {
    x.keys = c.mujoco.timestep_s < MujocoSettings{}.timestep_s ? std::vector<std::string>{"mujoco.timestep_s"}
                                                                : std::vector<std::string>{};
    if (c.mujoco.settle_s > w.sim_time_s) x.keys.push_back("mujoco.settle_s");
    append(x.keys, timeKeys(c));
    x.keys.push_back("mujoco.settle_s");
    x.keys.push_back("mujoco.timestep_s");
    x.what = "MuJoCo would take " + g(w.mujoco_steps) + " steps ((mujoco.settle_s " + g(c.mujoco.settle_s) + " s + " +
             span + ") / timestep_s " + g(c.mujoco.timestep_s) + " s), more than the limit " +
             g(limits::kMaxMujocoSteps) + see;
    return x;
  }
  if (!(w.render_frames <= limits::kMaxRenderFrames)) {
    x.keys = {"render.slowmo", "render.fps", "render.duration_s"};
    append(x.keys, timeKeys(c));
    x.what = "the video would have " + g(w.render_frames) + " frames (shown sim time x slowmo " + g(c.render.slowmo) +
             " x fps " + std::to_string(c.render.fps) + "), more than the limit " + g(limits::kMaxRenderFrames) + see;
    return x;
  }
  return x;
}

std::string jointSpeedWarning(const ExperimentCase& c) {
  if (c.kind != CaseKind::kSimulate) return "";
  const TailTrajectory traj = c.trajectory();
  double peak = 0;
  std::size_t at = 0;
  for (std::size_t i = 0; i < traj.joints.size(); ++i) {
    const double w = std::abs(traj.joints[i].peakSpeed()) * 180.0 / M_PI;
    if (w > peak) {
      peak = w;
      at = i;
    }
  }
  if (!(peak > limits::kMaxJointSpeedDps)) return "";
  return "tail joint " + std::to_string(at + 1) + " peaks at " + g(peak) + " deg/s, above " +
         g(limits::kMaxJointSpeedDps) + " deg/s (100 turns a second, beyond any tail motor; " +
         "docs/experiment-format.md \"Limits\"): the result describes a stroke no robot makes";
}

WorkTotal totalWork(const std::vector<ExperimentCase>& cases) {
  WorkTotal t;
  t.cases = static_cast<double>(cases.size());
  for (const ExperimentCase& c : cases) {
    if (c.kind != CaseKind::kSimulate) continue;
    const WorkEstimate w = estimateWork(c);
    t.steps += w.analytic_steps + w.mujoco_steps;
    t.samples += w.render_samples;
    t.frames += w.render_frames;
    const double share = c.output.time_series == TimeSeriesOutput::kNone   ? 0.0
                         : c.output.time_series == TimeSeriesOutput::kThin ? 0.1
                                                                            : 1.0;
    t.bytes += share * w.csv_bytes * static_cast<double>(c.models.size());
  }
  return t;
}

WorkTotal& operator+=(WorkTotal& a, const WorkTotal& b) {
  a.cases += b.cases;
  a.steps += b.steps;
  a.bytes += b.bytes;
  a.samples += b.samples;
  a.frames += b.frames;
  return a;
}

std::string workTotalExcess(const WorkTotal& w, const std::string& n) {
  const std::string see = " (docs/experiment-format.md \"Limits\")";
  if (!(w.steps <= limits::kMaxExperimentSteps))
    return "the " + n + " would take about " + g(w.steps) + " solver steps in all (analytic steps + MuJoCo steps, " +
           "summed over the cases), more than the limit " + g(limits::kMaxExperimentSteps) + see +
           ": sweep fewer values or split the experiment";
  if (!(w.bytes <= limits::kMaxExperimentBytes))
    return "the " + n + " would write about " + g(w.bytes) + " bytes of time series in all (rows x columns x " +
           g(limits::kCsvBytesPerValue) + " B per model run, summed over the cases), more than the limit " +
           g(limits::kMaxExperimentBytes) + see + ": set output.time_series: thin or none, raise output.sample_dt_s, " +
           "or sweep fewer values";
  if (!(w.samples <= limits::kMaxExperimentRenderSamples))
    return "the " + n + " would render about " + g(w.frames) + " video frames, " + g(w.samples) +
           " samples in all (frames x render.width x render.height x render.msaa, summed over the cases), more "
           "than the limit " + g(limits::kMaxExperimentRenderSamples) + " (about 14 hours of rendering)" + see +
           ": lower render.width, render.height, render.msaa, render.fps or render.slowmo, set render.duration_s, "
           "or sweep fewer values";
  return "";
}

WorkExcess checkExperimentWork(const std::vector<ExperimentCase>& cases) {
  WorkExcess x;
  x.what = workTotalExcess(totalWork(cases), std::to_string(cases.size()) + (cases.size() == 1 ? " case" : " cases"));
  return x;
}

}  // namespace tailsim
