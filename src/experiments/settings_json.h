// The resolved case as JSON: every parameter a run used, defaults included,
// written and read through the settings declarations (settings/fields.h). result.json's "resolved".
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "experiments/experiment_config.h"

namespace tailsim {

// {"experiment", "case", "sweep", "source_file", "robot_file", "kind", "models", "quadruped",
//  "friction", "gravity_mps2", "tail": [...], "joints": [...], "pose", "analytic", "mujoco",
//  "effects", "output", "render"}: SI values under the declared keys (angles of the resolved
// trajectory in rad, so the round trip is exact), enums by name.
nlohmann::json resolvedJson(const ExperimentCase& c);

// The inverse: the same ExperimentCase (throws std::runtime_error naming a missing or mistyped key).
ExperimentCase caseFromResolved(const nlohmann::json& j);

// The canonical text the resume key hashes: the resolved case without its file names (the robot's
// values count, not its file's name), the models run, whether the case is rendered (and the render
// settings only then), the tailsim version and git commit; sorted keys, round-trippable numbers.
std::string caseKeyText(const ExperimentCase& c, bool render);

// A tailsim build: its version and git commit (as in summary.json, result.json, cases.jsonl lines).
struct BuildId {
  std::string version, git_commit;
  bool operator==(const BuildId& o) const { return version == o.version && git_commit == o.git_commit; }
  bool operator!=(const BuildId& o) const { return !(*this == o); }
};
BuildId thisBuild();
// The key text as the build `b` computes it (resume and merge recognise another build's results).
std::string caseKeyText(const ExperimentCase& c, bool render, const BuildId& b);

}  // namespace tailsim
