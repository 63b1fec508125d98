// Effect selection: a scene that leaves an effect out neither computes it nor feels it.
// The MJCF side (disable flags, omitted floor, joints) is covered in test_mujoco_model.cc.
#include <gtest/gtest.h>

#include <cmath>

#include "analytic_test_util.h"
#include "models/mujoco/mujoco_simulation.h"

using namespace tailsim;
using namespace tailsim::testing;

namespace {
bool allNaN(const std::vector<double>& v) {
  for (double x : v)
    if (!std::isnan(x)) return false;
  return true;
}
bool allZero(const std::vector<double>& v) {
  for (double x : v)
    if (x != 0.0) return false;
  return true;
}
}  // namespace

TEST(Effects, NoFrictionSkipsFootLoadsAndFrictionEverywhere) {
  Effects e;
  e.friction = FrictionLaw::kNone;
  const RunResult r = runFig7({}, e);
  ASSERT_TRUE(r.summary.ok);
  EXPECT_TRUE(allNaN(r.series.values("LF_m")));  // the foot-load model was not evaluated
  EXPECT_TRUE(allZero(r.series.values("MzF_Nm")));
  EXPECT_TRUE(allZero(r.series.values("FFx_N")));
  EXPECT_EQ(r.summary.stick_slip_events, 0);
  // No gravity means no weight on the feet, hence no friction: the frictionless result.
  Effects g;
  g.gravity = false;
  const RunResult rg = runFig7({}, g);
  EXPECT_EQ(rg.summary.phi_net_deg, r.summary.phi_net_deg);
}

TEST(Effects, LockedTranslationKeepsXYAtZero) {
  Effects e;
  e.translation = false;
  const RunResult a = runFig7({}, e);
  EXPECT_TRUE(allZero(a.series.values("x_m")));
  EXPECT_TRUE(allZero(a.series.values("y_m")));
  // The paper's rotation does not depend on translation (Eq. 13 is body-frame invariant).
  EXPECT_NEAR(a.summary.phi_net_deg, runFig7().summary.phi_net_deg, 1e-5);
  const RunResult m = simulateMujoco(paperRobot(1), sameMove(1, 0, -90, 0.25, 0.25), {}, e, {});
  ASSERT_TRUE(m.summary.ok) << m.summary.error;
  for (const char* c : {"x_m", "y_m"})
    for (double v : m.series.values(c)) EXPECT_NEAR(v, 0.0, 1e-12) << c;
}

TEST(Effects, ConstantFootLoadsFreezeTheFrictionArm) {
  Effects e;
  e.foot_loads = FootLoadModel::kConstant;
  const RunResult r = runFig7({}, e);
  const auto& lf = r.series.values("LF_m");
  for (double v : lf) EXPECT_EQ(v, lf.front());
  // Fig. 10's < 3 % variation of L_F: the frozen arm changes phi_net by a few percent at most.
  EXPECT_NEAR(r.summary.phi_net_deg, runFig7().summary.phi_net_deg, 0.05 * runFig7().summary.phi_net_deg);
}

TEST(Effects, NoLoadDecompositionSkipsTheExtraRecursions) {
  Effects e;
  e.load_decomposition = false;
  const RunResult r = runFig7({}, e);
  EXPECT_TRUE(allNaN(r.series.values("MzT_acc_Nm")));
  EXPECT_TRUE(allNaN(r.series.values("MzT_cen_Nm")));
  EXPECT_EQ(r.summary.phi_net_deg, runFig7().summary.phi_net_deg);  // the dynamics never used them
}

TEST(Effects, FreeFloatingMujocoSceneHasNoContacts) {
  Effects e;
  e.friction = FrictionLaw::kNone;
  e.gravity = false;
  e.ground_contact = false;
  OutputSettings o;
  o.duration_s = 0.3;
  const RunResult m = simulateMujoco(paperRobot(1, 0.1405), sameMove(1, 0, -90, 0.25, 0.25), {}, e, o);
  ASSERT_TRUE(m.summary.ok) << m.summary.error;
  for (int k = 1; k <= 4; ++k)
    EXPECT_TRUE(allZero(m.series.values("foot" + std::to_string(k) + "_Fn_N"))) << k;
  // Free-floating in the plane: the exact analytic coupling without friction is the same system.
  AnalyticSettings exact;
  exact.coupling = Coupling::kExact;
  const RunResult a = simulateAnalytic(paperRobot(1, 0.1405), sameMove(1, 0, -90, 0.25, 0.25), exact, e, o);
  EXPECT_NEAR(m.summary.phi_net_deg, a.summary.phi_net_deg, 0.01 * std::abs(a.summary.phi_net_deg));
}
