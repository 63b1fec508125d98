#include "experiments/model_registry.h"

#include <algorithm>
#include <stdexcept>

#include "models/analytic/analytic_rows.h"
#include "models/analytic/analytic_simulation.h"
#include "models/perfoot/per_foot_model.h"
#include "models/mujoco/attach_tail.h"
#include "models/mujoco/mujoco_simulation.h"
#include "experiments/work_estimate.h"
#include "results/columns.h"
#include "common/palette.h"

namespace tailsim {

namespace {

// A model whose run throws (bad settings found late) fails that run, not the case.
RunResult failedRun(const std::string& model, const std::string& why) {
  RunResult r;
  r.summary.model = model;
  r.summary.ok = false;
  r.summary.error = why;
  return r;
}

// What an analytic or per-foot run records. With output.time_series none and no video to
// render, nothing reads its rows: the run records the two at t = 0 and at the end instead of one
// every sample_dt_s. Their summaries come from the state, not the rows (docs/accuracy.md
// "Summaries from the state"), and a row's evaluation does not feed back into the run, so the
// results are bit-identical (test TimeSeriesOutput.NoneRecordsTwoRowsAndSummarizesTheSame). Tipping
// over does not depend on the rows either: it is checked along the whole trajectory before the run
// (support_check.h); the per-foot load transfer's shifted centre of pressure, which depends on the
// state, is scanned along the solution with the stick/slip events (per_foot_simulation.cc).
//
// With thin and no video, the analytic and per-foot models evaluate only the rows thinning keeps (they return
// them with RunResult::series_thinned); a video needs every row, so with one it records them all
// and the runner thins the CSV's copy.
OutputSettings recordedOutput(const ExperimentCase& c) {
  OutputSettings o = c.output;
  if (c.render.enabled) o.time_series = TimeSeriesOutput::kFull;
  if (o.time_series != TimeSeriesOutput::kNone) return o;
  const double t_end = c.simDuration();  // the models' own end (planRun)
  if (t_end > o.sample_dt_s) o.sample_dt_s = t_end;
  return o;
}

// The MuJoCo model of a robot given by its model file (robot: {mjcf: ...}): the robot itself, legs
// held by its own actuators, with the tail attached, standing kArticulatedStandS with the tail
// before the stroke, and its check run at twice the model's timestep (attach_tail.h).
constexpr double kArticulatedStandS = 2.0;
RunResult simulateRobotModel(const ExperimentCase& c) {
  if (!c.robot_derived)
    throw std::invalid_argument("the robot of its model file was not derived (resolveRobotModels) before the run");
  const TailTrajectory traj = c.trajectory();
  const double t_end = c.simDuration();
  const double dt = c.output.time_series == TimeSeriesOutput::kNone && !c.render.enabled ? t_end : c.output.sample_dt_s;
  return simulateArticulated(*c.robot_derived, c.robot_model->mount, c.robot.tail, traj, c.mujoco, kArticulatedStandS,
                             t_end - traj.endTime(), dt, kMujocoModel);
}

// The built-in models and those ModelRegistration added, in order.
std::deque<ModelEntry>& registry() {
  static std::deque<ModelEntry> models = [] {
    std::deque<ModelEntry> m;
    ModelEntry analytic;
    analytic.name = kAnalyticModel;
    analytic.title = "analytic (stiction)";
    analytic.color = kAnalyticColor;
    analytic.glossary = "Analytic = the paper's model (stiction friction)";
    analytic.run = [](const ExperimentCase& c, RunContext*) {
      return simulateAnalytic(c.robot, c.trajectory(), c.analytic, c.effects, recordedOutput(c));
    };
    analytic.columns = analyticColumns;
    analytic.steps = analyticStepEstimate;
    analytic.too_many_steps = analyticStepExcess;
    analytic.cost_fixed_s = 1e-3;
    analytic.cost_per_row_s = 2e-6;
    analytic.cost_group = "planar";  // the analytic and per-foot models: one measured cost per case
    analytic.render_rank = 1;
    m.push_back(analytic);

    ModelEntry perfoot;
    perfoot.name = kPerFootModel;
    perfoot.title = "per-foot (Coulomb per foot)";
    perfoot.color = okabe_ito::kGreen;
    perfoot.glossary = "per-foot = Coulomb friction at each foot (docs/per-foot-model.md)";
    perfoot.run = [](const ExperimentCase& c, RunContext*) {
      try {
        return simulatePerFoot(c.robot, c.trajectory(), c.perfoot, c.effects, recordedOutput(c));
      } catch (const std::exception& e) {
        return failedRun(kPerFootModel, e.what());
      }
    };
    perfoot.columns = perFootColumns;
    perfoot.cost_fixed_s = analytic.cost_fixed_s;
    perfoot.cost_per_row_s = analytic.cost_per_row_s;
    perfoot.cost_group = analytic.cost_group;
    m.push_back(perfoot);

    ModelEntry mujoco;
    mujoco.name = kMujocoModel;
    mujoco.title = "MuJoCo (contact)";
    mujoco.articulated_title = "MuJoCo (articulated robot)";  // simulateRobotModel: the model file's own robot
    mujoco.color = kMujocoColor;
    mujoco.glossary = "MuJoCo = the contact model";
    mujoco.long_running = true;
    mujoco.run = [](const ExperimentCase& c, RunContext* ctx) {
      try {
        if (c.robot_model) return simulateRobotModel(c);
        return simulateMujoco(c.robot, c.trajectory(), c.mujoco, c.effects, c.output, nullptr,
                              ctx ? &ctx->mujoco_settle : nullptr);
      } catch (const std::exception& e) {
        return failedRun(kMujocoModel, e.what());
      }
    };
    mujoco.columns = [](int n) {
      std::vector<std::string> c = col::shared(n);
      for (const std::string& x : col::mujocoOnly(n)) c.push_back(x);
      return c;
    };
    mujoco.steps = mujocoStepEstimate;
    mujoco.too_many_steps = mujocoStepExcess;
    mujoco.cost_per_step_s = 1e-5;
    mujoco.render_rank = 2;
    mujoco.simulates_mjcf = true;
    mujoco.moments_note = "impulse-averaged over each output interval";
    mujoco.moments_caption =
        "MuJoCo's moments are impulse averages: the contact and joint impulses of the MuJoCo steps in each "
        "output interval (t ± Δt/2) summed and divided by the interval's length, not single samples of the "
        "chattering contact forces.";
    m.push_back(mujoco);
    return m;
  }();
  return models;
}

}  // namespace

const std::deque<ModelEntry>& modelRegistry() { return registry(); }

const ModelEntry* findModel(const std::string& name) {
  for (const ModelEntry& m : modelRegistry())
    if (m.name == name) return &m;
  return nullptr;
}

std::vector<std::string> modelNames() {
  std::vector<std::string> n;
  for (const ModelEntry& m : modelRegistry()) n.push_back(m.name);
  return n;
}

std::vector<std::string> modelColumnOrder(int links) {
  std::vector<std::string> order = col::shared(links);
  for (const ModelEntry& m : modelRegistry())
    for (const std::string& c : m.columns(links))
      if (std::find(order.begin(), order.end(), c) == order.end()) order.push_back(c);
  return order;
}

ModelRegistration::ModelRegistration(ModelEntry entry) : name_(entry.name) {
  if (name_.empty()) throw std::invalid_argument("a model needs a name");
  if (findModel(name_)) throw std::invalid_argument("model '" + name_ + "' is already registered");
  registry().push_back(std::move(entry));
}

ModelRegistration::~ModelRegistration() {
  std::deque<ModelEntry>& r = registry();
  for (auto it = r.begin(); it != r.end(); ++it)
    if (it->name == name_) {
      r.erase(it);  // the last ones added go first: the entries before stay where they are
      return;
    }
}

}  // namespace tailsim
