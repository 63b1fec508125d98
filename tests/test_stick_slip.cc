// The friction and stick/slip event logic of the analytic model on its own (stick_slip.h):
// sliding friction loads, which DOF switches, and locating a switch inside a step.
#include "models/planar/stick_slip.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace tailsim;

namespace {
FrictionParams paperFriction() { return FrictionParams{}; }  // mu_s 0.25, mu_d 0.30
}  // namespace

TEST(StickSlip, BreakawayUsesTheLargerCoefficient) {
  FrictionParams f = paperFriction();
  EXPECT_EQ(breakawayCoefficient(f), 0.30);
  f.mu_s = 0.5;
  EXPECT_EQ(breakawayCoefficient(f), 0.5);
}

TEST(StickSlip, StictionSlidingMomentOpposesTheSlipDirectionAtMuD) {
  const SlidingFriction f =
      slidingFriction(FrictionLaw::kStiction, paperFriction(), 100.0, 0.2, +1.0, 3.0, Vec2::Zero(), 1e-4);
  EXPECT_DOUBLE_EQ(f.MzF, -0.30 * 100.0 * 0.2);  // Eq. (16): -mu_d W L_F
  EXPECT_EQ(f.FF, Vec2::Zero());                 // not moving: no force
  // The mode's direction, not the rate's sign: a trial state past zero keeps the same moment.
  EXPECT_DOUBLE_EQ(slidingFriction(FrictionLaw::kStiction, paperFriction(), 100.0, 0.2, +1.0, -1e-9, Vec2::Zero(), 0).MzF,
                   f.MzF);
}

TEST(StickSlip, StictionSlidingForceIsCoulombAboveVregAndLinearBelow) {
  const double W = 50.0, v_reg = 1e-3;
  const SlidingFriction fast =
      slidingFriction(FrictionLaw::kStiction, paperFriction(), W, 0.1, 0.0, 0.0, Vec2(0.3, -0.4), v_reg);
  EXPECT_NEAR(fast.FF.norm(), 0.30 * W, 1e-12);               // Eq. (15): mu_d W
  EXPECT_NEAR(fast.FF.dot(Vec2(0.3, -0.4)), -0.30 * W * 0.5, 1e-12);  // against v
  const SlidingFriction slow =
      slidingFriction(FrictionLaw::kStiction, paperFriction(), W, 0.1, 0.0, 0.0, Vec2(0.5e-3, 0.0), v_reg);
  EXPECT_NEAR(slow.FF.x(), -0.30 * W * 0.5, 1e-12);  // regularized: half the speed, half the force
}

TEST(StickSlip, AdamsLawFollowsTheSlipSpeed) {
  const FrictionParams fp = paperFriction();
  // Far above phidot_d and v_d: mu_d; at zero speed: no friction.
  const SlidingFriction f = slidingFriction(FrictionLaw::kContinuous, fp, 10.0, 0.2, 0.0, -2.0, Vec2(0, 2.0), 0);
  EXPECT_NEAR(f.MzF, +0.30 * 10.0 * 0.2, 1e-12);
  EXPECT_NEAR(f.FF.y(), -0.30 * 10.0, 1e-12);
  const SlidingFriction z = slidingFriction(FrictionLaw::kContinuous, fp, 10.0, 0.2, 1.0, 0.0, Vec2::Zero(), 0);
  EXPECT_EQ(z.MzF, 0.0);
  EXPECT_EQ(z.FF, Vec2::Zero());
  const SlidingFriction none = slidingFriction(FrictionLaw::kNone, fp, 10.0, 0.2, 1.0, 1.0, Vec2(1, 0), 0);
  EXPECT_EQ(none.MzF, 0.0);
  EXPECT_EQ(none.FF, Vec2::Zero());
}

TEST(StickSlip, DofToSwitchPrefersBreakawayThenStopOfTranslationThenRotation) {
  Modes stuck;
  stuck.stuck[kRot] = stuck.stuck[kTrans] = true;
  EXPECT_EQ(dofToSwitch(stuck, {1.0, 1.0}, true), -1);
  EXPECT_EQ(dofToSwitch(stuck, {0.0, 1.0}, true), kRot);    // at the limit breaks away
  EXPECT_EQ(dofToSwitch(stuck, {-1.0, -1.0}, true), kTrans);
  Modes sliding;
  EXPECT_EQ(dofToSwitch(sliding, {0.0, 0.0}, true), -1);    // a sliding margin must go below zero
  EXPECT_EQ(dofToSwitch(sliding, {-1.0, -1.0}, true), kTrans);
  EXPECT_EQ(dofToSwitch(sliding, {-1.0, -1.0}, false), kRot);  // translation locked: never switched
  Modes mixed;
  mixed.stuck[kTrans] = true;
  EXPECT_EQ(dofToSwitch(mixed, {-1.0, 0.5}, true), kRot);
}

TEST(StickSlip, IllinoisLocatesTheCrossingFromThePastSide) {
  int calls = 0;
  auto g = [&](double t) { ++calls; return std::cos(t); };  // crosses at pi/2
  const double t = illinois(g, 1.0, 2.0, g(1.0), g(2.0), 1e-12);
  EXPECT_GE(t, M_PI / 2);
  EXPECT_NEAR(t, M_PI / 2, 1e-12);
  EXPECT_LT(calls, 40);
  // Already at the switch at a: a + tol.
  EXPECT_DOUBLE_EQ(illinois(g, 0.0, 1.0, 0.0, -1.0, 1e-9), 1e-9);
}

TEST(StickSlip, GoldenMinFindsTheMinimum) {
  const auto [t, g] = goldenMin([](double x) { return (x - 0.3) * (x - 0.3) + 0.1; }, 0.0, 1.0, 1e-9);
  EXPECT_NEAR(t, 0.3, 1e-6);
  EXPECT_NEAR(g, 0.1, 1e-12);
}

TEST(StickSlip, FindSwitchReturnsTheEarlierOfTwoCrossingsInOneInterval) {
  Modes m;
  m.stuck[kRot] = m.stuck[kTrans] = true;
  // Both margins cross inside the same sample interval [0, 1]: translation first (0.4 < 0.6).
  auto gAt = [](double t) { return Margins{0.6 - t, 0.4 - t}; };
  const Found f = findSwitch(gAt, m, 0.0, 1.0, 10.0, 1e-12);
  ASSERT_TRUE(f.hit);
  EXPECT_EQ(f.which, kTrans);
  EXPECT_NEAR(f.t, 0.4, 1e-12);
  // No crossing: no hit.
  EXPECT_FALSE(findSwitch([](double t) { return Margins{1.0 + t, 2.0}; }, m, 0.0, 1.0, 0.1, 1e-12).hit);
}

TEST(StickSlip, FindSwitchCatchesADipBetweenSamples) {
  Modes m;
  m.stuck[kRot] = true;
  // A stuck margin that dips below zero only near t = 0.52, between samples at 0.5 and 0.6 (h 0.1).
  auto gAt = [](double t) { return Margins{std::abs(t - 0.52) * 10.0 - 0.05, 1.0}; };
  const Found f = findSwitch(gAt, m, 0.0, 1.0, 0.1, 1e-12);
  ASSERT_TRUE(f.hit);
  EXPECT_EQ(f.which, kRot);
  EXPECT_NEAR(f.t, 0.515, 1e-9);  // the first zero of the dip
}

TEST(StickSlip, FindSwitchReportsASwitchAlreadyPastAtTheStart) {
  Modes sliding;
  const Found f = findSwitch([](double) { return Margins{-1e-3, 1.0}; }, sliding, 2.0, 3.0, 0.1, 1e-12);
  ASSERT_TRUE(f.hit);
  EXPECT_EQ(f.t, 2.0);
  EXPECT_EQ(f.which, kRot);
}

// A stuck margin's narrow dip (below zero for about 1 ms) whose lowest sample is the first scan's
// last one (t = 1.02) and so the second scan's first: only a scan that starts from the first one's
// last two samples (ScanEnd, `across`) sees both of its neighbours. The dip's first zero lies after
// the boundary (centre 1.025) or before it (centre 1.018: the switch is found in the first scan's
// interval, which its caller's deferred rows and kept dense output allow).
TEST(StickSlip, FindSwitchCatchesADipAcrossTwoScans) {
  Modes m;
  m.stuck[kRot] = m.stuck[kTrans] = true;
  for (const double centre : {1.025, 1.018}) {
    auto gAt = [centre](double t) {
      const double u = (t - centre) / 0.005;
      return Margins{1.0 - 1.01 * std::exp(-u * u), 1.0};
    };
    ScanEnd first;
    ASSERT_FALSE(findSwitch(gAt, m, 0.0, 1.02, 0.1, 1e-12, nullptr, &first).hit);
    EXPECT_NEAR(first.t_before, 1.02 * 10 / 11, 1e-15);
    EXPECT_EQ(first.g_end[kRot], gAt(1.02)[kRot]);
    ASSERT_TRUE(dipMayCross(m, first)) << centre;  // the margin still falls at the boundary
    // Without the first scan's samples the dip is missed (the limit before the fix).
    EXPECT_FALSE(findSwitch(gAt, m, 1.02, 2.0, 0.1, 1e-12, &first, nullptr, false).hit);
    const Found f = findSwitch(gAt, m, 1.02, 2.0, 0.1, 1e-12, &first, nullptr, true);
    ASSERT_TRUE(f.hit) << centre;
    EXPECT_EQ(f.which, kRot);
    const double first_zero = centre - 0.005 * std::sqrt(std::log(1.01));  // g = 0 on the way down
    EXPECT_NEAR(f.t, first_zero, 1e-9) << centre;
  }
}

// A slide that has just begun (margin exactly 0) rises and falls back below zero inside the first
// sample interval: its stop is where the margin falls through zero (t = 0.01), not the start.
// Before the fix the switch was put at the start, the DOF re-stuck, broke away again at once, and
// the run crept forward by the event tolerance per step until its step budget ran out.
TEST(StickSlip, FindSwitchLocatesTheStopOfASlideThatJustBegan) {
  Modes sliding;
  sliding.stuck[kTrans] = true;
  auto gAt = [](double t) { return Margins{t * (0.01 - t), 1.0}; };
  const Found f = findSwitch(gAt, sliding, 0.0, 1.0, 0.1, 1e-12);
  ASSERT_TRUE(f.hit);
  EXPECT_EQ(f.which, kRot);
  EXPECT_NEAR(f.t, 0.01, 1e-9);
  // A margin that never rises still stops at the start.
  const Found g = findSwitch([](double t) { return Margins{-t, 1.0}; }, sliding, 0.0, 1.0, 0.1, 1e-12);
  ASSERT_TRUE(g.hit);
  EXPECT_NEAR(g.t, 0.0, 1e-12);
}
