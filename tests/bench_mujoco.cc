// Speed of the MuJoCo contact model: the simulation loop of simulateMujoco (controller with
// feed-forward, warning checks, 1 ms logging) against a bare mj_step loop on the same model, in
// one run. Target: loop >= 90 % of bare steps/s. Compare with
//   mujoco-testspeed mjcf/tail_n6.xml 10000 1 0
#include <benchmark/benchmark.h>

#include <chrono>
#include <algorithm>
#include <cmath>
#include <vector>

#include "models/mujoco/mjcf_generator.h"
#include "models/mujoco/mujoco_handles.h"
#include "models/mujoco/mujoco_simulation.h"

using namespace tailsim;

namespace {

TailTrajectory eq25(int n) {
  TailTrajectory t;
  for (int i = 0; i < n; ++i) t.joints.emplace_back(equalPeakSpeedParams(n, 10.47, 0.25));
  return t;
}

// Bare loop: same MJCF, same initial state and the same tail motion (ctrl = theta_ref(t), so
// the contact solver does the same work), `steps` plain mj_step calls: no feed-forward, no
// warning checks, no logging.
double bareStepsPerSecond(const RobotParams& p, const MujocoSettings& s, const Effects& e, const TailTrajectory& tr,
                          long steps) {
  ModelPtr m = loadModelFromXml(generateMjcf(p, s, e));
  DataPtr d = makeData(m.get());
  mj_resetDataKeyframe(m.get(), d.get(), mj_name2id(m.get(), mjOBJ_KEY, mjcf::kHomeKey));
  std::vector<JointState> ref;
  tr.evaluate(0.0, ref);
  for (int i = 0; i < m->nu; ++i) d->qpos[7 + i] = d->ctrl[i] = ref[i].theta;
  const auto t0 = std::chrono::steady_clock::now();
  for (long k = 0; k < steps; ++k) {
    for (int i = 0; i < m->nu; ++i) d->ctrl[i] = tr.joints[i].at(d->time).theta;
    mj_step(m.get(), d.get());
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return steps / wall;
}

void BM_LoopVsBareStep(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Effects e = [&] {
    Effects x;
    x.friction = state.range(1) ? FrictionLaw::kContinuous : FrictionLaw::kStiction;
    return x;
  }();
  const RobotParams p = paperRobot(n);
  const MujocoSettings s;
  double sim_rate = 0, bare_rate = 0;
  long iters = 0;
  // The machine is shared: interleave the two loops and keep the best of 3 of each per iteration.
  for (auto _ : state) {
    double best_sim = 0, best_bare = 0, wall = 0;
    for (int rep = 0; rep < 3; ++rep) {
      const RunResult r = simulateMujoco(p, eq25(n), s, e, OutputSettings{});
      if (!r.summary.ok) state.SkipWithError(r.summary.error.c_str());
      const double rate = r.summary.solver_steps / r.summary.wall_time_s;
      if (rate > best_sim) best_sim = rate, wall = r.summary.wall_time_s;
      best_bare = std::max(best_bare, bareStepsPerSecond(p, s, e, eq25(n), r.summary.solver_steps));
    }
    state.SetIterationTime(wall);
    sim_rate += best_sim;
    bare_rate += best_bare;
    ++iters;
  }
  state.counters["sim_steps_per_s"] = sim_rate / iters;
  state.counters["bare_steps_per_s"] = bare_rate / iters;
  state.counters["ratio"] = sim_rate / bare_rate;
}

}  // namespace

// Args: links, friction law (0 stiction = constant mu, 1 continuous ADAMS law).
BENCHMARK(BM_LoopVsBareStep)->Args({1, 0})->Args({6, 0})->Args({6, 1})->UseManualTime()->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
