// Split-cycle profiles (Eqs. 20-23) and the equal-peak-speed rule (Eq. 25).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "trajectory/split_cycle_profile.h"

using namespace tailsim;

TEST(SplitCycleProfile, MeetsEq22BoundaryConditions) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < 200; ++k) {
    SplitCycleParams p{(u(rng) - 0.5) * 3, (u(rng) - 0.5) * 6, 0.05 + u(rng), 0.02 + 0.96 * u(rng), u(rng)};
    SplitCycleProfile prof(p);
    const JointState a = prof.at(p.t0_s), b = prof.at(p.t0_s + p.dT_s);
    EXPECT_NEAR(a.theta, p.theta0_rad, 1e-12);
    EXPECT_NEAR(a.theta_dot, 0.0, 1e-12);
    EXPECT_NEAR(b.theta, p.theta0_rad + p.dtheta_rad, 1e-12);
    EXPECT_NEAR(b.theta_dot, 0.0, 1e-12);
    // Eq. (23): A Delta_a = B Delta_d.
    EXPECT_NEAR(prof.accelAmplitude() * p.w_ss, prof.decelAmplitude() * (1 - p.w_ss),
                1e-12 * std::abs(prof.accelAmplitude()));
  }
}

TEST(SplitCycleProfile, PeakSpeedAtSplitPoint) {
  SplitCycleParams p{0.3, -M_PI / 2, 0.25, 0.25, 0.1};
  SplitCycleProfile prof(p);
  const double t1 = p.t0_s + p.w_ss * p.dT_s;
  EXPECT_NEAR(prof.at(t1).theta_dot, 2 * p.dtheta_rad / p.dT_s, 1e-12);
  double vmax = 0, tmax = 0;
  for (int i = 0; i <= 100000; ++i) {
    const double t = p.t0_s + p.dT_s * i / 100000.0;
    const double v = std::abs(prof.at(t).theta_dot);
    if (v > vmax) { vmax = v; tmax = t; }
  }
  EXPECT_NEAR(vmax, 2 * std::abs(p.dtheta_rad) / p.dT_s, 1e-9);
  EXPECT_NEAR(tmax, t1, p.dT_s / 100000.0);
  // Sec. 4.5: theta(w_ss dT) = theta0 + w_ss dtheta.
  EXPECT_NEAR(prof.at(t1).theta, p.theta0_rad + p.w_ss * p.dtheta_rad, 1e-12);
}

TEST(SplitCycleProfile, DerivativesAreConsistent) {
  // theta_dot and theta_ddot are the derivatives of theta (central differences).
  SplitCycleProfile prof({0.2, -1.3, 0.3, 0.3, 0.05});
  const double h = 1e-6;
  for (double t = 0.06; t < 0.34; t += 0.0137) {
    const JointState s = prof.at(t);
    EXPECT_NEAR((prof.at(t + h).theta - prof.at(t - h).theta) / (2 * h), s.theta_dot, 1e-7);
    EXPECT_NEAR((prof.at(t + h).theta_dot - prof.at(t - h).theta_dot) / (2 * h), s.theta_ddot, 1e-5);
  }
}

TEST(SplitCycleProfile, RejectsBadParameters) {
  EXPECT_THROW(SplitCycleProfile({0, 1, 0.0, 0.25, 0}), std::invalid_argument);
  EXPECT_THROW(SplitCycleProfile({0, 1, 0.25, 0.0, 0}), std::invalid_argument);
  EXPECT_THROW(SplitCycleProfile({0, 1, 0.25, 1.0, 0}), std::invalid_argument);
  EXPECT_THROW(SplitCycleProfile({0, NAN, 0.25, 0.5, 0}), std::invalid_argument);
}

TEST(EqualPeakSpeedRule, MatchesPaperNotesNumbers) {
  const double dtheta_deg[] = {-180, -120, -90, -72, -60, -51.43};
  const double dT[] = {0.600, 0.400, 0.300, 0.240, 0.200, 0.171};
  for (int n = 1; n <= 6; ++n) {
    const SplitCycleParams p = equalPeakSpeedParams(n, 10.47, 0.25);
    EXPECT_NEAR(p.dtheta_rad * 180 / M_PI, dtheta_deg[n - 1], 0.005) << n;
    EXPECT_NEAR(p.dT_s, dT[n - 1], 0.0005) << n;
    EXPECT_NEAR(p.theta0_rad, -0.5 * p.dtheta_rad, 1e-15);  // sign fix: start at +180/(n+1) deg
    EXPECT_NEAR(std::abs(SplitCycleProfile(p).peakSpeed()), 10.47, 1e-12);
  }
}
