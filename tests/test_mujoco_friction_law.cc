// The ADAMS friction law of Fig. 4 (paper-notes point 6), checked against closed forms.
#include <gtest/gtest.h>

#include <cmath>

#include "robot/friction_law.h"

using namespace tailsim;

TEST(AdamsFrictionLaw, StepIsTheCubic) {
  EXPECT_DOUBLE_EQ(adamsStep(-1.0, 0.0, 2.0, 1.0, 5.0), 2.0);
  EXPECT_DOUBLE_EQ(adamsStep(3.0, 0.0, 2.0, 1.0, 5.0), 5.0);
  EXPECT_DOUBLE_EQ(adamsStep(0.5, 0.0, 2.0, 1.0, 5.0), 3.5);           // midpoint
  EXPECT_NEAR(adamsStep(0.25, 0.0, 2.0, 1.0, 5.0), 2.0 + 3.0 * 0.0625 * 2.5, 1e-15);
}

TEST(AdamsFrictionLaw, ShapeOfFig4) {
  const double vs = 0.05, vd = 0.5, ms = 0.25, md = 0.30;
  EXPECT_EQ(adamsFrictionCoefficient(0.0, vs, vd, ms, md), 0.0);
  EXPECT_NEAR(adamsFrictionCoefficient(vs, vs, vd, ms, md), ms, 1e-15);
  EXPECT_NEAR(adamsFrictionCoefficient(vd, vs, vd, ms, md), md, 1e-15);
  EXPECT_NEAR(adamsFrictionCoefficient(7.0, vs, vd, ms, md), md, 1e-15);
  // Half step: upper half of STEP(v, -vs, -ms, vs, ms); at v = vs/2, d = 3/4: ms (2 * 27/32 - 1).
  EXPECT_NEAR(adamsFrictionCoefficient(0.5 * vs, vs, vd, ms, md), ms * (2.0 * 27.0 / 32.0 - 1.0), 1e-15);
  // Even in the slip velocity, continuous, C1 at vs (zero slope from both sides) and at vd.
  EXPECT_EQ(adamsFrictionCoefficient(-0.2, vs, vd, ms, md), adamsFrictionCoefficient(0.2, vs, vd, ms, md));
  const double e = 1e-7;
  for (double v : {vs, vd}) {
    const double left = (adamsFrictionCoefficient(v, vs, vd, ms, md) - adamsFrictionCoefficient(v - e, vs, vd, ms, md)) / e;
    const double right = (adamsFrictionCoefficient(v + e, vs, vd, ms, md) - adamsFrictionCoefficient(v, vs, vd, ms, md)) / e;
    EXPECT_NEAR(left, 0.0, 1e-4);  // FD error ~ f'' * e / 2 = 1.5e-5
    EXPECT_NEAR(right, 0.0, 1e-4);
  }
  // Slope at 0+: d/dv of the cubic at its midpoint = 1.5 * (2 ms) / (2 vs).
  EXPECT_NEAR(adamsFrictionCoefficient(e, vs, vd, ms, md) / e, 1.5 * ms / vs, 1e-4);
  // Monotone between the printed values (mu_s < mu_d): no overshoot.
  double prev = 0.0;
  for (int i = 1; i <= 10000; ++i) {
    const double mu = adamsFrictionCoefficient(i * 1e-4, vs, vd, ms, md);
    EXPECT_GE(mu, prev - 1e-15);
    prev = mu;
  }
}
