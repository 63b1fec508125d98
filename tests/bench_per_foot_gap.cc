// The per-foot model: its cost per run next to the analytic and MuJoCo models,
// and (with --gap) the first gap measurement: |phi_net difference| / |phi_net| against MuJoCo with
// the same friction law, over every case of Figs. 6, 7, 9, 11-14 (configs/paper), for the
// exact-coupling analytic model and the per-foot model (quasi-static loads / load transfer).
//   build/tests/bench_per_foot_gap --gap [--csv FILE] [--suite SUITE.yaml]   (about a minute on one core;
//   --suite: another copy of configs/paper/all.yaml, e.g. with other mujoco settings)
//   build/tests/bench_per_foot_gap                          (benchmarks only)
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "models/analytic/analytic_simulation.h"
#include "models/perfoot/per_foot_model.h"
#include "analytic_test_util.h"
#include "experiments/experiment_loader.h"
#include "models/mujoco/mujoco_simulation.h"

using namespace tailsim;
using namespace tailsim::testing;

namespace {

bool inGap(const std::string& name) {
  for (const char* p : {"fig06a", "fig06b", "fig07", "fig09", "fig11", "fig12", "fig13", "fig14"})
    if (name.rfind(p, 0) == 0) return true;
  return false;
}

std::vector<ExperimentCase> gapCases(const std::string& suite) {
  std::vector<ExperimentCase> out;
  for (const Experiment& e : loadExperimentSuite(suite))
    if (inGap(e.name))
      for (const ExperimentCase& c : e.cases) out.push_back(c);
  return out;
}

PerFootSettings perFootFor(const ExperimentCase& c, NormalLoadModel loads) {
  PerFootSettings s;
  s.normal_loads = loads;
  return s;
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Columns of one case's row.
const char* kModels[] = {"exact_stiction", "perfoot_stiction_qs", "perfoot_stiction_lt", "mujoco_stiction",
                         "exact_adams", "perfoot_adams_qs", "perfoot_adams_lt", "mujoco_adams"};
constexpr int kN = 8;

int runGap(const char* csv_path, const std::string& suite) {
  const std::vector<ExperimentCase> cases = gapCases(suite);
  std::map<std::string, std::vector<std::array<double, kN>>> byFig;
  std::vector<std::pair<std::string, std::array<double, kN>>> rows;
  double wall[kN] = {0};
  int runs[kN] = {0};
  for (const ExperimentCase& c : cases) {
    const TailTrajectory tr = c.trajectory();
    std::array<double, kN> phi;
    for (int law = 0; law < 2; ++law) {
      Effects e = c.effects;
      e.friction = law == 0 ? FrictionLaw::kStiction : FrictionLaw::kContinuous;
      AnalyticSettings as = c.analytic;
      as.coupling = Coupling::kExact;
      const RunResult results[4] = {
          simulateAnalytic(c.robot, tr, as, e, c.output),
          simulatePerFoot(c.robot, tr, perFootFor(c, NormalLoadModel::kQuasiStatic), e, c.output),
          simulatePerFoot(c.robot, tr, perFootFor(c, NormalLoadModel::kLoadTransfer), e, c.output),
          simulateMujoco(c.robot, tr, c.mujoco, e, c.output)};
      for (int k = 0; k < 4; ++k) {
        const int col = 4 * law + k;
        phi[col] = results[k].summary.ok ? results[k].summary.phi_net_deg : NAN;
        wall[col] += results[k].summary.wall_time_s;
        ++runs[col];
        if (!results[k].summary.ok)
          std::fprintf(stderr, "%s/%s %s: %s\n", c.experiment.c_str(), c.name.c_str(), kModels[col],
                       results[k].summary.error.c_str());
      }
    }
    byFig[c.experiment.substr(0, 5)].push_back(phi);
    rows.push_back({c.experiment + "/" + c.name, phi});
  }
  if (csv_path) {
    std::ofstream f(csv_path);
    f << "case";
    for (const char* m : kModels) f << ",phi_net_deg_" << m;
    f << "\n";
    for (const auto& [name, phi] : rows) {
      f << '"' << name << '"';
      for (double v : phi) f << "," << v;
      f << "\n";
    }
  }
  // Relative gap of model a to reference b over a set of cases.
  auto stats = [](const std::vector<std::array<double, kN>>& v, int a, int b) {
    std::vector<double> r;
    for (const auto& p : v)
      if (std::isfinite(p[a]) && std::isfinite(p[b]) && p[b] != 0) r.push_back(std::abs(p[a] - p[b]) / std::abs(p[b]));
    return std::make_pair(median(r), r.empty() ? NAN : *std::max_element(r.begin(), r.end()));
  };
  std::vector<std::array<double, kN>> all;
  for (const auto& [fig, v] : byFig) all.insert(all.end(), v.begin(), v.end());
  std::printf("|phi_net - phi_net,MuJoCo| / |phi_net,MuJoCo| (same friction law), median / max, %zu cases\n",
              all.size());
  std::printf("%-8s %5s | %-17s %-17s %-17s | %-17s %-17s %-17s\n", "figure", "cases", "exact stiction",
              "perfoot stic. qs", "perfoot stic. lt", "exact ADAMS", "perfoot ADAMS qs", "perfoot ADAMS lt");
  auto line = [&](const std::string& name, const std::vector<std::array<double, kN>>& v) {
    std::printf("%-8s %5zu |", name.c_str(), v.size());
    for (int law = 0; law < 2; ++law) {
      for (int k = 0; k < 3; ++k) {
        const auto [md, mx] = stats(v, 4 * law + k, 4 * law + 3);
        std::printf(" %6.1f%% / %6.1f%%", 100 * md, 100 * mx);
      }
      std::printf(" |");
    }
    std::printf("\n");
  };
  for (const auto& [fig, v] : byFig) line(fig, v);
  line("all", all);
  // Relative gaps of near-zero turns (creep of a few hundredths of a degree in MuJoCo where the
  // stiction models stay stuck, or a sign change near w_ss = 0.6) say little: also without them.
  std::vector<std::array<double, kN>> big;
  for (const auto& p : all)
    if (std::abs(p[3]) >= 1.0 && std::abs(p[7]) >= 1.0) big.push_back(p);
  line("|phi|>=1", big);
  std::printf("\nmean wall time per run:");
  for (int k = 0; k < kN; ++k) std::printf(" %s %.2f ms;", kModels[k], 1e3 * wall[k] / std::max(1, runs[k]));
  std::printf("\n");
  return 0;
}

// Cost per run: the Fig. 7 case (n = 1) and the Fig. 6(b) case (n = 6), 1 ms output grid.
void BM_Run(benchmark::State& st, int kModel, int n) {
  const RobotParams r = paperRobot(n, 0.1405);
  const TailTrajectory tr = sameMove(n, 0, n == 1 ? -90 : -30, 0.25, 0.25);
  AnalyticSettings as;
  as.coupling = Coupling::kExact;
  PerFootSettings ps;
  Effects e;
  long steps = 0;
  for (auto _ : st) {
    RunResult res;
    if (kModel == 0) res = simulateAnalytic(r, tr, as, e, {});
    if (kModel == 1) res = simulatePerFoot(r, tr, ps, e, {});
    if (kModel == 2) {
      ps.normal_loads = NormalLoadModel::kLoadTransfer;
      res = simulatePerFoot(r, tr, ps, e, {});
    }
    if (kModel == 3) {
      e.friction = FrictionLaw::kContinuous;
      res = simulatePerFoot(r, tr, ps, e, {});
    }
    if (kModel == 4) res = simulateMujoco(r, tr, MujocoSettings{}, e, {});
    steps = res.summary.solver_steps;
    benchmark::DoNotOptimize(res.summary.phi_net_deg);
  }
  st.counters["steps"] = steps;
}
BENCHMARK_CAPTURE(BM_Run, analytic_exact_n1, 0, 1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Run, perfoot_stiction_n1, 1, 1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Run, perfoot_stiction_loadtransfer_n1, 2, 1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Run, perfoot_adams_n1, 3, 1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Run, mujoco_n1, 4, 1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Run, analytic_exact_n6, 0, 6)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Run, perfoot_stiction_n6, 1, 6)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Run, perfoot_adams_n6, 3, 6)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Run, mujoco_n6, 4, 6)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (std::strcmp(argv[i], "--gap") == 0) {
      const char* csv = nullptr;
      std::string suite = TAILSIM_SOURCE_DIR "/configs/paper/all.yaml";
      for (int j = 1; j + 1 < argc; ++j) {
        if (std::strcmp(argv[j], "--csv") == 0) csv = argv[j + 1];
        if (std::strcmp(argv[j], "--suite") == 0) suite = argv[j + 1];
      }
      return runGap(csv, suite);
    }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  return 0;
}
