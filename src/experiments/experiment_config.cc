#include "experiments/experiment_config.h"

namespace tailsim {

TailTrajectory ExperimentCase::trajectory() const {
  TailTrajectory t;
  for (const SplitCycleParams& p : joints) t.joints.emplace_back(p);
  return t;
}

double ExperimentCase::simDuration() const {
  if (output.duration_s > 0.0) return output.duration_s;
  return trajectory().endTime() + output.settle_s;
}

}  // namespace tailsim
