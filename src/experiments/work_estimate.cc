#include "experiments/work_estimate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "common/work_limits.h"
#include "common/number_text.h"
#include "common/units.h"

namespace tailsim {
namespace {

std::string g(double v) { return formatG(v, 3); }

// The keys that set the simulated time, most likely culprit first.
std::vector<std::string> timeKeys(const ExperimentCase& c) {
  if (c.output.duration_s > 0) return {"output.duration_s"};
  double t0 = 0;
  for (const JointProfile& j : c.trajectory().joints) t0 = std::max(t0, j.params().t0_s);
  if (t0 > c.output.settle_s) return {"trajectory.t0_s", "output.settle_s", "trajectory.dT_s"};
  return {"output.settle_s", "trajectory.t0_s", "trajectory.dT_s"};
}

void append(std::vector<std::string>& a, const std::vector<std::string>& b) { a.insert(a.end(), b.begin(), b.end()); }

const std::string kSeeLimits = " (docs/experiment-format.md \"Limits\")";

}  // namespace

double WorkEstimate::solverSteps() const {
  double s = 0;
  for (const ModelSteps& m : model_steps) s += m.steps.steps;
  return s;
}

StepLimit analyticStepEstimate(const ExperimentCase& c) {
  StepLimit s;
  s.limit = limits::kMaxAnalyticSteps;
  const TailTrajectory traj = c.trajectory();
  // While the tail moves (t0 delay included) the adaptive step is at most max_step_s, by default
  // 1/8 of the shortest phase of the joints moving in each segment between two breakpoints
  // (analytic_simulation.cc segmentScales); the fixed step is fixed_dt_s.
  const double moving_until = std::min(traj.endTime(), c.simDuration());
  const bool fixed = c.analytic.solver == AnalyticSolver::kFixed;
  if (fixed || c.analytic.max_step_s > 0) {
    const double h = fixed ? c.analytic.fixed_dt_s : c.analytic.max_step_s;
    s.steps = moving_until / h;
  } else {
    // A segment where no joint moves before the tail's end (a start delay) keeps the run's bound.
    const double shortest = traj.shortestPhase();
    std::vector<double> b = traj.breakpoints();
    b.insert(b.begin(), 0.0);
    for (std::size_t k = 0; k + 1 < b.size() && b[k] < moving_until; ++k) {
      const double lo = b[k], hi = std::min(b[k + 1], moving_until);
      const double phase = traj.shortestActivePhase(0.5 * (lo + hi));
      if (hi > lo) s.steps += (hi - lo) / ((std::isfinite(phase) ? phase : shortest) / 8.0);
    }
  }
  return s;
}

WorkExcess analyticStepExcess(const ExperimentCase& c, const StepLimit& s) {
  WorkExcess x;
  const bool fixed = c.analytic.solver == AnalyticSolver::kFixed;
  x.keys = {fixed ? "analytic.fixed_dt_s" : "analytic.max_step_s", "trajectory.t0_s", "trajectory.dT_s"};
  x.what = "the analytic model would take at least " + g(s.steps) + " steps (tail motion until t = " +
           g(std::min(c.trajectory().endTime(), c.simDuration())) + " s / step " +
           (fixed ? g(c.analytic.fixed_dt_s) : g(c.analytic.max_step_s > 0 ? c.analytic.max_step_s : 0.0)) +
           " s), more than the limit " + g(s.limit) + kSeeLimits;
  if (!fixed && !(c.analytic.max_step_s > 0))
    x.what = "the analytic model would take at least " + g(s.steps) +
             " steps (its step is at most 1/8 of the shortest acceleration or deceleration phase of the joints "
             "moving at each time), more "
             "than the limit " + g(s.limit) + kSeeLimits;
  return x;
}

StepLimit mujocoStepEstimate(const ExperimentCase& c) {
  StepLimit s;
  s.limit = limits::kMaxMujocoSteps;
  const double sim_time_s = c.simDuration();
  s.steps = (c.mujoco.settle_s + sim_time_s) / c.mujoco.timestep_s;
  return s;
}

WorkExcess mujocoStepExcess(const ExperimentCase& c, const StepLimit& s) {
  WorkExcess x;
  const double sim_time_s = c.simDuration();
  x.keys = c.mujoco.timestep_s < MujocoSettings{}.timestep_s ? std::vector<std::string>{"mujoco.timestep_s"}
                                                              : std::vector<std::string>{};
  if (c.mujoco.settle_s > sim_time_s) x.keys.push_back("mujoco.settle_s");
  append(x.keys, timeKeys(c));
  x.keys.push_back("mujoco.settle_s");
  x.keys.push_back("mujoco.timestep_s");
  x.what = "MuJoCo would take " + g(s.steps) + " steps ((mujoco.settle_s " + g(c.mujoco.settle_s) + " s + " +
           g(sim_time_s) + " s simulated) / timestep_s " + g(c.mujoco.timestep_s) + " s), more than the limit " +
           g(s.limit) + kSeeLimits;
  return x;
}

WorkEstimate estimateWork(const ExperimentCase& c) {
  WorkEstimate w;
  if (c.kind != CaseKind::kSimulate) return w;
  const int n = c.robot.numLinks();
  w.sim_time_s = c.simDuration();
  w.rows = c.output.rows(w.sim_time_s);
  double cols = 0;
  bool shown = false;
  for (const ModelEntry& m : modelRegistry()) {
    if (std::find(c.models.begin(), c.models.end(), m.name) == c.models.end()) continue;
    w.models.push_back(&m);
    cols = std::max(cols, static_cast<double>(m.columns(n).size()));
    if (m.steps) w.model_steps.push_back({&m, m.steps(c)});
    shown = shown || m.render_rank > 0;
  }
  if (shown && c.render.enabled) {
    const double on_screen = c.render.duration_s > 0 ? std::min(c.render.duration_s, w.sim_time_s) : w.sim_time_s;
    w.render_frames = std::floor(on_screen * c.render.fps * c.render.slowmo) + 1;
    w.render_samples = w.render_frames * c.render.width * c.render.height * std::max(1, c.render.msaa);
  }
  w.csv_bytes = w.rows * cols * limits::kCsvBytesPerValue;
  return w;
}

WorkExcess checkWork(const ExperimentCase& c) {
  WorkExcess x;
  if (c.kind != CaseKind::kSimulate) return x;
  if (c.render.enabled) {  // a video draws the model of the highest render_rank that ran (render_case.h)
    std::string drawn;
    bool any = false;
    for (const ModelEntry& m : modelRegistry()) {
      if (m.render_rank <= 0) continue;
      drawn += (drawn.empty() ? "" : " or ") + m.name;
      any = any || std::find(c.models.begin(), c.models.end(), m.name) != c.models.end();
    }
    if (!any) {
      x.keys = {"render", "models"};
      x.what = "a video needs the " + drawn + " model (the ones it can draw), and models has none of them: add one to models, "
               "or remove render";
      return x;
    }
  }
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
  for (const WorkEstimate::ModelSteps& m : w.model_steps)
    if (m.steps.limit > 0 && !(m.steps.steps <= m.steps.limit) && m.model->too_many_steps)
      return m.model->too_many_steps(c, m.steps);
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
    const double w = units::degrees(std::abs(traj.joints[i].peakSpeed()));
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
    t.steps += w.solverSteps();
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
    return "the " + n + " would take about " + g(w.steps) + " solver steps in all (every model's steps, " +
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
