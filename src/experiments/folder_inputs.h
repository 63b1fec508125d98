// The inputs a result folder keeps so that it runs again on its own (docs/ARCHITECTURE.md
// "Result folder"): a copy of the robot file, the experiment file with its `robot:` pointing at
// that copy, and the generated MJCF of each distinct MuJoCo model.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "experiments/experiment_loader.h"

namespace tailsim {

// What DIR/ holds of an experiment's inputs, as file name (relative to DIR) -> contents.
// "experiment.yaml" is the experiment file's text with the value of `robot:` (or each value of a
// `robot: {sweep: [...]}`) replaced by the name of its copy; everything else, comments included,
// is kept byte for byte. The robot file (a built-in robot too) becomes "robot.yaml" (a swept
// robot: "robot-<k>.yaml", k = 1.. in sweep order). Throws std::runtime_error naming the file.
std::map<std::string, std::string> folderInputs(const Experiment& e);

// The text of a YAML file with the value at `path` (keys from the top, e.g. {"maneuver",
// "stroke_from"}: a scalar written on one line) replaced by `by` (written as a plain scalar);
// everything else kept byte for byte. Throws std::runtime_error naming the file when the key is
// missing or not such a scalar.
std::string withValueAt(const std::string& file, const std::string& text, const std::vector<std::string>& path,
                        const std::string& by);

// A suite's DIR/experiment.yaml: `experiments:` listing each member's DIR/<name>/experiment.yaml.
std::string suiteFolderFile(const std::vector<Experiment>& suite);

// The name under DIR of the MJCF document `xml`: "mjcf/<first 16 hex digits of its SHA-256>.xml"
// (one file per distinct model, shared by all cases that simulate it).
std::string mjcfFileName(const std::string& xml);

}  // namespace tailsim
