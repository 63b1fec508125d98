// Foot-load distribution and friction moment arm (Eqs. 17-19, A1-A5).
#include <gtest/gtest.h>

#include <algorithm>

#include "models/planar/foot_loads.h"
#include "models/planar/system_loads.h"
#include "analytic_test_util.h"

using namespace tailsim;
using namespace tailsim::testing;

static void expectA1(const QuadrupedParams& q, const Vec2& p_QC, const FootLoads& f) {
  const double l = q.l_F_m, w = q.w_F_m;
  const double x = p_QC.x() - q.d_Q2C_m, y = p_QC.y();
  const auto& c = f.f_C;
  EXPECT_NEAR(c[0] + c[1] + c[2] + c[3], 1.0, 1e-12);
  EXPECT_NEAR((0.5 * l - x) * (c[0] + c[1]), (0.5 * l + x) * (c[2] + c[3]), 1e-12);
  EXPECT_NEAR((0.5 * w - y) * (c[0] + c[3]), (0.5 * w + y) * (c[1] + c[2]), 1e-12);
  for (double v : c) EXPECT_GE(v, 0.0);
}

TEST(FootLoads, SumToOneAndSatisfyA1OverTheSupportRectangle) {
  QuadrupedParams q;
  int clipped = 0;
  for (int i = -50; i <= 50; ++i)
    for (int j = -50; j <= 50; ++j) {
      // Includes the corners and edges (b up to the rectangle's corner, where the fallback acts).
      const Vec2 p(q.d_Q2C_m + 0.5 * q.l_F_m * i / 50.0, 0.5 * q.w_F_m * j / 50.0);
      const FootLoads f = footLoads(q, p);
      expectA1(q, p, f);
      clipped += f.clipped;
    }
  EXPECT_GT(clipped, 0);  // the b > w_F/(2 sqrt 2) fallback was exercised
}

TEST(FootLoads, CentredComLoadsFeetEqually) {
  QuadrupedParams q;
  const FootLoads f = footLoads(q, Vec2(q.d_Q2C_m, 0));
  for (double v : f.f_C) EXPECT_NEAR(v, 0.25, 1e-15);
  EXPECT_NEAR(f.L_F, std::hypot(0.15, 0.13), 1e-15);
}

TEST(FootLoads, ComOutsideSupportIsAnError) {
  QuadrupedParams q;
  EXPECT_THROW(footLoads(q, Vec2(q.d_Q2C_m + 0.151, 0)), TippingError);
  EXPECT_THROW(footLoads(q, Vec2(q.d_Q2C_m, -0.131)), TippingError);
  EXPECT_NO_THROW(footLoads(q, Vec2(q.d_Q2C_m + 0.15, 0.13)));  // on the corner: still standing
}

TEST(FootLoads, FrictionArmVariesLessThan3PercentFig10) {
  std::vector<double> lf;
  for (int d = 0; d <= 6; ++d)
    for (int th = -90; th <= 90; th += 5) {
      const RobotParams r = paperRobot(1, 0.025 * d);
      const SystemLoads s = systemLoads(r, {JointState{deg(th), 0, 0}});
      lf.push_back(footLoads(r.quadruped, s.p_QC).L_F);
    }
  std::vector<double> sorted = lf;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double median = sorted[sorted.size() / 2];
  double worst = 0;
  for (double v : lf) worst = std::max(worst, std::abs(v - median) / median);
  EXPECT_LT(worst, 0.03);
  RecordProperty("LF_max_rel_variation", std::to_string(worst));
  std::printf("L_F median %.5f m, max variation from median %.3f %%\n", median, 100 * worst);
}

TEST(FootLoads, ClosedFormEqualsEqA4AsPrinted) {
  // Inside the region where (A4) needs no clipping, compare with the literal (A3)-(A5).
  QuadrupedParams q;
  const double l = q.l_F_m, w = q.w_F_m;
  for (int i = -20; i <= 20; ++i)
    for (int j = -20; j <= 20; ++j) {
      const double xe = 0.5 * l * i / 40.0, ye = 0.5 * w * j / 40.0;  // b <= w_F / (2 sqrt 2)
      const double xi = std::atan2(ye, xe * w / l), b = std::hypot(xe * w / l, ye);
      const double B = b * std::sqrt(2.0) / (2 * w);
      const FootLoads f = footLoads(q, Vec2(q.d_Q2C_m + xe, ye));
      ASSERT_FALSE(f.clipped);
      for (int k = 0; k < 4; ++k) EXPECT_NEAR(f.f_C[k], 0.25 + B * std::sin(xi + M_PI / 4 + k * M_PI / 2), 1e-15);
    }
}
