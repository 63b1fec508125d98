// The work a case asks for, estimated before it runs (docs/experiment-format.md "Limits"): the
// one place that turns a case's settings into rows, CSV bytes, solver steps and video frames.
// The loader refuses a case over a limit of common/work_limits.h with file:line:col.
#pragma once

#include <string>
#include <vector>

#include "experiments/experiment_config.h"
#include "experiments/model_registry.h"

namespace tailsim {

struct WorkEstimate {
  double sim_time_s = 0;      // simulated time after t = 0 (duration_s, or tail end + settle_s)
  double rows = 0;            // output rows per model run
  double csv_bytes = 0;       // estimated CSV size of the largest model run (its registry columns)  [B]
  // The solver steps of each model the case runs that estimates them (ModelEntry::steps), in
  // registry order.
  struct ModelSteps {
    const ModelEntry* model = nullptr;
    StepLimit steps;
  };
  std::vector<ModelSteps> model_steps;
  std::vector<const ModelEntry*> models;  // the case's models, in registry order
  double render_frames = 0;   // shown sim time x slowmo x fps (0 without a render section or a model to show)
  double render_samples = 0;  // render_frames x width x height x MSAA samples (1 without MSAA)
  // Every model's solver steps, summed.
  double solverSteps() const;
};

WorkEstimate estimateWork(const ExperimentCase& c);

// The built-in models' solver work (their registry entries' `steps`): the analytic model's accepted
// steps while the tail moves (at most max_step_s each, by default 1/8 of the shortest phase of the
// joints moving in each segment between two breakpoints; fixed_dt_s with the fixed step), and
// MuJoCo's (mujoco.settle_s + sim time) / timestep_s.
// `...StepExcess`: the refusal of a case whose estimate exceeds the limit.
StepLimit analyticStepEstimate(const ExperimentCase& c);
WorkExcess analyticStepExcess(const ExperimentCase& c, const StepLimit& s);
StepLimit mujocoStepEstimate(const ExperimentCase& c);
WorkExcess mujocoStepExcess(const ExperimentCase& c, const StepLimit& s);

// A limit the estimate exceeds: WorkExcess (model_registry.h), `keys` the dotted keys that set it,
// most likely culprit first (the loader reports the first one the file sets); `what` says which
// estimate, its value, how it was computed and the limit.

// Empty `what` when every estimate is within its limit. kind: pose cases do no work to bound.
WorkExcess checkWork(const ExperimentCase& c);

// A run warning when a joint of the case's trajectory peaks above limits::kMaxJointSpeedDps, else "".
std::string jointSpeedWarning(const ExperimentCase& c);

// The whole experiment's work: solver steps (every model's), time-series bytes and rendered
// samples (frames x pixels x MSAA) summed over its cases and models (output.time_series: none writes
// none, thin about a tenth), against limits::kMaxExperimentSteps, kMaxExperimentBytes and
// kMaxExperimentRenderSamples. Empty `what` when within both; `keys` empty
// (the sweeps as a whole are the culprit).
WorkExcess checkExperimentWork(const std::vector<ExperimentCase>& cases);

// Those sums, to bound the members of a suite together (a suite of N members could ask N times
// what one experiment may): `cases` counts every case.
struct WorkTotal {
  double cases = 0, steps = 0, bytes = 0, samples = 0, frames = 0;
};
WorkTotal totalWork(const std::vector<ExperimentCase>& cases);
WorkTotal& operator+=(WorkTotal& a, const WorkTotal& b);
// What exceeds the whole-experiment limits ("" when within); `n` names the cases ("the <n> would ...").
std::string workTotalExcess(const WorkTotal& w, const std::string& n);

}  // namespace tailsim
