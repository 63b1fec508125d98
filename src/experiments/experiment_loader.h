// YAML experiment files -> fully validated Experiments, one ExperimentCase per sweep point.
// The file format is described in docs/experiment-format.md.
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "experiments/experiment_config.h"

namespace tailsim {

// Bad input in an experiment, suite or robot file. what() reads
// "<file>:<line>:<col>: <dotted.key>: <what is wrong>" (line and column 1-based; the file is the
// one that holds the bad value, e.g. the robot file for an error inside it).
struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Experiment {
  std::string name;
  std::string description;
  std::string source_file;              // absolute path of the YAML file
  std::vector<std::string> swept_keys;  // dotted keys that are swept, in file order ("trajectory.theta0_deg[1]")
  std::vector<ExperimentCase> cases;    // product of all sweeps, first swept key varying slowest
};

// Loads and validates every case of one experiment file before returning. Throws ConfigError.
Experiment loadExperiment(const std::string& path);

// The same for an experiment given as YAML text (e.g. built from Python dicts by the tailsim module):
// `label` stands for the file name in errors ("<label>:line:col: key: ..."), and relative paths in
// it (a robot file) are relative to the working directory. Throws ConfigError.
Experiment loadExperimentText(const std::string& text, const std::string& label);

// A robot file (`robot:` of an experiment): a built-in name (paper) or a path (relative to the
// working directory), read and validated as the loader does. Throws ConfigError.
struct RobotFileData {
  std::string file;               // absolute path of the file read
  RobotParams base;               // quadruped, friction, gravity; tail empty
  std::map<int, TailLink> tails;  // tails.<n>: the link of an n-link tail (all n links alike; per-joint
                                  // actuator keys: joint 1's values)
};
RobotFileData loadRobotFile(const std::string& name_or_path);

// A suite file is `experiments: [fig06.yaml, ...]` (paths relative to the suite file; entries may
// be suites themselves). A normal experiment file yields a one-element vector. Throws ConfigError.
std::vector<Experiment> loadExperimentSuite(const std::string& path);

// The longest `name` of an experiment, in bytes.
constexpr std::size_t kMaxNameChars = 100;

// The `name` of an experiment or design file (optimize, maneuver) becomes a folder, a plot file
// name and appears in plot titles: one safe path component of 1 to max_chars bytes, no '/', '\\'
// or control characters (NUL and line breaks included), not '.' or '..', not starting with '-',
// '|', '<' or '$' (gnuplot reads a file name starting with '|' or '<' as a shell pipe, with '$' as
// a datablock). A file whose name yields a longer derived name (optimize's `<name>_best`) passes
// a smaller max_chars. Returns "" when `name` is fine, else what is wrong (for the caller's
// ConfigError at the key).
std::string experimentNameProblem(const std::string& name, std::size_t max_chars = kMaxNameChars);

// At most this many values per sweep/range and this many cases per experiment.
constexpr std::size_t kMaxSweepValues = 10000;
constexpr std::size_t kMaxCases = 100000;
// A suite's members together (each within kMaxCases; their steps, bytes and render samples are bounded
// together by the whole-experiment limits too).
constexpr std::size_t kMaxSuiteCases = 10 * kMaxCases;

// Bounds on any YAML file the loader reads (hostile input must fail fast with file:line:col, never
// crash or run for minutes): its size, the nesting of lists and maps, the number of values, lists
// and maps counting each alias (*name) as everything it stands for, and the nesting of suites.
// Aliases inside the node they name (cycles) are refused, and every string must be UTF-8.
constexpr std::size_t kMaxYamlBytes = std::size_t{16} << 20;
// The largest MJCF or URDF file `robot: {mjcf: PATH}` names (text; its meshes are files of their own).
constexpr std::size_t kMaxModelFileBytes = std::size_t{64} << 20;
constexpr int kMaxYamlDepth = 64;
constexpr long kMaxYamlNodes = 100000;
constexpr std::size_t kMaxSuiteDepth = 64;

}  // namespace tailsim
