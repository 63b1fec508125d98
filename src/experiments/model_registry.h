// The models tailsim runs, one entry each (docs/ARCHITECTURE.md "Models"): everything the rest of
// tailsim knows about a model is in its entry: the name an experiment's `models:` lists (also the
// CSV file name and the key in summary.json), how plots and reports show it, how it runs a case,
// the time-series columns it writes, what a run costs and which limits bound it, and whether a
// video can show it. Code outside this file asks the registry, never a model's name, except where a
// comparison is about two particular models (the paper's claims: findings.cc, ladder.cc), which
// names them through the constants below.
//
// Adding a model: its own files (its run and its column table), one entry in model_registry.cc.
// A model built outside tailsim (a test's) is added for a while with ModelRegistration.
#pragma once

#include <deque>
#include <functional>
#include <string>
#include <vector>

#include "experiments/experiment_config.h"
#include "models/mujoco/mujoco_simulation.h"
#include "results/time_series.h"

namespace tailsim {

// The built-in models' names, for the places that compare two particular models.
inline constexpr const char* kAnalyticModel = "analytic";
inline constexpr const char* kPerFootModel = "perfoot";
inline constexpr const char* kMujocoModel = "mujoco";

// What the cases of one run share: caches that make a sweep cheaper without changing any number
// (each is bit-for-bit the run without it, tested). One per `tailsim run`; thread safe.
struct RunContext {
  MujocoSettleCache mujoco_settle;  // the MuJoCo pre-roll, once per distinct model and start pose
};

// A model's solver work in one case, and the limit on it (common/work_limits.h).
struct StepLimit {
  double steps = 0;  // estimated solver steps of one run (a lower bound)
  double limit = 0;  // at most this many (0: unbounded)
};
// A refusal for too much work: the dotted keys that set it, most likely culprit first (the loader
// reports the first one the file sets), and what is estimated, how, and the limit.
struct WorkExcess {
  std::vector<std::string> keys;
  std::string what;
};

struct ModelEntry {
  std::string name;      // "analytic": YAML models: value, cases/<dir>/<name>.csv, runs.<name>
  std::string title;     // legend and report text, "short name (what it is)"
  // The title in an experiment that names a model file (`robot: {mjcf: ...}`), whose run of this
  // model is the user's articulated robot; empty: `title` there too.
  std::string articulated_title;
  std::string color;     // plot colour, "#RRGGBB"
  std::string glossary;  // a figure caption's sentence saying what the model is
  bool long_running = false;  // scheduled first (the short cases fill the gaps at the end)
  // Runs a simulate case; a failure is a RunResult with ok == false and the reason (never throws).
  // `ctx`: the run's shared caches, or nullptr.
  std::function<RunResult(const ExperimentCase&, RunContext* ctx)> run;
  // The columns it writes for an n-link tail, in its CSV's order (from the table its writer fills
  // them from).
  std::function<std::vector<std::string>(int links)> columns;
  // Its solver work in a simulate case and the limit on it; null: no estimate (the run is bounded by
  // the output rows alone). `too_many_steps`: the refusal when the estimate exceeds the limit.
  std::function<StepLimit(const ExperimentCase&)> steps;
  std::function<WorkExcess(const ExperimentCase&, const StepLimit&)> too_many_steps;
  // Expected wall time of one run on one core [s] (docs/scale.md), to balance shards:
  // cost_fixed_s + cost_per_row_s x output rows + cost_per_step_s x steps. Models that share their
  // fixed and per-row cost (cost_group, non-empty) are charged it once per case.
  double cost_fixed_s = 0, cost_per_row_s = 0, cost_per_step_s = 0;
  std::string cost_group;
  // Videos (render section): the case's video shows the body as the model of the highest rank that
  // ran (0: never shown); with render.ghost, the model of rank 1 is drawn as an outline beside a
  // higher one.
  int render_rank = 0;
  bool simulates_mjcf = false;  // its run simulates the generated MJCF (the result folder keeps a copy)
  // The moment figure's panel of this model: a note after its title, and a sentence for the caption.
  std::string moments_note, moments_caption;
};

// Every model, in the order plots, reports and summaries list them ("analytic" first). A deque: an
// entry's address stays valid while models are added after it.
const std::deque<ModelEntry>& modelRegistry();
// The entry named `name`, or nullptr.
const ModelEntry* findModel(const std::string& name);
// The names, in registry order.
std::vector<std::string> modelNames();
// The one time-series column order of every model's CSV for an n-link tail: col::shared(n), then
// each entry's own columns in registry order (docs/ARCHITECTURE.md "Time-series columns").
std::vector<std::string> modelColumnOrder(int links);

// Adds a model after the built-in ones for the object's lifetime (a model built outside tailsim,
// e.g. a test's). Throws std::invalid_argument for a name already registered. Not thread safe:
// register before any run starts and keep the object until the runs are done.
class ModelRegistration {
 public:
  explicit ModelRegistration(ModelEntry entry);
  ~ModelRegistration();
  ModelRegistration(const ModelRegistration&) = delete;
  ModelRegistration& operator=(const ModelRegistration&) = delete;

 private:
  std::string name_;
};

}  // namespace tailsim
