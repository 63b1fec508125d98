// The models tailsim runs, one entry each (docs/ARCHITECTURE.md "Models"): the name an
// experiment's `models:` lists (also the CSV file name and the key in summary.json), how plots
// show it, how it runs a case, and the time-series columns it writes. Adding a model: its own
// files, one entry in model_registry.cc, its own column names in results/columns.h, its name in
// the loader's `models:` values (experiment_loader.cc).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "experiments/experiment_config.h"
#include "mujoco_model/mujoco_simulation.h"
#include "results/time_series.h"

namespace tailsim {

// What the cases of one run share: caches that make a sweep cheaper without changing any number
// (each is bit-for-bit the run without it, tested). One per `tailsim run`; thread safe.
struct RunContext {
  MujocoSettleCache mujoco_settle;  // the MuJoCo pre-roll, once per distinct model and start pose
};

struct ModelEntry {
  std::string name;    // "analytic": YAML models: value, cases/<dir>/<name>.csv, runs.<name>
  std::string title;   // legend and report text
  std::string color;   // plot colour, "#RRGGBB"
  bool long_running;   // scheduled first (the short cases fill the gaps at the end)
  // Runs a simulate case; a failure is a RunResult with ok == false and the reason (never throws).
  // `ctx`: the run's shared caches, or nullptr.
  std::function<RunResult(const ExperimentCase&, RunContext* ctx)> run;
  // The columns it writes for an n-link tail, in the CSV order (results/columns.h).
  std::function<std::vector<std::string>(int links)> columns;
};

// Every model, in the order plots, reports and summaries list them ("analytic" first).
const std::vector<ModelEntry>& modelRegistry();
// The entry named `name`, or nullptr.
const ModelEntry* findModel(const std::string& name);
// The names, in registry order.
std::vector<std::string> modelNames();
// The one time-series column order of every model's CSV for an n-link tail: col::shared(n), then
// each entry's own columns in registry order (docs/ARCHITECTURE.md "Time-series columns").
std::vector<std::string> modelColumnOrder(int links);

}  // namespace tailsim
