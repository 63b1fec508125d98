// The keyword arguments of the Python module's tailsim.simulate() (docs/python.md) as the YAML text
// of one experiment, for loadExperimentText: the one C++ function between a Python dict and the
// loader, so the fuzzer (tests/fuzz_experiment_loader.cc) drives the same path without Python.
#pragma once

#include <nlohmann/json.hpp>

#include <stdexcept>
#include <string>

namespace tailsim {

// A keyword simulate() does not take (name, robot, models among the sections): Python TypeError.
struct KeywordError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// {name: simulate, robot, <sections in the caller's order>, trajectory (unless null), models: [model]}
// written as JSON (which is YAML), one key a line, non-ASCII escaped, so a loader error's line:col
// points into this text. A non-finite number becomes null (the loader refuses it at its key).
std::string simulateExperimentText(const nlohmann::ordered_json& robot, const nlohmann::ordered_json& trajectory,
                                   const std::string& model, const nlohmann::ordered_json& sections);

}  // namespace tailsim
