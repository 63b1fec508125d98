// Limits at the model level: counts that would overflow are refused, step budgets
// end a run with a clear error, a run that ends while the body moves says so, non-finite loads
// fail the run, and doubtful results (paper coupling outside its validity, coarse MuJoCo step)
// carry warnings. (The loader's refusals of the same inputs are in test_experiment_loader.cc.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "analytic_test_util.h"
#include "random_cases.h"
#include "models/mujoco/mujoco_simulation.h"
#include "common/work_limits.h"

namespace tailsim {
namespace {

using testing::deg;
using testing::paperRobot;
using testing::runFig7;
using testing::sameMove;

bool anyWarningContains(const RunSummary& s, const std::string& what) {
  for (const std::string& w : s.warnings)
    if (w.find(what) != std::string::npos) return true;
  return false;
}

// 5: sample_dt_s 1e-20 made floor(t_end / dt) overflow a long (UB): 0 rows, phi_net 0, ok.
TEST(Finding5Overflow, AnalyticRefusesARowCountThatOverflows) {
  OutputSettings o;
  o.sample_dt_s = 1e-20;
  EXPECT_THROW(runFig7({}, {}, o), std::invalid_argument);
  o.sample_dt_s = 1e-3;
  o.duration_s = 1e300;
  EXPECT_THROW(runFig7({}, {}, o), std::invalid_argument);
}

TEST(Finding5Overflow, MujocoRefusesRowAndStepCountsThatOverflow) {
  OutputSettings o;
  o.sample_dt_s = 1e-20;
  EXPECT_THROW(simulateMujoco(paperRobot(1), sameMove(1, 0, -90, 0.25, 0.25), {}, {}, o), std::invalid_argument);
  MujocoSettings s;
  s.settle_s = 1e300;
  EXPECT_THROW(simulateMujoco(paperRobot(1), sameMove(1, 0, -90, 0.25, 0.25), s, {}, {}), std::invalid_argument);
}

// 7: a run needing more steps than its budget fails with a clear error instead of running on.
TEST(Finding7StepBudget, AnalyticRunOverItsStepBudgetFails) {
  AnalyticSettings s;
  s.max_step_s = 1e-7;  // 3.5 million steps for the tail motion
  s.max_steps = 2000;
  const RunResult r = runFig7(s);
  EXPECT_FALSE(r.summary.ok);
  EXPECT_NE(r.summary.error.find("step budget of 2000 steps exhausted"), std::string::npos) << r.summary.error;
  EXPECT_EQ(AnalyticSettings{}.max_steps, static_cast<long>(limits::kMaxAnalyticSteps));
}

TEST(Finding7StepBudget, MujocoRunOverItsStepBudgetFails) {
  MujocoSettings s;
  s.max_steps = 100;
  const RunResult r = simulateMujoco(paperRobot(1), sameMove(1, 0, -90, 0.25, 0.25), s, {}, {});
  EXPECT_FALSE(r.summary.ok);
  EXPECT_NE(r.summary.error.find("step budget of 100 MuJoCo steps exhausted"), std::string::npos) << r.summary.error;
}

// 6a: dT = 1e-4 s left the body spinning at 71,000 deg/s at the end, reported ok without a word.
TEST(Finding6aAtRest, AnalyticRunEndingWhileTheBodyMovesSaysSo) {
  const RunResult fast = simulateAnalytic(paperRobot(1), sameMove(1, 0, -90, 1e-4, 0.25), {}, {}, {});
  ASSERT_TRUE(fast.summary.ok) << fast.summary.error;
  EXPECT_FALSE(fast.summary.at_rest);
  EXPECT_TRUE(anyWarningContains(fast.summary, "still moving when the run ends")) << fast.summary.warnings.size();
  const RunResult fig7 = runFig7();
  EXPECT_TRUE(fig7.summary.at_rest);
  EXPECT_TRUE(fig7.summary.warnings.empty());
}

TEST(Finding6aAtRest, MujocoRunEndingWhileTheBodyMovesSaysSo) {
  OutputSettings cut;
  cut.duration_s = 0.2;  // the tail is still swinging
  const RunResult moving = simulateMujoco(paperRobot(1), sameMove(1, 0, -90, 0.25, 0.25), {}, {}, cut);
  ASSERT_TRUE(moving.summary.ok) << moving.summary.error;
  EXPECT_FALSE(moving.summary.at_rest);
  EXPECT_TRUE(anyWarningContains(moving.summary, "still moving when the run ends"));
  const RunResult full = simulateMujoco(paperRobot(1), sameMove(1, 0, -90, 0.25, 0.25), {}, {}, {});
  ASSERT_TRUE(full.summary.ok) << full.summary.error;
  EXPECT_TRUE(full.summary.at_rest);
  EXPECT_TRUE(full.summary.warnings.empty()) << full.summary.warnings.front();
}

// 6b: dtheta = -1e300 deg gave NaN loads and phi_net 0, ok.
TEST(Finding6bNonFinite, NonFiniteTailLoadsFailBothModels) {
  const TailTrajectory huge = sameMove(1, 0, -1e300, 0.25, 0.25);
  const RunResult a = simulateAnalytic(paperRobot(1), huge, {}, {}, {});
  EXPECT_FALSE(a.summary.ok);
  EXPECT_NE(a.summary.error.find("non-finite"), std::string::npos) << a.summary.error;
  const RunResult m = simulateMujoco(paperRobot(1), huge, {}, {}, {});
  EXPECT_FALSE(m.summary.ok);
  EXPECT_TRUE(std::isnan(m.summary.phi_net_deg));
}

// 6c: a near-massless body: the analytic model said it tips over, MuJoCo +163.8 deg ok.
TEST(Finding6cMassless, BothModelsReportTheNearMasslessBodyTippingOver) {
  RobotParams r = paperRobot(1, 0.1405);
  r.quadruped.mass_kg = 1e-6;
  const TailTrajectory t = sameMove(1, 0, -90, 0.25, 0.25);
  const RunResult a = simulateAnalytic(r, t, {}, {}, {});
  const RunResult m = simulateMujoco(r, t, {}, {}, {});
  EXPECT_FALSE(a.summary.ok);
  EXPECT_FALSE(m.summary.ok);
  EXPECT_NE(m.summary.error.find("fell over"), std::string::npos) << m.summary.error;
}

// 6d: a 6-link tail at 5000 deg/s: the paper coupling -175 deg where the exact one gives +20.6.
TEST(Finding6dPaperCoupling, LargeAngularMomentumErrorIsReportedAndWarned) {
  const TailTrajectory fast = sameMove(6, 0, -90, 2 * 90 / 5000.0, 0.25);  // peak 5000 deg/s
  const RunResult bad = simulateAnalytic(paperRobot(6, 0.1405), fast, {}, {}, {});
  ASSERT_TRUE(bad.summary.ok) << bad.summary.error;
  EXPECT_GT(bad.summary.extra.at("paper_spurious_turn_deg"), 100.0);
  EXPECT_LT(bad.summary.extra.at("paper_residual_spin_dps"), -500.0);
  EXPECT_TRUE(anyWarningContains(bad.summary, "angular-momentum error is large"));
  const RunResult fig7 = runFig7();
  EXPECT_LT(fig7.summary.extra.at("paper_spurious_turn_deg"), limits::kMaxPaperSpuriousTurnDeg);
  AnalyticSettings exact;
  exact.coupling = Coupling::kExact;
  const RunResult ex = simulateAnalytic(paperRobot(6, 0.1405), fast, exact, {}, {});
  EXPECT_EQ(ex.summary.extra.count("paper_spurious_turn_deg"), 0u);
  EXPECT_FALSE(anyWarningContains(ex.summary, "angular-momentum"));
}

// The residual spin is a quadrature of M_z,T / I_zz over the tail's motion. Independent of it: the
// paper-coupling run itself without friction, integrated to rel_tol 1e-13, ends spinning at exactly
// that rate. Seeded random split-cycle strokes (1-6 links, per-joint start times), and strokes whose
// loads oscillate within one segment (a 6-link tail whose joints each turn a full circle: the
// integrand turns 3 times a phase), which one 21-point pass cannot integrate to 1e-9.
TEST(Finding6dPaperCoupling, ResidualSpinIsTheFrictionlessRunsFinalRate) {
  int checked = 0;
  double worst = 0.0;
  auto check = [&](const RobotParams& robot, const TailTrajectory& traj, AnalyticSettings s, const std::string& what) {
    Effects e;
    e.friction = FrictionLaw::kNone;
    s.rel_tol = 1e-13;
    s.abs_tol = 1e-15;
    const RunResult r = simulateAnalytic(robot, traj, s, e, {});
    ASSERT_TRUE(r.summary.ok) << r.summary.error << ": " << what;
    const double quad = r.summary.extra.at("paper_residual_spin_dps"), sim = r.summary.extra.at("final_phidot_dps");
    const double err = std::abs(quad - sim) / std::max(std::abs(sim), 1e-2);  // 1e-11 deg/s near 0
    worst = std::max(worst, err);
    EXPECT_LT(err, 1e-9) << "quadrature " << quad << " deg/s, run " << sim << " deg/s: " << what;
    ++checked;
  };
  testing::RandomCases gen(4242u);
  for (int k = 0; k < 400 && checked < 150; ++k) {
    const testing::RandomCase c = gen.next();
    if (c.settings.coupling != Coupling::kPaper || c.settings.solver != AnalyticSolver::kAdaptive) continue;
    check(c.robot, c.trajectory, c.settings, testing::describe(c));
  }
  EXPECT_GE(checked, 100);
  for (double w_ss : {0.5, 0.2})
    for (double dT : {1.0, 3.0})
      check(paperRobot(6, 0.1405), testing::sameMove(6, 0, 360, dT, w_ss), {},
            "6 links, 360 deg per joint, dT " + std::to_string(dT) + " s, w_ss " + std::to_string(w_ss));
  std::printf("residual spin vs frictionless run: worst relative difference %.2e over %d strokes\n", worst, checked);
}

// 6e: timestep_s 1e-2 was 44 % off the default step's result, without a warning.
TEST(Finding6eCoarseStep, CoarseMujocoStepWarnsThroughTheTrackingError) {
  MujocoSettings coarse;
  coarse.timestep_s = 1e-2;
  const TailTrajectory t = sameMove(1, 0, -90, 0.25, 0.25);
  const RunResult r = simulateMujoco(paperRobot(1, 0.1405), t, coarse, {}, {});
  ASSERT_TRUE(r.summary.ok) << r.summary.error;
  EXPECT_GT(r.summary.extra.at("tracking_max_deg_j1"), limits::kMaxTrackingErrorDeg);
  EXPECT_TRUE(anyWarningContains(r.summary, "tail servo is off its reference"));
  const RunResult fine = simulateMujoco(paperRobot(1, 0.1405), t, {}, {}, {});
  EXPECT_FALSE(anyWarningContains(fine.summary, "tail servo"));
}

}  // namespace
}  // namespace tailsim
