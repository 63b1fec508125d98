// `kind: optimize` experiment files (docs/design-a-tail-stroke.md). The file names a
// one-case base experiment (robot, tail, effects, solver settings, and the start trajectory),
// read by the experiment loader, and an `optimize:` section read here with the loader's
// conventions: ConfigError "<file>:<line>:<col>: <key>: <what>", unknown keys refused, every
// range checked before any work.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "design/stroke_family.h"
#include "design/stroke_optimizer.h"
#include "experiments/experiment_config.h"
#include "common/work_limits.h"

namespace tailsim {

// best.yaml's experiment is named <name> + this suffix; an optimize name is therefore at most
// kMaxNameChars minus its length.
inline constexpr char kBestNameSuffix[] = "_best";

struct OptimizeSpec {
  std::string name, description;
  std::string source_file;  // absolute path of the optimize file
  std::string base_file;    // absolute path of the base experiment
  ExperimentCase base;      // its one case
  StrokeProblem problem;    // base + stroke space + objective
  OptimizerSettings optimizer;
  std::vector<std::uint64_t> seeds{1};  // one optimisation per seed; the best is the result
  int pareto_points = 0;                // > 0: phi_net vs peak torque front with this many points
  bool mujoco_check = true;             // re-simulate the optimum in MuJoCo
  double min_turn_deg = 0.1;            // a best stroke turning the body less is no answer (exit 3, what would)
  // Where this file's limits replace different ones the robot file gives (a copied preset's keep
  // their values over the user's robot): one line each, printed and in summary.json.
  std::vector<std::string> limit_overrides;
  // The objective's model (objective: {model: ...}); with mujoco the search runs
  // problem.search_model and MuJoCo re-ranks its best problem.keep_candidates points.
  ObjectiveModel objective_model = ObjectiveModel::kAnalytic;
};

// Limits of the optimize section (documented in docs/design-a-tail-stroke.md; common/work_limits.h).
constexpr int kMaxKnots = limits::kMaxOptimizeKnots;
constexpr int kMaxIslands = limits::kMaxOptimizeIslands;
constexpr int kMaxPopulation = limits::kMaxOptimizePopulation;
constexpr int kMaxGenerations = limits::kMaxOptimizeGenerations;
constexpr int kMaxRestarts = limits::kMaxOptimizeRestarts;
constexpr int kMaxLocalRestarts = limits::kMaxOptimizeLocalRestarts;
constexpr int kMaxKeptDirectionsLog2 = limits::kMaxKeptDirectionsLog2;
constexpr int kMaxPolishEvaluations = limits::kMaxPolishEvaluations;
constexpr int kMaxSeeds = limits::kMaxOptimizeSeeds;
constexpr int kMaxParetoPoints = limits::kMaxParetoPoints;
constexpr int kMaxMujocoCandidates = 50;

// Analytic model runs the whole optimisation asks for at most (every seed and Pareto point; each
// search: the start, islands x population x (generations + 1 + refine_generations) per restart,
// the local restarts, the polish; x 2^n patterns with directions: enumerate, later stages only in
// directions_kept of them). The loader refuses more than limits::kMaxOptimizeRuns.
double optimizeRunEstimate(const OptimizeSpec& s);

// Throws ConfigError (experiments/experiment_loader.h) before any optimisation.
OptimizeSpec loadOptimizeSpec(const std::string& path);

// True when the YAML file is a `kind: optimize` file (for the command line's checks).
bool isOptimizeFile(const std::string& path);

}  // namespace tailsim
