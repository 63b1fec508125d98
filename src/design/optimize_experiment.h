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

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "design/optimize_config.h"
#include "design/stiction_reach.h"
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

// No stroke within the limits turned the body by min_turn_deg: what would. The best stroke the
// search found is run faster (time scaled by k: its loads on the body and its joint torques grow by
// k^2, its speeds by k) until it turns the body by min_turn_deg (bisection on k in the search's model).
struct Infeasibility {
  bool infeasible = false;
  StictionReach reach;             // of the best stroke within the limits
  double peak_torque_Nm = 0.0;     // that stroke's peak joint torque and speed
  double peak_speed_dps = 0.0;
  double torque_needed_Nm = 0.0;   // the same shape turning the body by min_turn_deg (infinite: not found)
  double speed_needed_dps = 0.0;
  std::vector<double> torque_needed_per_joint_Nm, speed_needed_per_joint_dps;  // the same, joint by joint
  // The joint that binds (0-based; -1: none): the largest share of its torque limit (of the
  // largest torque without one), its peak torque and limit (0: none).
  int binding_joint = -1;
  double binding_torque_Nm = 0.0, binding_limit_Nm = 0.0;
  // The check: that shape at the needed torque and speed (the bisection's turning end).
  double check_torque_Nm = 0.0, check_speed_dps = 0.0, check_phi_net_deg = 0.0;
  bool check_ok = false;
  std::string message;             // the console's and summary.json's explanation
};

// The infeasibility analysis of a search whose best stroke turns the body by less than min_turn_rad.
Infeasibility analyseInfeasible(const StrokeProblem& p, const StrokeEvaluation& best, const TailTrajectory& traj,
                                double min_turn_rad);

// One candidate of a MuJoCo re-ranking (objective model: mujoco).
struct RerankRow {
  double search_phi_net_deg = 0.0;  // the search model's
  double mujoco_phi_net_deg = 0.0;
  double mujoco_objective = -1.0;   // objectiveValue of MuJoCo's phi_net (-1: the run failed)
  bool ok = false;
  std::string error;
};

struct OptimizeReport {
  Infeasibility infeasible;
  std::vector<RerankRow> rerank;   // objective model mujoco: the candidates, best of the search first
  std::size_t rerank_chosen = 0;   // the row chosen
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
  // A stop signal (stopped() returned it) ended the search before all seeds ran: the best of the
  // seeds that finished is the result (0: none); with no seed finished nothing but the inputs is written.
  int stop_signal = 0;
};

// The inputs a design folder keeps so that it runs again on its own after a move: the design file
// (as `design_copy`, its `base:` naming base.yaml), the base experiment (its `robot:` naming
// robot.yaml) and the robot file, as file name -> contents. With a stroke file (a maneuver's
// stroke_from: FILE) also stroke.yaml (its `robot:` naming stroke_robot.yaml) and that robot, and
// the design file's maneuver.stroke_from names stroke.yaml. Throws std::runtime_error.
std::map<std::string, std::string> designFolderInputs(const std::string& design_file, const std::string& design_copy,
                                                      const std::string& base_file, const std::string& stroke_file = "");

// `stopped`: polled between seeds, the stop signal received (0: none); empty: never stops.
OptimizeReport runOptimize(const OptimizeSpec& spec, const std::string& out_dir, bool progress,
                           const std::function<int()>& stopped = {});

// The ready-to-run experiment YAML of a split-cycle stroke on the spec's base experiment.
std::string bestExperimentYaml(const OptimizeSpec& spec, const TailTrajectory& traj);

}  // namespace tailsim
