// The stroke optimiser (src/design/): spline profiles, limits kept on the re-simulated
// optimum, a brute-force optimum found, `kind: optimize` errors at file:line:col, the best
// stroke as a ready-to-run experiment.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "models/analytic/analytic_simulation.h"
#include "models/planar/tail_dynamics.h"
#include "design/optimize_config.h"
#include "design/optimize_experiment.h"
#include "experiments/experiment_loader.h"
#include "random_robots.h"

namespace tailsim {
namespace {

namespace fs = std::filesystem;
constexpr double kDeg = M_PI / 180.0;
const std::string kSourceDir = TAILSIM_SOURCE_DIR;

// The Fig. 14 base case with n links (Eq. 25 at 600 deg/s).
ExperimentCase baseCase(int n) {
  return loadExperiment(kSourceDir + "/configs/design/base/eq25_n" + std::to_string(n) + ".yaml").cases.at(0);
}

// The Eq. (25) stroke of an n-link tail as the start, every joint torque within torque_max_Nm.
StrokeProblem torqueLimitedProblem(int n, double torque_max_Nm) {
  StrokeProblem p;
  p.base = baseCase(n);
  p.space.n_links = n;
  p.space.limits.torque_max_Nm = torque_max_Nm;
  return p;
}

OptimizerSettings smallBudget(std::uint64_t seed = 1) {
  OptimizerSettings s;
  s.islands = 2;
  s.population = 8;
  s.generations = 12;
  s.polish_evaluations = 60;
  s.seed = seed;
  return s;
}

TEST(SplineProfile, PassesThroughItsKnotsAtRestAtBothEnds) {
  SplineParams sp;
  sp.knots_rad = {0.5, 0.2, -0.7, -0.4, -1.0};
  sp.dT_s = 0.4;
  sp.t0_s = 0.1;
  const JointProfile p(sp);
  ASSERT_TRUE(p.isSpline());
  for (std::size_t k = 0; k < sp.knots_rad.size(); ++k)
    EXPECT_NEAR(p.at(sp.t0_s + sp.dT_s * k / 4.0).theta, sp.knots_rad[k], 1e-12) << "knot " << k;
  EXPECT_EQ(p.at(0.0).theta, 0.5);
  EXPECT_EQ(p.at(0.0).theta_dot, 0.0);
  EXPECT_NEAR(p.at(sp.t0_s + 1e-9).theta_dot, 0.0, 1e-6);    // clamped: zero speed at the start
  EXPECT_NEAR(p.at(sp.t0_s + sp.dT_s - 1e-9).theta_dot, 0.0, 1e-6);
  EXPECT_EQ(p.at(1.0).theta, -1.0);
  EXPECT_EQ(p.at(1.0).theta_dot, 0.0);
  // Speed is the derivative of the angle, acceleration of the speed (central differences).
  for (double t = 0.11; t < 0.5; t += 0.013) {
    const double h = 1e-6;
    EXPECT_NEAR((p.at(t + h).theta - p.at(t - h).theta) / (2 * h), p.at(t).theta_dot, 1e-5);
    EXPECT_NEAR((p.at(t + h).theta_dot - p.at(t - h).theta_dot) / (2 * h), p.at(t).theta_ddot, 1e-3);
  }
  // Peak speed: no sample is faster.
  double peak = 0;
  for (double t = 0.1; t <= 0.5; t += 1e-5) peak = std::max(peak, std::abs(p.at(t).theta_dot));
  EXPECT_NEAR(std::abs(p.peakSpeed()), peak, 1e-6);
  EXPECT_THROW(JointProfile(SplineParams{{0.1}, 0.3, 0.0}), std::invalid_argument);
}

// A short global search with no polish: its generation rows are the whole history.
OptimizerSettings globalOnly(std::uint64_t seed, int generations) {
  OptimizerSettings s = smallBudget(seed);
  s.generations = generations;
  s.polish = "none";
  return s;
}

TEST(StrokeDesign, JointOneTorqueIsTheBaseMoment) {
  const ExperimentCase c = baseCase(3);
  const TailTrajectory t = c.trajectory();
  std::vector<JointState> js;
  t.evaluate(0.1, js);
  EXPECT_NEAR(jointTorques(c.robot.tail, js)[0], tailBaseLoad(c.robot.tail, js).M_J1, 1e-12);
}

// With the paper coupling the search simulates the yaw alone (searchEffects: translation locked);
// its phi_net is the full model's to the solver's tolerance, over random strokes of every n, and
// the strokes and the full run's figures (torque sampling) are what the full run sees. With the
// exact coupling the yaw depends on the translation, and the search keeps it.
TEST(StrokeDesign, YawOnlySearchGivesTheFullModelsPhiNet) {
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double worst = 0.0;
  for (int k = 0; k < 120; ++k) {
    const int n = 1 + k % 6;
    StrokeProblem p;
    p.base = baseCase(n);
    p.space.n_links = n;
    p.space.limits.t0_max_s = 0.1;
    std::vector<double> x(static_cast<std::size_t>(p.space.dim()));
    for (double& v : x) v = u(rng);
    const StrokeEvaluation e = evaluateStroke(p, x);
    const TailTrajectory traj = p.space.trajectory(x);
    OutputSettings out;
    out.sample_dt_s = 0.01;
    out.settle_s = p.base.output.settle_s;
    const RunResult full = simulateAnalytic(p.base.robot, traj, p.base.analytic, p.base.effects, out);
    ASSERT_EQ(e.ok, full.summary.ok) << k << " " << full.summary.error;
    if (!e.ok) continue;
    const double phi_full = full.summary.phi_net_deg * kDeg;
    worst = std::max(worst, std::abs(e.phi_net_rad - phi_full) / std::max(std::abs(phi_full), 1e-3));
  }
  std::printf("yaw-only vs full phi_net, 120 random strokes: worst relative difference %.2e\n", worst);
  EXPECT_LT(worst, 1e-5);
  ExperimentCase exact = baseCase(1);
  EXPECT_FALSE(searchEffects(exact).translation);
  EXPECT_FALSE(searchEffects(exact).load_decomposition);
  exact.analytic.coupling = Coupling::kExact;
  EXPECT_EQ(searchEffects(exact).translation, exact.effects.translation);
}

// A returned optimum keeps every limit on the trajectory the model actually ran (its CSV columns),
// not as the optimiser claims: both families, with a torque limit that binds, over_torque penalize
// and slow_down.
TEST(StrokeDesign, LimitsNeverViolatedOnTheResimulatedOptimum) {
  for (const bool slow : {false, true})
  for (StrokeFamily fam : {StrokeFamily::kSplitCycle, StrokeFamily::kSpline}) {
    SCOPED_TRACE(slow ? "slow_down" : "penalize");
    StrokeProblem p;
    p.base = baseCase(2);
    p.space.family = fam;
    p.space.n_links = 2;
    p.space.knots = 2;
    p.space.limits.theta_min_rad = -60 * kDeg;
    p.space.limits.theta_max_rad = 70 * kDeg;
    p.space.limits.thetadot_max_radps = 500 * kDeg;
    p.space.limits.torque_max_Nm = 6.0;
    p.space.limits.t0_max_s = 0.05;
    p.space.slow_down_over_torque = slow;
    p.space.tail = p.base.robot.tail;
    const OptimizeResult r = optimizeStroke(p, smallBudget());
    ASSERT_TRUE(r.best.feasible()) << familyName(fam);
    const TailTrajectory traj = p.space.trajectory(r.x);
    const RunResult run = simulateAnalytic(p.base.robot, traj, p.base.analytic, p.base.effects, p.base.output);
    ASSERT_TRUE(run.summary.ok);
    const LimitCheck lc = checkLimitsOnSeries(p.base.robot.tail, run.series, p.space.limits);
    EXPECT_TRUE(lc.ok) << familyName(fam) << ": " << (lc.violations.empty() ? "" : lc.violations[0]);
    EXPECT_LE(lc.figures.peak_torque_Nm, 6.0 + 1e-9);
    EXPECT_LE(lc.figures.peak_speed_radps, 500 * kDeg * (1 + 1e-9));
    EXPECT_GE(lc.figures.theta_min_rad, -60 * kDeg - 1e-12);
    EXPECT_LE(lc.figures.theta_max_rad, 70 * kDeg + 1e-12);
    // The limit binds: the optimum uses most of the torque allowed.
    EXPECT_GT(lc.figures.peak_torque_Nm, 3.0) << familyName(fam);
    EXPECT_GT(std::abs(run.summary.phi_net_deg), 0.01);  // it turns (little: 6 N m is tight)
  }
}

// The unit box's bounds are feasible: a split-cycle stroke at speed share 1 peaks at the speed limit
// and one ending at the angle bound ends on it, each measured to rounding (1 ulp over). The n = 3
// optimum lies there; counted strictly those points were infeasible. A real excess still counts.
TEST(StrokeDesign, StrokesOnTheBoxBoundsKeepTheLimits) {
  StrokeSpace sp;
  sp.n_links = 3;
  sp.limits.t0_max_s = 0.1;
  int measured_over = 0;  // points whose measured peak speed or angle lies (by rounding) past the limit
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    sp.directions = {k % 2 ? 1 : -1, k % 3 ? 1 : -1, k % 5 ? -1 : 1};
    std::vector<double> x(static_cast<std::size_t>(sp.dim()));
    for (double& v : x) v = u(rng);
    for (int i = 0; i < 3; ++i) {
      x[static_cast<std::size_t>(5 * i + 1)] = 1.0;  // the end angle on its side's limit
      x[static_cast<std::size_t>(5 * i + 2)] = 1.0;  // the peak speed at the limit
    }
    const StrokeFigures f = strokeFigures(baseCase(3).robot.tail, sp.trajectory(x));
    if (f.peak_speed_radps > sp.limits.thetadot_max_radps || f.theta_max_rad > sp.limits.theta_max_rad ||
        f.theta_min_rad < sp.limits.theta_min_rad)
      ++measured_over;
    EXPECT_NEAR(f.peak_speed_radps, sp.limits.thetadot_max_radps, 1e-12 * sp.limits.thetadot_max_radps);
    EXPECT_EQ(limitViolation(f, sp.limits), 0.0) << k;
    StrokeLimits tighter = sp.limits;
    tighter.thetadot_max_radps *= 1.0 - 1e-6;
    EXPECT_NEAR(limitViolation(f, tighter), 1e-6, 1e-8) << k;
  }
  EXPECT_GT(measured_over, 0);  // the case the tolerance is for does occur
}

// A tiny problem solved by brute force: n = 1, w_ss and start fixed, so the free parameters are
// the start angle, the end angle and the speed share. The optimiser must reach the best point of
// a 14^3 grid (it may beat it: the grid is coarse).
TEST(StrokeDesign, FindsTheBruteForceOptimum) {
  StrokeProblem p;
  p.base = baseCase(1);
  p.space.n_links = 1;
  p.space.limits.theta_min_rad = -90 * kDeg;
  p.space.limits.theta_max_rad = 90 * kDeg;
  p.space.limits.w_ss_min = p.space.limits.w_ss_max = 0.25;
  p.space.limits.t0_max_s = 0.0;
  p.space.limits.torque_max_Nm = 12.0;
  double grid_best = 0;
  const int N = 14;
  for (int a = 0; a < N; ++a)
    for (int b = 0; b < N; ++b)
      for (int s = 0; s < N; ++s) {
        const StrokeEvaluation e = evaluateStroke(p, std::vector<double>{a / (N - 1.0), b / (N - 1.0), s / (N - 1.0), 0.0, 0.0});
        if (e.feasible()) grid_best = std::max(grid_best, e.objective);
      }
  ASSERT_GT(grid_best, 0.0);
  OptimizerSettings os = smallBudget();
  os.generations = 25;
  os.polish_evaluations = 150;
  const OptimizeResult r = optimizeStroke(p, os);
  EXPECT_TRUE(r.best.feasible());
  EXPECT_GE(r.best.objective, grid_best * (1 - 1e-3)) << "grid " << grid_best << " optimiser " << r.best.objective;
  EXPECT_GE(r.best.objective, r.start.objective);  // never worse than where it started (Eq. 25)
}

// limits.over_torque: slow_down. Every stroke over a joint's torque limit is the same motion slowed
// by one factor s: angles, w_ss and the joints' relative timing unchanged, each torque at s t the raw
// one's at t over s^2 (the fixed-base Newton-Euler recursion, an independent closed form), and the
// peak on the limit unless a duration or delay reached its range's end. Strokes within the limits
// are untouched. Per-joint limits, both families.
TEST(StrokeDesign, SlowDownMeetsTheTorqueLimitWithTheSameMotion) {
  const ExperimentCase base = baseCase(3);
  std::mt19937 rng(35);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  int untouched = 0, on_limit = 0, capped = 0;
  double lowest = 1.0;
  for (const StrokeFamily family : {StrokeFamily::kSplitCycle, StrokeFamily::kSpline}) {
    StrokeSpace raw;
    raw.family = family;
    raw.n_links = 3;
    raw.knots = 2;
    raw.limits.t0_max_s = 0.1;
    raw.limits.dT_min_s = 0.05;
    raw.limits.dT_max_s = 1.0;
    raw.limits.joints = {{-M_PI / 2, M_PI / 2, 600 * kDeg, 12.0}, {-M_PI / 2, M_PI / 2, 600 * kDeg, 6.0},
                         {-M_PI / 2, M_PI / 2, 600 * kDeg, 0.0 /* none */}};
    StrokeSpace slow = raw;
    slow.slow_down_over_torque = true;
    slow.tail = base.robot.tail;
    for (int k = 0; k < 200; ++k) {
      std::vector<double> x(static_cast<std::size_t>(raw.dim()));
      for (double& v : x) v = u01(rng);
      const TailTrajectory a = raw.trajectory(x), b = slow.trajectory(x);
      const StrokeFigures fa = strokeFigures(base.robot.tail, a), fb = strokeFigures(base.robot.tail, b);
      double over = 0.0, after = 0.0;  // the largest peak / limit before and after
      for (std::size_t i = 0; i < 2; ++i) {
        over = std::max(over, fa.joints[i].peak_torque_Nm / raw.limits.joints[i].torque_max_Nm);
        after = std::max(after, fb.joints[i].peak_torque_Nm / raw.limits.joints[i].torque_max_Nm);
      }
      auto dT = [](const JointProfile& j) { return j.isSpline() ? j.spline().dT_s : j.params().dT_s; };
      auto t0 = [](const JointProfile& j) { return j.isSpline() ? j.spline().t0_s : j.params().t0_s; };
      const double s = dT(b.joints[0]) / dT(a.joints[0]);
      if (over <= 1.0 + 1e-9) {
        EXPECT_EQ(s, 1.0) << "a stroke within its limits is left as it is";
        ++untouched;
        continue;
      }
      bool at_range_end = false;
      for (std::size_t i = 0; i < 3; ++i) {
        EXPECT_NEAR(dT(b.joints[i]), s * dT(a.joints[i]), 1e-12 * s);
        EXPECT_NEAR(t0(b.joints[i]), s * t0(a.joints[i]), 1e-12 * s);
        if (family == StrokeFamily::kSplitCycle) {
          EXPECT_EQ(b.joints[i].params().theta0_rad, a.joints[i].params().theta0_rad);
          EXPECT_EQ(b.joints[i].params().dtheta_rad, a.joints[i].params().dtheta_rad);
          EXPECT_EQ(b.joints[i].params().w_ss, a.joints[i].params().w_ss);
        } else {
          EXPECT_EQ(b.joints[i].spline().knots_rad, a.joints[i].spline().knots_rad);
        }
        at_range_end = at_range_end || dT(b.joints[i]) >= raw.limits.dT_max_s * (1 - 1e-12) ||
                       (t0(b.joints[i]) > 0 && t0(b.joints[i]) >= raw.limits.t0_max_s * (1 - 1e-12));
      }
      if (!at_range_end) {
        ASSERT_GT(s, 1.0);
      }
      for (const double t : {0.013, 0.071, 0.19, 0.33}) {  // tau_b(s t) = tau_a(t) / s^2
        std::vector<JointState> ja, jb;
        a.evaluate(t, ja);
        b.evaluate(s * t, jb);
        const std::vector<double> ta = jointTorques(base.robot.tail, ja), tb = jointTorques(base.robot.tail, jb);
        for (std::size_t i = 0; i < 3; ++i) {
          EXPECT_NEAR(jb[i].theta, ja[i].theta, 1e-9);
          EXPECT_NEAR(tb[i], ta[i] / (s * s), 1e-9 * std::max(1.0, std::abs(ta[i])));
        }
      }
      if (at_range_end) {  // slowed as far as the ranges allow: still over, by less (up to the sampling)
        EXPECT_LE(after, over * (1 + 1e-2));
        capped += s > 1.0;
      } else {
        EXPECT_LE(after, 1.0 + 1e-9);
        // On the limit, up to the figures' 0.5 ms sampling grid (the slowed stroke's grid samples
        // other phases of the motion than the raw one's).
        EXPECT_GT(after, 0.99) << "the peak torque sits on the limit";
        lowest = std::min(lowest, after);
        if (family == StrokeFamily::kSplitCycle) {
          EXPECT_EQ(limitViolation(fb, slow.limits), 0.0);
        }
        ++on_limit;
      }
    }
  }
  // Every branch is exercised.
  std::printf("untouched %d on_limit %d (lowest peak / limit %.6f) capped %d\n", untouched, on_limit, lowest, capped);
  EXPECT_GT(untouched, 5);
  EXPECT_GT(on_limit, 20);
  EXPECT_GT(capped, 5);
}

// A random robot's limits for the slow-down tests: each joint's torque limit `share` of the stroke's
// peak there, every third joint without one; durations up to 5 s, delays up to 1 s.
StrokeLimits sharedTorqueLimits(const std::vector<TailLink>& tail, const TailTrajectory& t, double share) {
  const StrokeFigures raw = strokeFigures(tail, t);
  StrokeLimits L;
  L.dT_max_s = 5.0;
  L.t0_max_s = 1.0;
  for (std::size_t i = 0; i < tail.size(); ++i)
    L.joints.push_back({-10.0, 10.0, 1e6, i % 3 == 2 ? 0.0 : share * raw.joints[i].peak_torque_Nm});
  return L;
}

// The same on 60 seeded random robots and their own strokes (tests/random_robots.h: 1-6 link tails
// of 0.3-18 kg, Eq. 25, sweeps and flicks), each joint limited to half its peak torque (or none
// for every third joint): the slowed stroke is the same motion s times slower, every torque
// tau(t) / s^2, and its peak meets the limit unless a duration reached the range's end.
TEST(StrokeDesign, SlowDownOnRandomRobotsAndStrokes) {
  int on_limit = 0;
  for (int k = 0; k < 60; ++k) {
    const testing::RandomRobotCase rc = testing::randomRobotCase(35, k);
    const std::vector<TailLink>& tail = rc.robot.tail;
    const StrokeLimits L = sharedTorqueLimits(tail, rc.trajectory, 0.5);
    StrokeFigures f;
    const TailTrajectory b = slowedToTorqueLimit(tail, L, rc.trajectory, &f);
    const StrokeFigures fb = strokeFigures(tail, b);
    EXPECT_EQ(f.peak_torque_Nm, fb.peak_torque_Nm) << "the figures handed back are the slowed stroke's";
    const double s = b.joints[0].params().dT_s / rc.trajectory.joints[0].params().dT_s;
    EXPECT_GT(s, 1.3) << testing::describe(rc);  // half the torque: about sqrt(2)
    double after = 0.0;
    for (std::size_t i = 0; i < tail.size(); ++i) {
      EXPECT_NEAR(b.joints[i].params().dT_s, s * rc.trajectory.joints[i].params().dT_s, 1e-12 * s);
      if (L.joints[i].torque_max_Nm > 0) after = std::max(after, fb.joints[i].peak_torque_Nm / L.joints[i].torque_max_Nm);
    }
    std::vector<JointState> ja, jb;
    const double t = rc.trajectory.startTime() + 0.37 * (rc.trajectory.endTime() - rc.trajectory.startTime());
    rc.trajectory.evaluate(t, ja);
    b.evaluate(s * t, jb);
    const std::vector<double> ta = jointTorques(tail, ja), tb = jointTorques(tail, jb);
    for (std::size_t i = 0; i < tail.size(); ++i) {
      EXPECT_NEAR(jb[i].theta, ja[i].theta, 1e-9);
      EXPECT_NEAR(tb[i], ta[i] / (s * s), 1e-9 * std::max(1.0, std::abs(ta[i])));
    }
    EXPECT_LE(after, 1.0 + 1e-9) << testing::describe(rc);
    EXPECT_GT(after, 0.99) << testing::describe(rc);
    ++on_limit;
  }
  EXPECT_EQ(on_limit, 60);
}

// slowedToTorqueLimit reads the slowed strokes' torques only near the raw stroke's peak (its
// corrections) and then samples the answer in full. slowedToTorqueLimitOnFullSamples makes the same
// corrections on full samples every time (the algorithm before the windows): the same stroke, bit for
// bit, and the same figures, on 60 random robots with their own strokes and on 400 random strokes of both
// families on the paper robot, whose many humps (a 6-link tail's, a spline's) are where a window
// could miss the peak.
TEST(StrokeDesign, SlowDownDecidesOnTheSameSamplesAsFullSampling) {
  int slowed = 0, compared = 0;
  auto expectSame = [&](const std::vector<TailLink>& tail, const StrokeLimits& L, const TailTrajectory& t,
                        const std::string& what) {
    StrokeFigures f;
    const TailTrajectory a = slowedToTorqueLimit(tail, L, t, &f), b = slowedToTorqueLimitOnFullSamples(tail, L, t);
    ++compared;
    if (a.joints[0].params().dT_s != t.joints[0].params().dT_s) ++slowed;
    for (std::size_t i = 0; i < t.joints.size(); ++i) {
      EXPECT_EQ(a.joints[i].params().dT_s, b.joints[i].params().dT_s) << what << " joint " << i;
      EXPECT_EQ(a.joints[i].params().t0_s, b.joints[i].params().t0_s) << what << " joint " << i;
    }
    const StrokeFigures fb = strokeFigures(tail, b);
    EXPECT_EQ(f.peak_torque_Nm, fb.peak_torque_Nm) << what;
    EXPECT_EQ(f.peak_speed_radps, fb.peak_speed_radps) << what;
    EXPECT_EQ(f.energy_J, fb.energy_J) << what;
  };
  for (int k = 0; k < 60; ++k) {
    const testing::RandomRobotCase rc = testing::randomRobotCase(36, k);
    const std::vector<TailLink>& tail = rc.robot.tail;
    const StrokeLimits L = sharedTorqueLimits(tail, rc.trajectory, 0.3 + 0.01 * k);
    expectSame(tail, L, rc.trajectory, testing::describe(rc));
  }
  const ExperimentCase base = baseCase(3);
  std::mt19937 rng(36);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  for (const StrokeFamily family : {StrokeFamily::kSplitCycle, StrokeFamily::kSpline}) {
    StrokeSpace space;
    space.family = family;
    space.n_links = 3;
    space.knots = 4;
    space.limits.t0_max_s = 0.1;
    space.limits.joints = {{-M_PI / 2, M_PI / 2, 600 * kDeg, 8.0}, {-M_PI / 2, M_PI / 2, 600 * kDeg, 3.0},
                           {-M_PI / 2, M_PI / 2, 600 * kDeg, 1.0}};
    for (int k = 0; k < 200; ++k) {
      std::vector<double> x(static_cast<std::size_t>(space.dim()));
      for (double& v : x) v = u01(rng);
      expectSame(base.robot.tail, space.limits, space.trajectory(x), std::string(familyName(family)) + " stroke " + std::to_string(k));
    }
  }
  EXPECT_EQ(compared, 460);
  EXPECT_GT(slowed, 300) << "most strokes must be over a limit, or the comparison shows little";
}

// Stuck strokes (the body does not turn) rank by how close they come to breaking away, in a band
// CMA-ES can see: its tolerance stops a generation whose fitnesses differ by less than 1e-9. With a
// band of 1e-12 the 3 kg robot's single-start search (2 x 12 x 450 generations, COBYLA 300, seed 17)
// stopped after its first population, all stuck, and reported "no stroke within the limits turns the
// body", while other seeds turn it 1.39 deg.
TEST(StrokeDesign, StuckStrokesRankAboveCmaesToleranceAndBelowEveryTurn) {
  StrokeEvaluation a, b, turn;
  a.ok = b.ok = turn.ok = true;
  a.stiction_ratio = 0.5;
  b.stiction_ratio = 0.501;
  turn.objective = 1e-12;  // the smallest turn still ranks above every stuck stroke
  EXPECT_GT(a.fitness() - b.fitness(), 1e-9 * 100);
  EXPECT_LT(turn.fitness(), b.fitness());
  StrokeEvaluation stuck_near_one = a;
  stuck_near_one.stiction_ratio = 0.999999;
  EXPECT_LT(turn.fitness(), stuck_near_one.fitness());
  StrokeEvaluation stuck_over_one = a;  // the analytic stiction ratio of a stroke another model found stuck
  stuck_over_one.stiction_ratio = 3.0;
  EXPECT_LT(turn.fitness(), stuck_over_one.fitness());
  StrokeEvaluation over = a;
  over.violation = 1e-6;
  EXPECT_GT(over.fitness(), a.fitness());  // every infeasible point below every feasible one
  StrokeEvaluation failed, far_over = over;
  far_over.violation = 50.0;  // a torque 51 times its limit
  EXPECT_GT(failed.fitness(), far_over.fitness());  // and a failed run below every infeasible one

  const fs::path dir = fs::temp_directory_path() / ("tailsim_stuck_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path f = dir / "o.yaml";
  std::ofstream(f) << "name: o\nkind: optimize\nbase: " << kSourceDir << "/configs/design/base/small_n2.yaml\n"
                   << "optimize:\n  family: split_cycle\n  limits: {dT_s: [0.05, 1.0], start_delay_s: 0.1}\n"
                   << "  islands: 2\n  population: 12\n  generations: 450\n  polish_evaluations: 300\n  seeds: [17]\n";
  const OptimizeSpec spec = loadOptimizeSpec(f.string());
  fs::remove_all(dir);
  OptimizerSettings os = spec.optimizer;
  os.seed = 17;
  const OptimizeResult r = optimizeStroke(spec.problem, os);
  EXPECT_GT(r.evaluations, 5000);
  EXPECT_GT(std::abs(r.best.phi_net_rad) / kDeg, 1.0);
}

TEST(StrokeDesign, SameSeedSameResult) {
  StrokeProblem p;
  p.base = baseCase(1);
  p.space.family = StrokeFamily::kSpline;
  p.space.knots = 1;
  p.space.limits.torque_max_Nm = 8.0;
  OptimizerSettings os = smallBudget(7);
  os.generations = 5;
  const OptimizeResult a = optimizeStroke(p, os), b = optimizeStroke(p, os);
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.best.objective, b.best.objective);
  EXPECT_EQ(a.evaluations, b.evaluations);
}

// Restarts (IPOP): the first restart is the single-start search itself (same sub-seeds), the later
// ones run fresh archipelagos with populations growing by restart_growth; the result is the best
// over all of them, so it is never worse than the single start's global best.
TEST(StrokeDesign, RestartsRunGrowingPopulationsAndKeepTheBest) {
  const StrokeProblem p = torqueLimitedProblem(1, 8.0);
  const OptimizerSettings one = globalOnly(5, 6);
  OptimizerSettings three = one;
  three.restarts = 3;
  three.restart_growth = 2;
  const OptimizeResult a = optimizeStroke(p, one), b = optimizeStroke(p, three);
  // Generation rows: 0, then one per generation of every restart.
  ASSERT_EQ(a.history.size(), 1u + 6u);
  ASSERT_EQ(b.history.size(), 1u + 3u * 6u);
  // Restart 0 repeats the single start exactly.
  for (std::size_t g = 0; g < a.history.size(); ++g) {
    EXPECT_EQ(b.history[g].evaluations, a.history[g].evaluations) << g;
    EXPECT_EQ(b.history[g].best_objective, a.history[g].best_objective) << g;
  }
  // Each restart r evaluates islands x population x 2^r per generation (and once more to fill its
  // population): the extra evaluations are those of populations 16 and 32 on 2 islands.
  const long per_pop = 2L * (6 + 1);  // islands x (initial population + generations)
  EXPECT_EQ(b.evaluations - a.evaluations, per_pop * (16 + 32));
  EXPECT_GE(b.best.objective, a.best.objective);
  EXPECT_TRUE(b.best.feasible());
}

TEST(StrokeDesign, RefineRunsCmaesOnTheGlobalSearchsPopulations) {
  const StrokeProblem p = torqueLimitedProblem(1, 8.0);
  OptimizerSettings de = smallBudget(5);
  de.algorithm = "de";
  de.generations = 5;
  de.polish = "none";
  OptimizerSettings refined = de;
  refined.refine_generations = 4;
  const OptimizeResult a = optimizeStroke(p, de), b = optimizeStroke(p, refined);
  // The global rows are the same search; then one "refine" row per CMA-ES generation.
  ASSERT_EQ(a.history.size(), 1u + 5u);
  ASSERT_EQ(b.history.size(), 1u + 5u + 4u);
  for (std::size_t g = 0; g < a.history.size(); ++g) {
    EXPECT_EQ(b.history[g].stage, "global");
    EXPECT_EQ(b.history[g].evaluations, a.history[g].evaluations) << g;
    EXPECT_EQ(b.history[g].best_objective, a.history[g].best_objective) << g;
  }
  for (std::size_t g = a.history.size(); g < b.history.size(); ++g) {
    EXPECT_EQ(b.history[g].stage, "refine");
    EXPECT_GE(b.history[g].best_objective, b.history[g - 1].best_objective);
  }
  // Each refine generation evaluates islands x population points (CMA-ES keeps the population size).
  EXPECT_EQ(b.evaluations - a.evaluations, 2L * de.population * 4);
  EXPECT_GE(b.best.objective, a.best.objective);
  EXPECT_TRUE(b.best.feasible());
}

TEST(StrokeDesign, DirectionsFixEachJointsStrokeSideAndRoundTrip) {
  StrokeSpace sp;
  sp.n_links = 3;
  sp.limits.t0_max_s = 0.1;
  sp.directions = {1, -1, 1};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 2000; ++k) {
    std::vector<double> x(static_cast<std::size_t>(sp.dim()));
    for (double& v : x) v = u(rng);
    const TailTrajectory t = sp.trajectory(x);
    for (int i = 0; i < 3; ++i) {
      const SplitCycleParams& p = t.joints[static_cast<std::size_t>(i)].params();
      EXPECT_GE(p.dtheta_rad * sp.directions[static_cast<std::size_t>(i)], 0.0);
      EXPECT_GE(p.theta0_rad + p.dtheta_rad, sp.limits.theta_min_rad - 1e-12);
      EXPECT_LE(p.theta0_rad + p.dtheta_rad, sp.limits.theta_max_rad + 1e-12);
    }
    // pointOf inverts trajectory (the duration is clipped by the dT range, so compare strokes).
    std::vector<SplitCycleParams> ps;
    for (const auto& j : t.joints) ps.push_back(j.params());
    const TailTrajectory back = sp.trajectory(sp.pointOf(ps));
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(back.joints[static_cast<std::size_t>(i)].params().theta0_rad, ps[static_cast<std::size_t>(i)].theta0_rad, 1e-12);
      EXPECT_NEAR(back.joints[static_cast<std::size_t>(i)].params().dtheta_rad, ps[static_cast<std::size_t>(i)].dtheta_rad, 1e-12);
    }
  }
}

TEST(StrokeDesign, EnumeratedDirectionsSearchEveryPatternAndKeepTheBest) {
  StrokeProblem p;
  p.base = baseCase(2);
  p.space.n_links = 2;
  OptimizerSettings s = smallBudget(3);
  s.generations = 4;
  s.polish_evaluations = 20;
  s.enumerate_directions = true;
  const OptimizeResult r = optimizeStroke(p, s);
  ASSERT_EQ(r.by_direction.size(), 4u);
  std::set<std::vector<int>> patterns;
  long evaluations = 0;
  double best = 0.0;
  for (const DirectionResult& d : r.by_direction) {
    patterns.insert(d.directions);
    evaluations += d.evaluations;
    if (d.best.feasible()) best = std::max(best, d.best.objective);
  }
  EXPECT_EQ(patterns.size(), 4u);
  EXPECT_EQ(evaluations, r.evaluations);
  EXPECT_EQ(r.best.objective, best);
  // The result's trajectory is its point in its pattern's space, strokes on the pattern's sides,
  // and re-evaluating it gives the same objective.
  ASSERT_EQ(r.directions.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) EXPECT_GE(r.trajectory.joints[i].params().dtheta_rad * r.directions[i], 0.0);
  EXPECT_EQ(evaluateStroke(p, r.trajectory).objective, r.best.objective);
  // The history is one curve: counts and the best so far never go down.
  for (std::size_t k = 1; k < r.history.size(); ++k) {
    EXPECT_GE(r.history[k].evaluations, r.history[k - 1].evaluations);
    EXPECT_GE(r.history[k].generation, r.history[k - 1].generation);
    EXPECT_GE(r.history[k].best_objective, r.history[k - 1].best_objective);
  }
}

// Local restarts: after the global search, CMA-ES runs centred on the best point so far. The
// global rows are the same search; each local run evaluates its random population, the incumbent
// placed in it, and population points per generation on every island; the best never goes down.
TEST(StrokeDesign, LocalRestartsContinueFromTheBestAndNeverLose) {
  const StrokeProblem p = torqueLimitedProblem(1, 8.0);
  const OptimizerSettings global = globalOnly(5, 6);
  OptimizerSettings local = global;
  local.local_restarts = 3;
  local.local_step = 0.05;
  const OptimizeResult a = optimizeStroke(p, global), b = optimizeStroke(p, local);
  ASSERT_EQ(a.history.size(), 1u + 6u);
  ASSERT_EQ(b.history.size(), 1u + 6u + 3u * 6u);
  for (std::size_t g = 0; g < a.history.size(); ++g) {
    EXPECT_EQ(b.history[g].stage, "global");
    EXPECT_EQ(b.history[g].evaluations, a.history[g].evaluations) << g;
    EXPECT_EQ(b.history[g].best_objective, a.history[g].best_objective) << g;
  }
  for (std::size_t g = a.history.size(); g < b.history.size(); ++g) {
    EXPECT_EQ(b.history[g].stage, "local");
    EXPECT_GE(b.history[g].best_objective, b.history[g - 1].best_objective);
  }
  EXPECT_EQ(b.evaluations - a.evaluations, 3L * 2L * ((6 + 1) * global.population + 1));
  EXPECT_GE(b.best.objective, a.best.objective);
  EXPECT_TRUE(b.best.feasible());
}

// max_runs caps a search's runs, polish included. A search whose first restart is the single-start
// search (same islands, population, generations and seed) repeats it exactly while it runs and
// gives only the budget it leaves (CMA-ES stopped by its tolerances) to the later restarts, the
// local restarts and the polish: at the single start's cost it never ends below it.
TEST(StrokeDesign, RunBudgetCapsTheSearchAndTheFirstRestartIsTheSingleStart) {
  const StrokeProblem p = torqueLimitedProblem(1, 8.0);
  OptimizerSettings single = smallBudget(3);
  single.islands = 1;
  single.population = 6;
  single.generations = 1000;
  single.polish_evaluations = 40;
  const long cost = 2 + single.islands * single.population * (single.generations + 1L) + single.polish_evaluations;
  OptimizerSettings preset = single;
  preset.restarts = 4;
  preset.restart_growth = 2;
  preset.local_restarts = 2;
  preset.local_step = 0.05;
  preset.max_runs = cost;
  const OptimizeResult a = optimizeStroke(p, single), b = optimizeStroke(p, preset);
  ASSERT_LT(a.evaluations, cost / 2);  // CMA-ES stopped early: budget left for the preset's other stages
  EXPECT_LE(b.evaluations, cost);
  EXPECT_GT(b.evaluations, a.evaluations);
  // The single start's global stage, row by row.
  std::size_t g = 0;
  for (; g < a.history.size() && a.history[g].stage == "global"; ++g) {
    EXPECT_EQ(b.history[g].evaluations, a.history[g].evaluations) << g;
    EXPECT_EQ(b.history[g].best_objective, a.history[g].best_objective) << g;
  }
  EXPECT_GE(b.best.objective, a.best.objective);
  EXPECT_TRUE(b.best.feasible());
  std::set<std::string> stages;
  for (std::size_t k = g; k < b.history.size(); ++k) stages.insert(b.history[k].stage);
  EXPECT_TRUE(stages.count("global")) << "the budget left ran a later restart";
}

// Successive halving over the joint-direction patterns: every pattern's first global restart runs,
// the other restarts, the local restarts and the polish only in the directions_kept patterns whose
// first restart found the most. The other patterns' results are exactly their first restart (the
// same sub-seeds), the kept ones' exactly the whole search.
TEST(StrokeDesign, DirectionsKeptFinishOnlyTheBestPatterns) {
  StrokeProblem p;
  p.base = baseCase(2);
  p.space.n_links = 2;
  OptimizerSettings global = globalOnly(3, 4);
  global.enumerate_directions = true;
  OptimizerSettings kept = global;
  kept.restarts = 2;
  kept.restart_growth = 2;
  kept.polish = "cobyla";
  kept.polish_evaluations = 20;
  kept.local_restarts = 1;
  kept.directions_kept = 1;
  OptimizerSettings whole = kept;
  whole.directions_kept = 0;
  const OptimizeResult a = optimizeStroke(p, global), b = optimizeStroke(p, kept), w = optimizeStroke(p, whole);
  ASSERT_EQ(a.by_direction.size(), 4u);
  ASSERT_EQ(b.by_direction.size(), 4u);
  std::size_t top = 0;
  for (std::size_t m = 1; m < 4; ++m)
    if (a.by_direction[m].best.objective > a.by_direction[top].best.objective) top = m;
  for (std::size_t m = 0; m < 4; ++m) {
    EXPECT_EQ(b.by_direction[m].directions, a.by_direction[m].directions);
    if (m == top) {
      EXPECT_EQ(b.by_direction[m].evaluations, w.by_direction[m].evaluations);
      EXPECT_EQ(b.by_direction[m].best.objective, w.by_direction[m].best.objective);
      EXPECT_GT(b.by_direction[m].evaluations, a.by_direction[m].evaluations + 2L * 5 * 16);
      EXPECT_GE(b.by_direction[m].best.objective, a.by_direction[m].best.objective);
    } else {
      EXPECT_EQ(b.by_direction[m].evaluations, a.by_direction[m].evaluations) << m;
      EXPECT_EQ(b.by_direction[m].best.objective, a.by_direction[m].best.objective) << m;
    }
  }
  EXPECT_GE(b.best.objective, a.best.objective);
  // Keeping every pattern is the plain enumeration (each pattern's search runs through).
  OptimizerSettings all = kept;
  all.directions_kept = 4;
  const OptimizeResult c = optimizeStroke(p, all);
  for (std::size_t m = 0; m < 4; ++m) {
    EXPECT_EQ(c.by_direction[m].evaluations, w.by_direction[m].evaluations);
    EXPECT_EQ(c.by_direction[m].best.objective, w.by_direction[m].best.objective);
  }
}

// restart_polish_evaluations: the polish's algorithm runs from each global restart's best point
// before the next restart, so every restart's basin is converged, not only the best one's. The
// first restart's global rows are the plain search's; one polish row follows every restart, each
// within its budget, and the best never goes down.
TEST(StrokeDesign, RestartPolishConvergesEveryRestart) {
  const StrokeProblem p = torqueLimitedProblem(1, 8.0);
  OptimizerSettings plain = globalOnly(5, 6);
  plain.restarts = 3;
  plain.polish = "cobyla";
  plain.polish_evaluations = 0;  // no final polish: the rows below are the restarts' own
  OptimizerSettings each = plain;
  each.restart_polish_evaluations = 25;
  const OptimizeResult a = optimizeStroke(p, plain), b = optimizeStroke(p, each);
  ASSERT_EQ(a.history.size(), 1u + 3u * 6u);
  ASSERT_EQ(b.history.size(), 1u + 3u * (6u + 1u));
  for (std::size_t g = 0; g <= 6; ++g) {
    EXPECT_EQ(b.history[g].stage, "global");
    EXPECT_EQ(b.history[g].evaluations, a.history[g].evaluations) << g;
    EXPECT_EQ(b.history[g].best_objective, a.history[g].best_objective) << g;
  }
  long polish_runs = 0;
  for (std::size_t r = 0; r < 3; ++r) {
    const std::size_t row = 1 + r * 7 + 6;  // after restart r's 6 generations
    EXPECT_EQ(b.history[row].stage, "polish") << r;
    const long runs = b.history[row].evaluations - b.history[row - 1].evaluations;
    EXPECT_GE(runs, 1) << r;
    EXPECT_LE(runs, 25) << r;
    polish_runs += runs;
  }
  EXPECT_EQ(b.evaluations - a.evaluations, polish_runs);
  for (std::size_t k = 1; k < b.history.size(); ++k) EXPECT_GE(b.history[k].best_objective, b.history[k - 1].best_objective);
  EXPECT_GE(b.best.objective, a.best.objective);
  EXPECT_TRUE(b.best.feasible());
}

// With directions: enumerate, max_runs is the seed's budget over all patterns: the first restarts
// share it evenly, the kept patterns share what they leave (the earlier kept pattern's unused
// runs go to the next), so the seed costs at most max_runs whatever n is.
TEST(StrokeDesign, EnumeratedDirectionsShareOneRunBudget) {
  StrokeProblem p;
  p.base = baseCase(2);
  p.space.n_links = 2;
  OptimizerSettings s = globalOnly(3, 4);
  s.enumerate_directions = true;
  s.restarts = 10;
  s.polish = "cobyla";
  s.polish_evaluations = 20;
  s.restart_polish_evaluations = 10;
  s.directions_kept = 1;
  const long first = 1 + 2L * 8 * (4 + 1) + 2 + 10;  // start, restart 0 (the start set in 2 islands), its polish
  s.max_runs = 4 * first + 300;
  const OptimizeResult r = optimizeStroke(p, s);
  ASSERT_EQ(r.by_direction.size(), 4u);
  EXPECT_LE(r.evaluations, s.max_runs);
  EXPECT_GT(r.evaluations, s.max_runs - 2L * 8 * 5);  // the runs left went to the kept pattern
  int kept = 0;
  for (const DirectionResult& d : r.by_direction) {
    EXPECT_LE(d.evaluations, d.evaluations > first ? s.max_runs : first);
    if (d.evaluations > first) ++kept;
  }
  EXPECT_EQ(kept, 1);
  // Without halving every pattern's whole search shares it too.
  s.directions_kept = 0;
  const OptimizeResult all = optimizeStroke(p, s);
  EXPECT_LE(all.evaluations, s.max_runs);
  for (const DirectionResult& d : all.by_direction) EXPECT_GT(d.evaluations, first);
}

class OptimizeFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string tmpl = (fs::temp_directory_path() / "tailsim_design_XXXXXX").string();
    ASSERT_NE(mkdtemp(tmpl.data()), nullptr);
    dir_ = tmpl;
    std::ofstream(dir_ / "base.yaml") << "name: b\nrobot: " << kSourceDir
                                       << "/configs/robots/paper_quadruped.yaml\ntail: {links: 1}\n"
                                          "trajectory: {rule: eq25, thetadot_max_dps: 600, w_ss: 0.25}\nmodels: [analytic]\n";
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string write(const std::string& optimize_section, const std::string& head = "name: o\nkind: optimize\nbase: base.yaml\n") {
    const fs::path p = dir_ / "opt.yaml";
    std::ofstream(p) << head << "optimize:\n" << optimize_section;
    return p.string();
  }
  std::string error(const std::string& file) {
    try {
      loadOptimizeSpec(file);
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "(no error)";
  }
  // `tailsim optimize` on a tiny budget, then `tailsim run DIR/best.yaml`: same phi_net in every model.
  void checkBestRuns(const std::string& family);
  fs::path dir_;
};

constexpr const char* kLimits = "  limits: {theta_deg: [-90, 90], thetadot_max_dps: 600, torque_max_Nm: none}\n";

// best.yaml runs its stroke to the tail's end + settle, as the re-runs in summary.json do, even
// when the base experiment cut its runs short (output.duration_s); without an output section it
// gets none.
TEST_F(OptimizeFileTest, BestYamlRunsTheStrokeToItsEnd) {
  for (const bool cut : {true, false}) {
    std::ofstream(dir_ / "base.yaml") << "name: b\nrobot: " << kSourceDir
                                       << "/configs/robots/paper_quadruped.yaml\ntail: {links: 1}\n"
                                          "trajectory: {rule: eq25, thetadot_max_dps: 600, w_ss: 0.25}\nmodels: [analytic]\n"
                                       << (cut ? "output: {duration_s: 0.05, sample_dt_s: 0.01}\n" : "");
    const OptimizeSpec s = loadOptimizeSpec(write(std::string("  family: split_cycle\n") + kLimits + "  seeds: [1]\n"));
    EXPECT_EQ(s.base.output.duration_s, cut ? 0.05 : 0.0);
    const std::string y = bestExperimentYaml(s, s.base.trajectory());
    // best.yaml names the robot copy its folder holds (designFolderInputs).
    fs::copy_file(kSourceDir + "/configs/robots/paper_quadruped.yaml", dir_ / "robot.yaml", fs::copy_options::overwrite_existing);
    const Experiment e = loadExperimentText(y, (dir_ / "best.yaml").string());
    ASSERT_EQ(e.cases.size(), 1u);
    EXPECT_EQ(e.cases[0].output.duration_s, 0.0) << y;
    if (cut) {
      EXPECT_EQ(e.cases[0].output.sample_dt_s, 0.01) << y;  // the rest of the section stays
    }
    EXPECT_EQ(y.find("output") != std::string::npos, cut) << y;
  }
}

TEST_F(OptimizeFileTest, GoodFileLoads) {
  const OptimizeSpec s = loadOptimizeSpec(write(std::string("  family: spline\n  knots: 2\n") + kLimits +
                                                "  seeds: [1, 2]\n  islands: 3\n  objective: phi_net_per_energy\n"));
  EXPECT_EQ(s.problem.space.family, StrokeFamily::kSpline);
  EXPECT_EQ(s.problem.space.knots, 2);
  EXPECT_EQ(s.problem.space.n_links, 1);
  EXPECT_EQ(s.optimizer.islands, 3);
  EXPECT_EQ(s.seeds.size(), 2u);
  EXPECT_EQ(s.problem.objective, StrokeObjective::kPhiNetPerEnergy);
  EXPECT_NEAR(s.problem.space.limits.thetadot_max_radps, 600 * kDeg, 1e-12);
  EXPECT_EQ(s.problem.space.limits.torque_max_Nm, 0.0);  // no torque limit unless given
  // torque_max_Nm: base is the base stroke's own peak joint torque (Eq. 25, n = 1: about 8.4 N m).
  const OptimizeSpec t = loadOptimizeSpec(write("  family: spline\n  limits: {theta_deg: [-90, 90], thetadot_max_dps: 600, torque_max_Nm: base}\n"));
  EXPECT_NEAR(t.problem.space.limits.torque_max_Nm,
              strokeFigures(t.base.robot.tail, t.base.trajectory()).peak_torque_Nm, 1e-12);
  EXPECT_GT(t.problem.space.limits.torque_max_Nm, 8.0);
  EXPECT_LT(t.problem.space.limits.torque_max_Nm, 9.0);
  // The search-stage keys (defaults: no local restarts, step 0.1, every pattern kept).
  EXPECT_EQ(s.optimizer.local_restarts, 0);
  EXPECT_EQ(s.optimizer.directions_kept, 0);
  const OptimizeSpec u = loadOptimizeSpec(write(std::string("  family: split_cycle\n") + kLimits +
                                                "  local_restarts: 7\n  local_step: 0.2\n  directions: enumerate\n  directions_kept: 2\n"));
  EXPECT_EQ(u.optimizer.local_restarts, 7);
  EXPECT_EQ(u.optimizer.local_step, 0.2);
  EXPECT_TRUE(u.optimizer.enumerate_directions);
  EXPECT_EQ(u.optimizer.directions_kept, 2);
  // over_torque: penalize by default; slow_down gives the space the base's tail for its torques.
  EXPECT_FALSE(u.problem.space.slow_down_over_torque);
  const OptimizeSpec v = loadOptimizeSpec(write(
      "  family: split_cycle\n  limits: {theta_deg: [-90, 90], thetadot_max_dps: 600, torque_max_Nm: 2, over_torque: slow_down}\n"));
  EXPECT_TRUE(v.problem.space.slow_down_over_torque);
  EXPECT_EQ(v.problem.space.tail.size(), 1u);
  EXPECT_EQ(v.problem.space.tail.at(0).mass_kg, v.base.robot.tail.at(0).mass_kg);
}

TEST_F(OptimizeFileTest, BadSettingsNameFileLineColumnAndKey) {
  const std::string f = (dir_ / "opt.yaml").string();
  struct Bad {
    std::string section;
    std::string where;  // line:col: key:
    std::string what;
  };
  const std::vector<Bad> cases = {
      {"  family: split_cycle\n" + std::string(kLimits) + "  islands: 0\n", "7:12: optimize.islands: ", "must lie in [1, 64]"},
      {"  family: spline\n" + std::string(kLimits) + "  populaton: 10\n", "7:3: optimize.populaton: ", "unknown key"},
      {"  family: spline\n  limits: {theta_deg: [90, -90], thetadot_max_dps: 600}\n", "6:23: optimize.limits.theta_deg: ",
       "low <= high"},
      {"  family: spline\n  limits: {theta_deg: [-90, 90], thetadot_max_dps: 600, w_ss: [0.1, 0.3]}\n",
       "6:63: optimize.limits.w_ss: ", "only used with family: split_cycle"},
      {"  family: split_cycle\n  limits: {theta_deg: [-90, 90], thetadot_max_dps: 600, end: start}\n",
       "6:62: optimize.limits.end: ", "cannot end where it started"},
      {"  family: split_cycle\n  limits: {theta_deg: [-90, 90], thetadot_max_dps: 600, over_torque: slower}\n",
       "6:70: optimize.limits.over_torque: ", "not one of: penalize, slow_down"},
      {"  family: spline\n  limits: {theta_deg: [-90, 90], thetadot_max_dps: -5}\n", "6:52: optimize.limits.thetadot_max_dps: ",
       "must lie in"},
      {"  family: spline\n  limits: {theta_deg: [-90, 90]}\n", "6:11: optimize.limits.thetadot_max_dps: ", "required key is missing"},
      {"  family: bspline\n" + std::string(kLimits), "5:11: optimize.family: ", "not one of: split_cycle, spline"},
      {"  family: spline\n" + std::string(kLimits) + "  seeds: [1, 1]\n", "7:14: optimize.seeds[1]: ", "duplicate seed"},
      {"  family: spline\n" + std::string(kLimits) + "  pareto_points: 1\n", "7:18: optimize.pareto_points: ", "at least 2"},
      {"  family: spline\n" + std::string(kLimits) + "  restarts: 0\n", "7:13: optimize.restarts: ", "must lie in [1, 50]"},
      {"  family: spline\n" + std::string(kLimits) + "  population: 300\n  restarts: 3\n  restart_growth: 2\n",
       "9:19: optimize.restart_growth: ", "population of 1200, over 1000"},
      {"  family: spline\n" + std::string(kLimits) + "  directions: enumerate\n", "7:15: optimize.directions: ",
       "enumerate needs family: split_cycle"},
      {"  family: split_cycle\n" + std::string(kLimits) + "  directions: both\n", "7:15: optimize.directions: ",
       "not one of: free, enumerate"},
      {"  family: split_cycle\n" + std::string(kLimits) + "  refine_generations: -1\n", "7:23: optimize.refine_generations: ",
       "must lie in [0, 10000]"},
      {"  family: split_cycle\n" + std::string(kLimits) + "  local_restarts: 201\n", "7:19: optimize.local_restarts: ",
       "must lie in [0, 200]"},
      {"  family: split_cycle\n" + std::string(kLimits) + "  local_step: 0\n", "7:15: optimize.local_step: ", "must be > 0"},
      {"  family: split_cycle\n" + std::string(kLimits) + "  directions_kept: 1\n", "7:20: optimize.directions_kept: ",
       "only used with directions: enumerate"},
      {"  family: split_cycle\n" + std::string(kLimits) + "  directions: enumerate\n  directions_kept: 3\n",
       "8:20: optimize.directions_kept: ", "an n = 1 tail has only 2"},
  };
  for (const Bad& b : cases) {
    const std::string msg = error(write(b.section));
    EXPECT_EQ(msg.rfind(f + ":" + b.where, 0), 0u) << msg;
    EXPECT_NE(msg.find(b.what), std::string::npos) << msg;
  }
  // The base experiment's own errors name the base file (the experiment loader's message).
  std::ofstream(dir_ / "base.yaml") << "name: b\nrobot: paper\ntail: {links: 9}\ntrajectory: {rule: eq25, thetadot_max_dps: 600}\n";
  const std::string msg = error(write(std::string("  family: spline\n") + kLimits));
  EXPECT_EQ(msg.rfind((dir_ / "base.yaml").string() + ":3:", 0), 0u) << msg;
}

// Every kind: optimize file shipped in configs/design loads (their bases load with the experiment loader).
TEST(ShippedConfigs, OptimizeFilesLoad) {
  int loaded = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(kSourceDir) / "configs/design")) {
    if (entry.path().extension() != ".yaml") continue;
    if (entry.path().filename().string().rfind("maneuver_", 0) == 0) continue;  // kind: maneuver (test_maneuver.cc)
    try {
      const OptimizeSpec s = loadOptimizeSpec(entry.path().string());
      EXPECT_EQ(s.problem.space.n_links, s.base.robot.numLinks());
    } catch (const ConfigError& e) {
      ADD_FAILURE() << e.what();
    }
    ++loaded;
  }
  EXPECT_GE(loaded, 5);  // split_n1, spline_n1, split_n3, split_n3_seeds_halving, the two start_here presets
}

int runCommand(const std::string& cmd, std::string& out) {
  std::unique_ptr<FILE, int (*)(FILE*)> p(popen((cmd + " 2>&1").c_str(), "r"), pclose);
  char buf[4096];
  std::size_t k;
  while ((k = fread(buf, 1, sizeof buf, p.get())) > 0) out.append(buf, k);
  const int rc = pclose(p.release());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

// `tailsim optimize` writes the best stroke as an experiment that `tailsim run` runs as it is,
// with the same phi_net; the history CSV and plot exist.
void OptimizeFileTest::checkBestRuns(const std::string& family) {
  const std::string f = write("  family: " + family + "\n" + kLimits +
                              "  islands: 2\n  population: 8\n  generations: 6\n  polish_evaluations: 30\n  seeds: [3]\n");
  const std::string bin = std::string(TAILSIM_BINARY_DIR) + "/tailsim";
  std::string out;
  ASSERT_EQ(runCommand(bin + " optimize " + f + " --out " + (dir_ / "res").string() + " --quiet", out), 0) << out;
  EXPECT_NE(out.find("limits kept"), std::string::npos) << out;
  for (const char* file :
       {"best.yaml", "history.csv", "plots/history.png", "summary.json", "best_analytic.csv", "best_perfoot.csv"})
    EXPECT_TRUE(fs::is_regular_file(dir_ / "res" / file)) << file;
  nlohmann::json opt;
  std::ifstream(dir_ / "res/summary.json") >> opt;
  std::string out2;
  ASSERT_EQ(runCommand(bin + " run " + (dir_ / "res/best.yaml").string() + " --out " + (dir_ / "run").string() + " --quiet",
                       out2), 0) << out2;
  nlohmann::json run;
  std::ifstream(dir_ / "run/summary.json") >> run;
  const double phi_run = run["cases"][0]["runs"]["analytic"]["phi_net_deg"].get<double>();
  EXPECT_NEAR(phi_run, opt["resimulated"]["analytic"]["phi_net_deg"].get<double>(), 1e-9);
  // The search ran the yaw alone (searchEffects: paper coupling, translation locked); the full run
  // agrees to the solver's tolerance (measured 5.8e-8 deg of 12.04 deg for this case).
  EXPECT_NEAR(phi_run, opt["best"]["phi_net_deg"].get<double>(), 1e-6 * std::abs(phi_run));
  EXPECT_GT(std::abs(phi_run), 2.43);  // beats the Eq. (25) start (2.44 deg) or equals it
  // The other models' re-runs in summary.json are what `tailsim run best.yaml` gives them.
  ASSERT_TRUE(opt["resimulated"]["perfoot"]["ok"].get<bool>()) << opt["resimulated"]["perfoot"].dump();
  EXPECT_NEAR(run["cases"][0]["runs"]["perfoot"]["phi_net_deg"].get<double>(),
              opt["resimulated"]["perfoot"]["phi_net_deg"].get<double>(), 1e-9);
  EXPECT_NEAR(opt["resimulated"]["perfoot"]["difference_deg"].get<double>(),
              opt["resimulated"]["perfoot"]["phi_net_deg"].get<double>() - phi_run, 1e-9);
  ASSERT_TRUE(opt["resimulated"].contains("mujoco"));
  {
    EXPECT_NEAR(run["cases"][0]["runs"]["mujoco"]["phi_net_deg"].get<double>(),
                opt["resimulated"]["mujoco"]["phi_net_deg"].get<double>(), 1e-9);
  }
}


TEST_F(OptimizeFileTest, BestStrokeIsAReadyToRunExperiment) { checkBestRuns("split_cycle"); }

// A spline optimum too: best.yaml holds `trajectory: {family: spline, knots_deg: ...}` (summary.json's
// knots), and `tailsim run` gives every model the phi_net summary.json reports.
TEST_F(OptimizeFileTest, BestSplineStrokeIsAReadyToRunExperiment) {
  checkBestRuns("spline\n  knots: 2");
  const Experiment best = loadExperiment((dir_ / "res/best.yaml").string());
  ASSERT_EQ(best.cases.size(), 1u);
  ASSERT_EQ(best.cases[0].splines.size(), 1u);
  EXPECT_TRUE(best.cases[0].joints.empty());
  nlohmann::json opt;
  std::ifstream(dir_ / "res/summary.json") >> opt;
  std::vector<double> knots;
  for (double k : best.cases[0].splines[0].knots_rad) knots.push_back(k * 180.0 / M_PI);
  const auto want = opt["best"]["joints"][0]["knots_deg"].get<std::vector<double>>();
  ASSERT_EQ(knots.size(), 4u);  // start, 2 interior knots, end
  ASSERT_EQ(want.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k) EXPECT_NEAR(knots[k], want[k], 1e-9) << k;
}

}  // namespace
}  // namespace tailsim
