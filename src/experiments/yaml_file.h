// A YAML file read as the experiment loader reads its files: within its bounds on size, nesting,
// values and aliases (experiment_loader.h), UTF-8 checked, and an empty or comment-only file
// refused. For the other readers of tailsim's input files (the design layer's optimize and
// maneuver files), so every file kind meets the same limits and messages.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

namespace tailsim {

// Throws ConfigError "<path>:<line>:<col>: <what>" (path as given).
YAML::Node loadBoundedYaml(const std::string& path);

// "unknown key (allowed here: a, b, c)", with "did you mean 'b'?" when one allowed key is a close
// spelling of key (an edit or two, case ignored): every reader's message for an unknown key.
std::string unknownKeyMessage(const std::string& key, const std::vector<std::string>& allowed);

// The kinds of input file and the command that reads each, told from a file's top-level keys:
// experiment and suite files (`tailsim run`, also render, mjcf and accuracy), kind: optimize
// (`tailsim optimize`), kind: maneuver (`tailsim maneuver`), robot files (named by an
// experiment's robot: key). Throws ConfigError "<path> is an optimize file: run it with `tailsim
// optimize <path> --out DIR`" when doc, the document read from path, is a file that `command`
// ("run", "optimize" or "maneuver") does not read. Nothing when the kind is not recognised: the
// reader's own checks then name the key.
void requireInputFor(const YAML::Node& doc, const std::string& path, const std::string& command);
// For a path given where a result folder is expected: "<path> is an experiment file: run it with
// `tailsim run <path> --out DIR`" and so on, or "" when it is no input file tailsim recognises.
std::string inputFileNote(const std::string& path);

}  // namespace tailsim
