// The per-foot model as a search objective: runs per second, and loadFactor calls per run
// (extra.load_factor_evaluations, a deterministic work count) and of them those that ran the
// start scan (extra.load_factor_start_scans; the others are warm-started), each run as `tailsim optimize` runs a
// search point (evaluateStroke: two rows, t = 0 and the end, no M_z,T decomposition), on two sets:
//  * RandomRobots: 50 seeded random robots and strokes (tests/random_robots.h, seed 35, cases 0..49);
//  * DesignBox: 50 seeded random points (mt19937 seed 35) of the split-cycle box of the 12 kg robot's
//    n = 3 design problem (configs/design/base/r12kg_n3.yaml, the preset's limits, 20 N m), the
//    strokes a per-foot search runs (about half leave the body stuck).
//   build/tests/bench_per_foot_speed                     (the benchmarks)
//   build/tests/bench_per_foot_speed --phi FILE          (each case's phi_net, %.17g, and its work
//                                                         counts as CSV: compare two builds' files)
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "design/optimize_config.h"
#include "models/perfoot/per_foot_model.h"
#include "random_robots.h"

using namespace tailsim;
using namespace tailsim::testing;

namespace {

constexpr unsigned kSeed = 35;
constexpr int kCases = 50;

// One stroke to run: robot, trajectory, settings, and a line to rebuild it from.
struct Case {
  RobotParams robot;
  TailTrajectory trajectory;
  PerFootSettings settings;
  Effects effects;
  double settle_s = 0.5;
  std::string description;
};

// One search point's run (evaluateStroke's output settings).
RunResult runCase(const Case& c) {
  Effects e = c.effects;
  e.load_decomposition = false;
  OutputSettings out;
  out.settle_s = c.settle_s;
  out.duration_s = 0.0;
  out.sample_dt_s = c.trajectory.endTime() + out.settle_s;
  return simulatePerFoot(c.robot, c.trajectory, c.settings, e, out);
}

std::vector<Case> randomRobots() {
  std::vector<Case> v;
  for (int k = 0; k < kCases; ++k) {
    const RandomRobotCase r = randomRobotCase(kSeed, k);
    v.push_back({r.robot, r.trajectory, PerFootSettings{}, Effects{}, 0.5, describe(r)});
  }
  return v;
}

std::vector<Case> designBox() {
  const std::string file =
      (std::filesystem::temp_directory_path() / ("bench_per_foot_speed_" + std::to_string(getpid()) + ".yaml")).string();
  {
    std::ofstream f(file);
    f << "name: bench_per_foot_speed\nkind: optimize\nbase: " << TAILSIM_SOURCE_DIR
      << "/configs/design/base/r12kg_n3.yaml\noptimize:\n  family: split_cycle\n  objective: {model: perfoot}\n"
         "  limits: {theta_deg: [-90, 90], thetadot_max_dps: 600, torque_max_Nm: 20, dT_s: [0.05, 1.0], "
         "start_delay_s: 0.1}\n";
  }
  const OptimizeSpec spec = loadOptimizeSpec(file);
  std::filesystem::remove(file);
  const StrokeProblem& p = spec.problem;
  std::mt19937 rng(kSeed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<Case> v;
  for (int k = 0; k < kCases; ++k) {
    std::vector<double> x(p.space.dim());
    for (double& xi : x) xi = U(rng);
    std::string d = "r12kg_n3 split_cycle x =";
    for (double xi : x) d += " " + std::to_string(xi);
    v.push_back({p.base.robot, p.space.trajectory(x), p.base.perfoot, p.base.effects, p.base.output.settle_s, d});
  }
  return v;
}

double extra(const RunResult& r, const char* key) {
  const auto it = r.summary.extra.find(key);
  return it == r.summary.extra.end() ? 0.0 : it->second;
}

void runAll(benchmark::State& state, const std::vector<Case>& cs) {
  double load_factors = 0, start_scans = 0, runs = 0;
  for (auto _ : state) {
    load_factors = start_scans = 0;
    for (const Case& c : cs) {
      const RunResult r = runCase(c);
      benchmark::DoNotOptimize(r.summary.phi_net_deg);
      load_factors += extra(r, "load_factor_evaluations");
      start_scans += extra(r, "load_factor_start_scans");
    }
    runs += cs.size();
  }
  state.counters["runs_per_s"] = benchmark::Counter(runs, benchmark::Counter::kIsRate);
  state.counters["loadFactor_per_run"] = load_factors / cs.size();
  state.counters["start_scans_per_run"] = start_scans / cs.size();
}
void BM_PerFootRandomRobots(benchmark::State& state) { runAll(state, randomRobots()); }
void BM_PerFootDesignBox(benchmark::State& state) { runAll(state, designBox()); }
BENCHMARK(BM_PerFootRandomRobots)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();
BENCHMARK(BM_PerFootDesignBox)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();

int writePhi(const char* path) {
  FILE* f = std::fopen(path, "w");
  if (!f) {
    std::perror(path);
    return 2;
  }
  std::fprintf(f, "set,case,ok,phi_net_deg,load_factor_evaluations,load_factor_start_scans,solver_steps,description\n");
  for (const auto& [name, cs] : {std::make_pair("random_robots", randomRobots()), std::make_pair("design_box", designBox())}) {
    int k = 0;
    for (const Case& c : cs) {
      const RunResult r = runCase(c);
      std::fprintf(f, "%s,%d,%d,%.17g,%.0f,%.0f,%ld,\"%s\"\n", name, k++, r.summary.ok ? 1 : 0,
                   r.summary.phi_net_deg, extra(r, "load_factor_evaluations"), extra(r, "load_factor_start_scans"),
                   r.summary.solver_steps, c.description.c_str());
    }
  }
  return std::fclose(f) == 0 ? 0 : 2;
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--phi") == 0) return writePhi(argv[i + 1]);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  return 0;
}
