// A YAML file read as the experiment loader reads its files: within its bounds on size, nesting,
// values and aliases (experiment_loader.h), UTF-8 checked, and an empty or comment-only file
// refused. For the other readers of tailsim's input files (the design layer's optimize and
// maneuver files), so every file kind meets the same limits and messages.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

namespace tailsim {

// Throws ConfigError "<path>:<line>:<col>: <what>" (path as given).
YAML::Node loadBoundedYaml(const std::string& path);

}  // namespace tailsim
