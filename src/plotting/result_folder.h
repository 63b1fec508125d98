// Reading a result folder (docs/ARCHITECTURE.md "Result folder") back for plots and reports:
// DIR/summary.json, DIR/cases/<dir>/<model>.csv, and the cases as run: DIR/experiment.yaml read by
// the experiments layer's loader (its robot: names the folder's copy DIR/robot.yaml), never the
// input files the folder was made from. A suite folder holds one such folder per experiment
// (DIR/<experiment>/summary.json).
#pragma once

#include <cmath>
#include <map>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/experiment_config.h"
#include "results/time_series.h"

namespace tailsim {

// One model run of one case, as summary.json records it (RunSummary).
struct RunRecord {
  bool ok = false;
  double phi_net_deg = NAN;
  double t_stop_s = NAN;
  double wall_time_s = NAN;
  double phi_net_uncertainty_deg = NAN;  // MuJoCo's extra of that name; NaN when not estimated
  int stick_slip_events = 0;
  std::string error;
  std::vector<std::string> warnings;  // the run's warnings, as summary.json lists them
  // The result as a reader should see it: "+6.123", "+6.123 +- 0.050", "+6.123 +- 2.300 (uncertain)"
  // (uncertain: a warning says the uncertainty exceeds the share the run was given).
  std::string phiText() const;
};

// A run as summary.json records it (a missing field takes RunRecord's default).
RunRecord readRunRecord(const nlohmann::json& run);

struct CaseRecord {
  std::string name;                           // "base" or "key=value,..."
  std::string dir;                            // folder under DIR/cases/
  std::map<std::string, std::string> sweep;   // swept key -> value as written
  std::map<std::string, RunRecord> runs;      // model -> run
  std::string verdict;                        // across the models (experiments/verdict.h); empty: none
};

// One swept key with its distinct values in increasing order (numeric when all values parse).
struct SweepAxis {
  std::string key;                  // as in summary.json ("trajectory.theta0_deg")
  std::vector<std::string> values;  // distinct values as written, sorted
  bool numeric = true;
  double number(size_t i) const;    // numeric value of values[i] (index i when not numeric)
  int indexOf(const std::string& value) const;  // -1 if absent
};

struct ExperimentResults {
  std::string dir;          // the result folder
  std::string name;         // experiment name
  std::string description;
  std::string source;       // YAML file it was run from
  std::string kind = "simulate";  // "simulate" | "pose"
  int links = 0;                    // tail links when every case has the same number, else 0
  std::vector<std::string> models;  // every model that has a run, "analytic" first
  std::vector<SweepAxis> axes;      // swept keys with more than one value, in summary order
  std::vector<CaseRecord> cases;
  // Every case as run (all values resolved: sweeps, defaults, per-joint lists, rule: eq25, custom
  // tails), by case name, from DIR/experiment.yaml. Empty when it cannot be loaded (a folder of
  // an older tailsim without its robot copy): resolve_error says why.
  std::map<std::string, ExperimentCase> resolved;
  std::string resolve_error;
  // A resolved case names a model file (`robot: {mjcf: ...}`): its MuJoCo run is the articulated robot.
  bool articulated = false;
  // A model's title in these results' figures and pages (modelTitle(model, articulated)).
  std::string modelTitle(const std::string& model) const;

  // DIR/cases/<case.dir>/<model>.csv; throws std::runtime_error if unreadable.
  std::string csvPath(const CaseRecord& c, const std::string& model) const;
  // The case's time series: DIR/cases/<dir>/<model>.csv, or /<dir>/<model> of DIR/time_series.h5
  // (output.time_series_file: hdf5). Throws std::runtime_error, saying so when the case kept none
  // (output.time_series: none).
  TimeSeries series(const CaseRecord& c, const std::string& model) const;
  // Empty, or a sentence saying how many cases have no time series and what that means for plots.
  std::string seriesNote() const;
  // phi_net of a run, NaN if the model did not run or failed.
  double phiNet(const CaseRecord& c, const std::string& model) const;
  bool hasModel(const std::string& model) const;
  // The case as run, or nullptr (resolve_error says why).
  const ExperimentCase* resolvedCase(const CaseRecord& c) const;
  // The case with these axis values (value strings as in SweepAxis::values), or nullptr.
  const CaseRecord* find(const std::map<std::string, std::string>& sweep) const;
};

// The case of each cell of the grid of two swept keys, [iy][ix] for ay.values[iy] and
// ax.values[ix] (the first such case, as ExperimentResults::find), nullptr where there is none.
// One pass over the cases: find() per cell is quadratic (100 x 1,000 cases: minutes).
std::vector<std::vector<const CaseRecord*>> caseGrid(const ExperimentResults& r, const SweepAxis& ay,
                                                     const SweepAxis& ax);

// Reads DIR/summary.json (falling back to DIR/cases/*/result.json for an interrupted run).
// Throws std::runtime_error if DIR holds neither.
ExperimentResults loadResults(const std::string& dir);

// DIR itself if it holds summary.json, else every direct subfolder that does (sorted by name).
std::vector<ExperimentResults> loadResultTree(const std::string& dir);

// Every model that ran in any of `results`, each once, in the order first met.
std::vector<std::string> allModels(const std::vector<ExperimentResults>& results);

// A warning with each number masked ("all four feet carry no load in 22.3 % ..." and "... in 23 %
// ..." -> "... in # % ..."): runs whose warnings differ only in their numbers say the same thing, shown once with
// their count (the console table, figures.html, report.md).
std::string warningShape(const std::string& warning);

// "trajectory.theta0_deg" -> "theta0_deg"; "trajectory.dtheta_deg[2]" -> "dtheta_deg[2]".
std::string leafKey(const std::string& key);
// Axis label with unit for a key: "theta0_deg" -> "θ0 [deg]", "d_Q2B_m" -> "d_Q2B [m]".
std::string axisLabel(const std::string& key);
// Parses a value as written ("0.25", "-90"); nullopt if it is not a number.
std::optional<double> parseNumber(const std::string& s);

}  // namespace tailsim
