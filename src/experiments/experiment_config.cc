#include "experiments/experiment_config.h"

namespace tailsim {

TailTrajectory ExperimentCase::trajectory() const {
  TailTrajectory t;
  for (const SplitCycleParams& p : joints) t.joints.emplace_back(p);
  for (const SplineParams& p : splines) t.joints.emplace_back(p);
  return t;
}

double ExperimentCase::simDuration() const {
  if (output.duration_s > 0.0) return output.duration_s;  // no trajectory to build
  return output.runEnd(trajectory().endTime());
}

std::vector<std::string> sectionKeys() {
  std::vector<std::string> keys;
  ExperimentCase c;
  forEachSection(c, [&](const SectionInfo& s, const auto&) { keys.push_back(s.key); });
  return keys;
}

}  // namespace tailsim
