// `tailsim optimize EXPERIMENT.yaml --out DIR`: run the optimiser for every seed, keep
// the best stroke, verify it (limits on the re-simulated trajectory, MuJoCo re-run), and write
// the result folder (docs/design-a-tail-stroke.md):
//   DIR/best.yaml            the best stroke as a ready-to-run experiment (split-cycle family)
//   DIR/best_trajectory.csv  the best stroke's joint angles/speeds/accelerations/torques on 1 ms
//   DIR/best_analytic.csv, DIR/best_mujoco.csv   the re-simulated time series of both models
//   DIR/history.csv          convergence: seed, stage, generation, evaluations, wall_s, best objective
//   DIR/pareto.csv           phi_net vs peak joint torque (optimize.pareto_points > 0)
//   DIR/plots/history.{gp,png,svg}, DIR/plots/pareto.{gp,png,svg}
//   DIR/summary.json         everything the note needs (objective per seed, spread, MuJoCo difference)
#pragma once

#include <string>
#include <vector>

#include "design/optimize_config.h"
#include "design/stroke_optimizer.h"
#include "results/time_series.h"

namespace tailsim {

struct LimitCheck {
  StrokeFigures figures;  // measured on the re-simulated series
  bool ok = true;         // every declared limit kept (1e-9 relative tolerance)
  std::vector<std::string> violations;
};

// Figures of a model's time series (theta<i>_deg, thetadot<i>_dps, thetaddot<i>_dps2 columns, i = 1..n),
// torques by the Newton-Euler recursion from those columns; checked against `lim`.
LimitCheck checkLimitsOnSeries(const std::vector<TailLink>& links, const TimeSeries& ts, const StrokeLimits& lim);

struct OptimizeReport {
  std::vector<OptimizeResult> per_seed;
  std::size_t best_seed_index = 0;
  double spread = 0.0;  // (max - min) / max of the seeds' objectives
  RunSummary analytic, mujoco;  // re-runs of the best stroke (mujoco.model empty when not run)
  RunSummary perfoot;           // the per-foot friction model's re-run (docs/per-foot-model.md)
  LimitCheck limits_analytic;
  long evaluations = 0;
  double wall_s = 0.0;
  std::vector<std::string> files;  // written, relative to DIR
  // Not empty when best.yaml could not be read back by the experiment loader (e.g. a limit the
  // base never met on this stroke): the re-runs then use the search's own trajectory, and
  // `tailsim run best.yaml` gives this error instead of their results.
  std::string best_yaml_error;
};

OptimizeReport runOptimize(const OptimizeSpec& spec, const std::string& out_dir, bool progress);

// The ready-to-run experiment YAML of a split-cycle stroke on the spec's base experiment.
std::string bestExperimentYaml(const OptimizeSpec& spec, const TailTrajectory& traj);

}  // namespace tailsim
