#include "experiments/model_registry.h"

#include <algorithm>

#include "analytic_model/analytic_simulation.h"
#include "analytic_model/per_foot_model.h"
#include "mujoco_model/mujoco_simulation.h"
#include "results/columns.h"

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

std::vector<std::string> concat(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

}  // namespace

const std::vector<ModelEntry>& modelRegistry() {
  static const std::vector<ModelEntry> kModels = {
      {"analytic", "analytic (stiction)", "#0072B2", false,
       [](const ExperimentCase& c, RunContext*) {
         return simulateAnalytic(c.robot, c.trajectory(), c.analytic, c.effects, recordedOutput(c));
       },
       [](int n) { return concat(col::shared(n), col::analyticOnly()); }},
      {"perfoot", "per-foot (Coulomb per foot)", "#009E73", false,
       [](const ExperimentCase& c, RunContext*) {
         try {
           return simulatePerFoot(c.robot, c.trajectory(), c.perfoot, c.effects, recordedOutput(c));
         } catch (const std::exception& e) {
           return failedRun("perfoot", e.what());
         }
       },
       [](int n) { return concat(concat(col::shared(n), col::analyticOnly()), col::perfootOnly()); }},
      {"mujoco", "MuJoCo (contact)", "#D55E00", true,
       [](const ExperimentCase& c, RunContext* ctx) {
         try {
           return simulateMujoco(c.robot, c.trajectory(), c.mujoco, c.effects, c.output, nullptr,
                                 ctx ? &ctx->mujoco_settle : nullptr);
         } catch (const std::exception& e) {
           return failedRun("mujoco", e.what());
         }
       },
       [](int n) { return concat(col::shared(n), col::mujocoOnly(n)); }},
  };
  return kModels;
}

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

}  // namespace tailsim
