// `kind: maneuver` experiment files and `tailsim maneuver EXP.yaml --out DIR`
// (docs/design-a-tail-stroke.md "Maneuvers"): turn the robot to a commanded heading with cycles of
// a fast stroke and a slow return (controllers/heading_controller.h),
//   (a) planned open-loop on the analytic model and run as planned in both models,
//   (b) closed-loop in MuJoCo: HeadingController picks each next cycle from the measured heading.
// The file names a one-case base experiment (robot, tail, friction, solver settings), like an
// optimize file, and holds a `maneuver:` section (ManeuverSettings, declared once).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "controllers/heading_controller.h"
#include "experiments/experiment_config.h"
#include "results/time_series.h"

namespace tailsim {

struct ManeuverSpec {
  std::string name, description;
  std::string source_file;  // absolute path of the maneuver file
  std::string base_file;    // absolute path of the base experiment
  ExperimentCase base;      // its one case (its trajectory is the fast stroke with stroke_from: base)
  ManeuverSettings settings;  // settings.stroke_shape: the stroke_from trajectory (empty: stroke_deg ...)
  std::string stroke_file;  // stroke_from: FILE, absolute (empty: none or base)
  bool min_scale_given = false;  // else runManeuver derives it from the tolerance (derivedMinScale)
  // "<file>:<line>:<col>: maneuver.max_strokes" (or of the maneuver section when the key is not set):
  // where a plan longer than max_strokes is reported.
  std::string max_strokes_at;
};


// Throws ConfigError "<file>:<line>:<col>: maneuver.<key>: ..." before any work.
ManeuverSpec loadManeuverSpec(const std::string& path);

// The analytic model's yaw of one cycle (fast stroke + return) at `scale`, direction +1, and of
// its two strokes apart; at_rest: the body was at rest after each stroke.
struct CycleYaw {
  double fast_rad = 0, back_rad = 0;
  bool at_rest = true;
  double total() const { return fast_rad + back_rad; }
};
CycleYaw analyticCycleYaw(const ExperimentCase& base, const ManeuverSettings& s, double scale);

// The smallest stroke scale the controller needs: the one whose analytic cycle turns the body by
// the tolerance (bisection; smaller cycles are never needed, larger ones cannot land within the
// tolerance from just outside it), at least `floor`; 1 when even a full cycle turns less.
double derivedMinScale(const ExperimentCase& base, const ManeuverSettings& s, double floor);

// The yaw-vs-scale map on the analytic model (map_points scales in [min_scale, 1]; |yaw| made
// monotone by a running maximum).
YawMap analyticYawMap(const ExperimentCase& base, const ManeuverSettings& s);

// One executed cycle.
struct StrokeRecord {
  double t_start_s = 0;
  StrokeCommand command;
  double heading_before_rad = 0, heading_after_rad = 0;
};

// One way of turning: the heading change over time (relative to the start) and the cycles.
struct ManeuverRun {
  std::string label;  // analytic_open_loop | mujoco_open_loop | mujoco_closed_loop
  bool ok = true;
  std::string error;
  TimeSeries series;  // t_s, x_m, y_m, phi_deg, theta<i>_deg (+ thetadot<i>_dps): for plots and video
  std::vector<StrokeRecord> strokes;
  // Figures (heading error e = target - heading):
  double final_error_rad = 0;
  double overshoot_rad = 0;        // largest turn past the target (>= 0)
  double t_within_s = -1;          // first time after which |e| <= tolerance to the end; -1: never
  int strokes_to_within = -1;      // cycles started before t_within_s
  std::vector<std::string> warnings;
};

// The open-loop plan: N full cycles and a last one scaled (bisection on the analytic model) so the
// analytic heading lands on the target. More than s.max_strokes cycles: ConfigError, its text
// starting with `where` ("<file>:<line>:<col>: maneuver.max_strokes") when given.
std::vector<StrokeCommand> planOpenLoop(const ExperimentCase& base, const ManeuverSettings& s, const YawMap& map,
                                        const std::string& where = "");

ManeuverRun runAnalyticOpenLoop(const ExperimentCase& base, const ManeuverSettings& s, const std::vector<StrokeCommand>& plan);
ManeuverRun runMujocoOpenLoop(const ExperimentCase& base, const ManeuverSettings& s, const std::vector<StrokeCommand>& plan);
// duration_s: simulated time (the controller idles once within tolerance).
ManeuverRun runMujocoClosedLoop(const ExperimentCase& base, const ManeuverSettings& s, const YawMap& map, double duration_s);

struct ManeuverReport {
  int stop_signal = 0;   // a stop signal ended it between runs: no results written (0: none)
  double min_scale = 0;  // used (given, or derived from the tolerance)
  YawMap map;
  CycleYaw full_cycle;
  std::vector<StrokeCommand> plan;
  std::vector<ManeuverRun> runs;
  std::vector<std::string> files;  // relative to DIR
  double wall_s = 0;
};

// Runs everything and writes DIR/maneuver.csv, strokes.csv, yaw_map.csv, summary.json,
// plots/heading.{gp,png,svg} and, with `video`, renders/<name>.mp4 (closed loop, analytic ghost).
// `stopped`: polled between the runs, the stop signal received (0: none): then the report's
// stop_signal is set and nothing but the inputs is written.
ManeuverReport runManeuver(const ManeuverSpec& spec, const std::string& out_dir, bool video, bool progress,
                           const std::function<int()>& stopped = {});

}  // namespace tailsim
