// The MuJoCo pre-roll once per model: a run that starts from the cached settled
// state is the run that simulates its own pre-roll, bit for bit (every column of every row, every
// summary field); the cache is keyed by everything the pre-roll depends on; the work it saves is
// counted in steps.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "models/mujoco/mjcf_generator.h"
#include "models/mujoco/mujoco_simulation.h"
#include "scratch_dir.h"

using namespace tailsim;

namespace {

constexpr double kDeg = M_PI / 180.0;

TailTrajectory stroke(int n, double theta0_deg, double dtheta_deg, double dT_s = 0.25, double w_ss = 0.25) {
  SplitCycleParams sp;
  sp.theta0_rad = theta0_deg * kDeg;
  sp.dtheta_rad = dtheta_deg * kDeg;
  sp.dT_s = dT_s;
  sp.w_ss = w_ss;
  TailTrajectory t;
  for (int i = 0; i < n; ++i) t.joints.emplace_back(sp);
  return t;
}

// Bit-for-bit equality of two runs: every column, every row, every summary number but wall time.
void expectIdentical(const RunResult& a, const RunResult& b) {
  ASSERT_EQ(a.summary.ok, b.summary.ok) << a.summary.error << " / " << b.summary.error;
  ASSERT_EQ(a.series.names(), b.series.names());
  for (const std::string& c : a.series.names()) {
    const std::vector<double>&va = a.series.values(c), &vb = b.series.values(c);
    ASSERT_EQ(va.size(), vb.size()) << c;
    for (size_t r = 0; r < va.size(); ++r)
      ASSERT_TRUE(va[r] == vb[r] || (std::isnan(va[r]) && std::isnan(vb[r])))
          << c << " row " << r << ": " << va[r] << " vs " << vb[r];
  }
  EXPECT_EQ(a.summary.phi_net_deg, b.summary.phi_net_deg);
  EXPECT_EQ(a.summary.t_stop_s, b.summary.t_stop_s);
  EXPECT_EQ(a.summary.solver_steps, b.summary.solver_steps);
  EXPECT_EQ(a.summary.at_rest, b.summary.at_rest);
  EXPECT_EQ(a.summary.warnings, b.summary.warnings);
  EXPECT_EQ(a.summary.extra, b.summary.extra);
}

struct Scene {
  std::string what;
  int n;
  MujocoSettings s;
  Effects e;
};

std::vector<Scene> scenes() {
  std::vector<Scene> v;
  v.push_back({"1 link, defaults", 1, {}, {}});
  v.push_back({"6 links, defaults", 6, {}, {}});
  Scene cont{"1 link, continuous friction law (foot friction changed at run time)", 1, {}, {}};
  cont.e.friction = FrictionLaw::kContinuous;
  v.push_back(cont);
  Scene rk4{"1 link, RK4 at 0.2 ms (docs/accuracy.md: explicit integrators need small steps)", 1, {}, {}};
  rk4.s.integrator = MujocoIntegrator::kRK4;
  rk4.s.timestep_s = 2e-4;
  v.push_back(rk4);
  Scene ell{"4 links, elliptic cones", 4, {}, {}};
  ell.s.cone = MujocoCone::kElliptic;
  v.push_back(ell);
  Scene ff{"3 links, no feed-forward", 3, {}, {}};
  ff.s.velocity_feedforward = false;
  ff.s.inverse_dynamics_feedforward = false;
  v.push_back(ff);
  return v;
}

}  // namespace

TEST(MujocoSettleCache, CachedPreRollGivesTheSameRunBitForBit) {
  OutputSettings out;
  for (const Scene& sc : scenes()) {
    SCOPED_TRACE(sc.what);
    const RobotParams robot = paperRobot(sc.n);
    const TailTrajectory traj = stroke(sc.n, 30.0, -120.0);
    const RunResult plain = simulateMujoco(robot, traj, sc.s, sc.e, out);
    ASSERT_TRUE(plain.summary.ok) << plain.summary.error;
    MujocoSettleCache cache;
    const RunResult first = simulateMujoco(robot, traj, sc.s, sc.e, out, nullptr, &cache);  // simulates, keeps
    const RunResult second = simulateMujoco(robot, traj, sc.s, sc.e, out, nullptr, &cache);  // from the cache
    EXPECT_EQ(cache.misses(), 1);
    EXPECT_EQ(cache.hits(), 1);
    // The pre-roll is settle_s / timestep_s steps (100 at the defaults), simulated once.
    EXPECT_EQ(cache.settleSteps(), std::lround(sc.s.settle_s / sc.s.timestep_s));
    expectIdentical(plain, first);
    expectIdentical(plain, second);
  }
}

TEST(MujocoSettleCache, StrokesFromOneStartAreTheirOwnRunsWithTheCache) {
  // The pre-roll holds theta(0) with the reference's speed and acceleration at t = 0 in the
  // feed-forward: strokes from one theta0 share it when those agree; the key decides, the runs
  // must be their own either way.
  const RobotParams robot = paperRobot(1);
  OutputSettings out;
  MujocoSettleCache cache;
  for (double dtheta : {-60.0, -120.0, 90.0}) {
    const TailTrajectory traj = stroke(1, 0.0, dtheta);
    const RunResult cached = simulateMujoco(robot, traj, {}, {}, out, nullptr, &cache);
    const RunResult plain = simulateMujoco(robot, traj, {}, {}, out);
    expectIdentical(plain, cached);
  }
  EXPECT_EQ(cache.misses(), 1);  // at t <= t0 the split-cycle reference is (theta0, 0, 0)
  EXPECT_EQ(cache.hits(), 2);
}

TEST(MujocoSettleCache, KeyedByModelStartPoseAndSettings) {
  OutputSettings out;
  MujocoSettleCache cache;
  const RobotParams robot = paperRobot(1);
  simulateMujoco(robot, stroke(1, 0.0, -90.0), {}, {}, out, nullptr, &cache);
  EXPECT_EQ(cache.misses(), 1);
  simulateMujoco(robot, stroke(1, 45.0, -90.0), {}, {}, out, nullptr, &cache);  // another start pose
  EXPECT_EQ(cache.misses(), 2);
  RobotParams heavier = robot;
  heavier.tail[0].mass_kg *= 1.5;  // another model (MJCF)
  simulateMujoco(heavier, stroke(1, 0.0, -90.0), {}, {}, out, nullptr, &cache);
  EXPECT_EQ(cache.misses(), 3);
  MujocoSettings longer;
  longer.settle_s = 0.2;  // a setting outside the MJCF
  simulateMujoco(robot, stroke(1, 0.0, -90.0), longer, {}, out, nullptr, &cache);
  EXPECT_EQ(cache.misses(), 4);
  RobotParams slipperier = robot;
  slipperier.friction.v_s_mps = 0.02;  // run-time friction law parameter (continuous law)
  Effects cont;
  cont.friction = FrictionLaw::kContinuous;
  simulateMujoco(robot, stroke(1, 0.0, -90.0), {}, cont, out, nullptr, &cache);
  simulateMujoco(slipperier, stroke(1, 0.0, -90.0), {}, cont, out, nullptr, &cache);
  EXPECT_EQ(cache.misses(), 6);
  EXPECT_EQ(cache.hits(), 0);
  simulateMujoco(robot, stroke(1, 45.0, -90.0), {}, {}, out, nullptr, &cache);
  EXPECT_EQ(cache.hits(), 1);
}

TEST(MujocoSettleCache, ASweepSettlesOncePerModelAndMatchesRunsWithoutIt) {
  // The paper's Fig. 12 style sweep: many strokes, one model and start pose.
  const tailsim::testing::ScratchDir dir("settle_cache");
  const std::string path = (dir / "settle_cache_sweep.yaml").string();
  {
    std::ofstream f(path);
    f << "name: settle_cache_sweep\nrobot: paper\nkind: simulate\nmodels: [mujoco]\ntail: {links: 1}\n"
         "trajectory:\n  theta0_deg: 90\n  dtheta_deg: {sweep: [-60, -120, -180]}\n  dT_s: {sweep: [0.2, 0.3]}\n"
         "  w_ss: 0.25\n";
  }
  const Experiment e = loadExperiment(path);
  ASSERT_EQ(e.cases.size(), 6u);
  RunContext ctx;
  for (const ExperimentCase& c : e.cases) {
    SCOPED_TRACE(c.name);
    const std::vector<RunResult> with = runCase(c, &ctx);
    const std::vector<RunResult> without = runCase(c);
    ASSERT_EQ(with.size(), 1u);
    expectIdentical(without[0], with[0]);
  }
  EXPECT_EQ(ctx.mujoco_settle.misses(), 1);
  EXPECT_EQ(ctx.mujoco_settle.hits(), 5);
}
