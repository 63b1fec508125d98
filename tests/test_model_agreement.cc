// The bridge between the paper's model and MuJoCo: with no friction, the exact planar
// coupling of the analytic model and the MuJoCo contact model must agree on phi(t); the paper's
// coupling (which drops the base-motion terms, paper-notes point 3) must not.
#include <gtest/gtest.h>

#include "analytic_test_util.h"
#include "models/mujoco/mujoco_simulation.h"

using namespace tailsim;
using namespace tailsim::testing;

namespace {
struct Fig6Case {
  int n;
  double dtheta_deg;
};

double maxAbsDiff(const std::vector<double>& a, const std::vector<double>& b) {
  double d = 0;
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) d = std::max(d, std::abs(a[i] - b[i]));
  return d;
}
}  // namespace

class Fig6Frictionless : public ::testing::TestWithParam<Fig6Case> {};

TEST_P(Fig6Frictionless, ExactCouplingAgreesWithMujocoPaperCouplingDoesNot) {
  const Fig6Case c = GetParam();
  const RobotParams robot = paperRobot(c.n, 0.1405);  // Sec. 4.2: d_Q2B = 140.5 mm
  const TailTrajectory tr = sameMove(c.n, 0, c.dtheta_deg, 0.25, 0.25);
  Effects e;
  e.friction = FrictionLaw::kNone;
  OutputSettings o;
  o.duration_s = 0.3;
  AnalyticSettings exact;
  exact.coupling = Coupling::kExact;
  const RunResult a = simulateAnalytic(robot, tr, exact, e, o);
  const RunResult p = simulateAnalytic(robot, tr, {}, e, o);
  const RunResult m = simulateMujoco(robot, tr, {}, e, o);
  ASSERT_TRUE(a.summary.ok && p.summary.ok);
  ASSERT_TRUE(m.summary.ok) << m.summary.error;
  ASSERT_EQ(a.series.numRows(), m.series.numRows());  // same output grid, row for row
  const double phi_net = std::abs(a.summary.phi_net_deg);
  const double exact_vs_mj = maxAbsDiff(a.series.values("phi_deg"), m.series.values("phi_deg"));
  const double paper_vs_mj = maxAbsDiff(p.series.values("phi_deg"), m.series.values("phi_deg"));
  std::printf("n=%d, mu=0: phi_net exact %.4f, MuJoCo %.4f, paper %.4f deg; max|phi exact - MuJoCo| = %.4f deg "
              "(%.3f %% of phi_net), max|phi paper - MuJoCo| = %.3f deg (%.1f %%)\n",
              c.n, a.summary.phi_net_deg, m.summary.phi_net_deg, p.summary.phi_net_deg, exact_vs_mj,
              100 * exact_vs_mj / phi_net, paper_vs_mj, 100 * paper_vs_mj / phi_net);
  EXPECT_LT(exact_vs_mj, 0.01 * phi_net);
  EXPECT_GT(paper_vs_mj, 0.1 * phi_net);
}

INSTANTIATE_TEST_SUITE_P(Fig6, Fig6Frictionless, ::testing::Values(Fig6Case{1, -90}, Fig6Case{6, -30}),
                         [](const auto& info) { return "n" + std::to_string(info.param.n); });
