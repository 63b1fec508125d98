// Speed of the analytic model (one Fig. 7 run at the default tolerance under 1 ms) and
// of the whole paper reproduction's analytic cases (about 130 runs under 1 s).
#include <benchmark/benchmark.h>

#include "analytic_test_util.h"
#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"

using namespace tailsim;
using namespace tailsim::testing;

// The full run as `tailsim run` does it: 1 ms output grid, all CSV columns.
static void BM_Fig7_DefaultTolerance(benchmark::State& st) {
  const RobotParams r = paperRobot(1);
  const TailTrajectory tr = sameMove(1, 0, -90, 0.25, 0.25);
  long steps = 0;
  double rhs = 0;
  for (auto _ : st) {
    const RunResult res = simulateAnalytic(r, tr, {}, {}, {});
    steps = res.summary.solver_steps;
    rhs = res.summary.extra.at("rhs_evaluations");
    benchmark::DoNotOptimize(res.summary.phi_net_deg);
  }
  st.counters["steps"] = steps;
  st.counters["rhs"] = rhs;
}
BENCHMARK(BM_Fig7_DefaultTolerance)->Unit(benchmark::kMicrosecond);

// Integration and events only: two output rows (t = 0 and the end).
static void BM_Fig7_NoTimeSeries(benchmark::State& st) {
  const RobotParams r = paperRobot(1);
  const TailTrajectory tr = sameMove(1, 0, -90, 0.25, 0.25);
  OutputSettings o;
  o.sample_dt_s = 0.75;  // the whole run: 0.25 s move + 0.5 s settle
  for (auto _ : st) benchmark::DoNotOptimize(simulateAnalytic(r, tr, {}, {}, o).summary.phi_net_deg);
}
BENCHMARK(BM_Fig7_NoTimeSeries)->Unit(benchmark::kMicrosecond);

// Translation locked (effects.translation: false), two output rows: with the paper coupling the
// yaw does not depend on the translation, so this is what a yaw-only search (tailsim optimize)
// needs to simulate.
static void BM_Fig7_YawOnly(benchmark::State& st) {
  const RobotParams r = paperRobot(1);
  const TailTrajectory tr = sameMove(1, 0, -90, 0.25, 0.25);
  OutputSettings o;
  o.sample_dt_s = 0.75;
  Effects e;
  e.translation = false;
  double rhs = 0;
  for (auto _ : st) {
    const RunResult res = simulateAnalytic(r, tr, {}, e, o);
    rhs = res.summary.extra.at("rhs_evaluations");
    benchmark::DoNotOptimize(res.summary.phi_net_deg);
  }
  st.counters["rhs"] = rhs;
}
BENCHMARK(BM_Fig7_YawOnly)->Unit(benchmark::kMicrosecond);

// Every analytic case of configs/paper/all.yaml (Figs. 6-14), one thread, no files.
static void BM_PaperReproduction_AnalyticCases(benchmark::State& st) {
  std::vector<ExperimentCase> cases;
  for (const Experiment& e : loadExperimentSuite(TAILSIM_SOURCE_DIR "/configs/paper/all.yaml"))
    for (ExperimentCase c : e.cases) {
      c.models = {"analytic"};
      cases.push_back(c);
    }
  for (auto _ : st)
    for (const ExperimentCase& c : cases) benchmark::DoNotOptimize(runCase(c).size());
  st.counters["cases"] = cases.size();
}
BENCHMARK(BM_PaperReproduction_AnalyticCases)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
