// The stroke optimiser. pagmo2 (CMA-ES or differential evolution on parallel
// thread islands) searches the unit box of a StrokeSpace; NLopt (COBYLA with the limits as
// constraints, or BOBYQA on the penalised objective) polishes the best point. Every point is
// judged by running the analytic model (simulateAnalytic) on its trajectory.
#pragma once

#include <algorithm>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "design/stroke_family.h"
#include "experiments/experiment_config.h"

namespace tailsim {

struct OptimizerSettings {
  std::string algorithm = "cmaes";  // "cmaes" | "de" (pagmo2)
  int islands = 2;                  // thread islands, evolved in parallel, no migration
  int population = 16;              // per island
  int generations = 60;             // per island and restart
  int restarts = 1;                 // independent global searches per seed (distinct sub-seeds); the best is polished
  int restart_growth = 1;           // population factor from one restart to the next (2: IPOP-CMA-ES)
  int refine_generations = 0;       // CMA-ES generations on each island's population after its global search
  // NLopt (the polish's algorithm) from each global restart's best point, up to this many runs, before the
  // next restart (0: none): each restart's basin converged, not only the best restart's.
  int restart_polish_evaluations = 0;
  bool enumerate_directions = false;  // split-cycle: one search per joint-direction pattern (2^n), the best kept
  int local_restarts = 0;           // CMA-ES runs (population, generations) centred on the best point so far, after the global search
  double local_step = 0.1;          // their initial step, a share of the unit box
  int directions_kept = 0;          // enumerate: local restarts and polish only in the K best patterns (0: all)
  std::string polish = "cobyla";    // "cobyla" | "bobyqa" | "none" (NLopt)
  int polish_evaluations = 200;
  // At most this many model runs per search (0: no cap): a generation, a restart or a local restart
  // that would take the runs so far over max_runs - polish_evaluations is not started, and the
  // polish gets what is left (at most polish_evaluations). The stages keep their order, so a search
  // whose first restart uses the whole budget is exactly the single-start search of that size.
  // With enumerate_directions it is the seed's budget over all patterns: the patterns' first
  // restarts share it evenly, the kept patterns (directions_kept) what those leave.
  long max_runs = 0;
  std::uint64_t seed = 1;
};

struct StrokeProblem {
  ExperimentCase base;  // robot, effects, analytic settings; its trajectory is the search's start
  StrokeSpace space;
  StrokeObjective objective = StrokeObjective::kPhiNet;
  ObjectiveModel search_model = ObjectiveModel::kAnalytic;  // the model every search point runs (analytic | perfoot)
  int keep_candidates = 0;  // > 0: OptimizeResult::candidates keeps the best this many distinct feasible points
};

struct StrokeEvaluation {
  bool ok = false;           // the run (of StrokeProblem::search_model) succeeded
  std::string error;
  double phi_net_rad = 0.0;  // signed
  double objective = 0.0;    // objectiveValue (|phi_net| based)
  StrokeFigures figures;
  double violation = 0.0;    // limitViolation (0: feasible)
  // A stroke that leaves the body stuck (phi_net exactly 0, stiction law): how close it came to
  // breaking away, stictionReach's ratio (< 1); 0 otherwise. It ranks the strokes that do not turn
  // the body (their objective is 0), so a search within limits too tight to turn it still climbs
  // towards breakaway, and its best stroke is the shape the infeasibility report scales.
  double stiction_ratio = 0.0;
  bool feasible() const { return ok && violation == 0.0; }
  // The search's score, maximised: kStuckBand + objective when turning, kStuckBand x stiction_ratio
  // when stuck, so every turning stroke ranks above every stuck one, and the stuck ones climb
  // towards breakaway in a band wide enough for CMA-ES's tolerance (it stops once a generation's
  // fitnesses differ by less than 1e-9: with a band of 1e-12 a first population that was all stuck
  // stopped the search at once, and the 3 kg robot, which turns 1.39 deg in other seeds, was
  // reported infeasible in seed 17); COBYLA maximises the same score (it saw 0 for every stuck one).
  static constexpr double kStuckBand = 1e-3;
  // The ratio is the analytic model's, sampled every 0.5 ms, while the search model decides "stuck"
  // at its own steps (or is the per-foot model): a stuck stroke may measure over 1; capped there, it
  // stays below every turning stroke.
  double score() const {
    return objective > 0.0 ? kStuckBand + objective : kStuckBand * std::min(stiction_ratio, 1.0);
  }
  // Minimised by CMA-ES and DE: -score() when feasible; else the violation (> any feasible);
  // kFailedFitness when the run failed (worse than any violation: a torque 11 times its limit is a
  // violation of 10, which used to rank below a failed run).
  static constexpr double kFailedFitness = 1e12;
  double fitness() const;
  // Better than o in the tracker's order: feasible first, then objective, then stiction_ratio.
  bool betterThan(const StrokeEvaluation& o) const {
    return objective > o.objective || (objective == o.objective && stiction_ratio > o.stiction_ratio);
  }
};

// The effects a search simulates with: the base's, without the output-only load decomposition and,
// with the paper coupling, with the translation locked (the yaw does not depend on it there). The
// optimum is re-run with the base's own effects (optimize_experiment.cc).
Effects searchEffects(const ExperimentCase& base);

// Runs the search model on traj (analytic: with searchEffects; per-foot: the base's effects
// without the load decomposition) and judges it against the limits.
// figures (optional): traj's strokeFigures when already known (a slowed stroke's, StrokeSpace).
StrokeEvaluation evaluateStroke(const StrokeProblem& p, const TailTrajectory& traj, const StrokeFigures* figures = nullptr);
StrokeEvaluation evaluateStroke(const StrokeProblem& p, const std::vector<double>& x);

struct HistoryRow {
  int generation = 0;        // pagmo generation; polish rows continue the count
  long evaluations = 0;      // analytic runs so far
  double wall_s = 0.0;
  double best_objective = 0.0;  // best feasible so far (0 when none yet)
  double best_phi_net_rad = 0.0;  // its signed phi_net
  std::string stage;         // "global" | "refine" | "local" | "polish"
};

// Called after every generation (and the polish) with the search's figures so far: stage,
// analytic runs, the best feasible point's objective and signed phi_net. Runs on the search's
// thread, between generations.
struct SearchProgress {
  const char* stage = "";
  long evaluations = 0;
  double best_objective = 0.0;
  double best_phi_net_rad = 0.0;
};
using ProgressFn = std::function<void(const SearchProgress&)>;

// One joint-direction pattern's search (OptimizerSettings::enumerate_directions).
struct DirectionResult {
  std::vector<int> directions;  // per joint, +1 or -1 (StrokeSpace::directions)
  StrokeEvaluation best;
  long evaluations = 0;
};

// A feasible point the search ran, with its trajectory (StrokeProblem::keep_candidates).
struct Candidate {
  TailTrajectory trajectory;
  StrokeEvaluation eval;
};

struct OptimizeResult {
  std::vector<Candidate> candidates;  // the best keep_candidates distinct feasible points, best first
  std::vector<double> x;  // best feasible point (the start point when nothing feasible beat it)
  std::vector<int> directions;  // the space x belongs to (StrokeSpace::directions; empty: all free)
  TailTrajectory trajectory;    // the stroke of x
  std::vector<DirectionResult> by_direction;  // enumerate_directions: every pattern's best
  StrokeEvaluation best;
  StrokeEvaluation start;  // the base trajectory's own evaluation
  std::vector<HistoryRow> history;
  long evaluations = 0;
  double wall_s = 0.0;
};

OptimizeResult optimizeStroke(const StrokeProblem& p, const OptimizerSettings& s, const ProgressFn& progress = {});

}  // namespace tailsim
