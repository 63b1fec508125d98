// The per-foot friction model (docs/per-foot-model.md) against closed forms and
// against the exact-coupling analytic model.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "models/perfoot/per_foot_model.h"
#include "analytic_test_util.h"
#include "random_cases.h"

using namespace tailsim;
using namespace tailsim::testing;

namespace {

constexpr double kG = 9.81;

// Feet of the paper's quadruped relative to a system COM at p_QC (in Q), discs mu N_i from the
// Appendix distribution (the same code as L_F).
FootDiscs paperDiscs(const Vec2& p_QC, double mu, double weight, double* L_F = nullptr) {
  const FootLoads fl = footLoads(QuadrupedParams{}, p_QC);
  FootDiscs d;
  for (int i = 0; i < 4; ++i) {
    d.r[i] = fl.p_F[i];
    d.c[i] = mu * weight * fl.f_C[i];
  }
  if (L_F) *L_F = fl.L_F;
  return d;
}

// Brute force min over instantaneous centres p of sum c_i |r_i - p| (grid, then finer grids).
double bruteForceWeberMin(const FootDiscs& d) {
  Vec2 best = Vec2::Zero();
  double span = 0.4, bestD = 1e300;
  for (int level = 0; level < 12; ++level) {
    const Vec2 centre = best;
    for (int i = -40; i <= 40; ++i)
      for (int j = -40; j <= 40; ++j) {
        const Vec2 p = centre + Vec2(i, j) * (span / 40);
        double D = 0;
        for (int k = 0; k < 4; ++k) D += d.c[k] * (d.r[k] - p).norm();
        if (D < bestD) bestD = D, best = p;
      }
    span /= 8;
  }
  return bestD;
}

PerFootSettings slideSettings(double vx) {
  PerFootSettings s;
  s.initial_velocity = {vx, 0.0, 0.0};
  return s;
}

}  // namespace

// Symmetric loads (COM on the foot centroid): a pure moment about the COM breaks away exactly at
// sum mu N_i r_i, which is the paper's mu m g L_F there; the breakaway twist is a pure rotation.
TEST(PerFootLimitSurface, PureMomentSymmetricBreaksAtSumMuNr) {
  const double W = 10.858 * kG, mu = 0.3;
  double L_F = 0;
  const FootDiscs d = paperDiscs(Vec2(QuadrupedParams{}.d_Q2C_m, 0.0), mu, W, &L_F);
  double sum = 0;
  for (int i = 0; i < 4; ++i) sum += d.c[i] * d.r[i].norm();
  EXPECT_NEAR(sum, mu * W * L_F, 1e-12 * sum);
  const LoadFactor lf = loadFactor(d, {Vec2::Zero(), sum});
  EXPECT_NEAR(lf.s, 1.0, 1e-12);
  EXPECT_NEAR(lf.direction.v.norm(), 0.0, 1e-9);
  EXPECT_GT(lf.direction.w, 0.0);
  EXPECT_NEAR(loadFactor(d, {Vec2::Zero(), -0.5 * sum}).s, 0.5, 1e-12);
}

// Unequal loads (tail swung aside: COM off the centroid): a pure moment about the COM breaks
// away at min_p sum mu N_i |r_i - p| (turning about the weighted geometric median, not the COM),
// below the paper's mu m g L_F = sum mu N_i |r_i|. Checked against a brute-force grid.
TEST(PerFootLimitSurface, PureMomentOffsetComBreaksBelowPaperArm) {
  const double W = 10.858 * kG, mu = 0.3;
  for (const Vec2& p_QC : {Vec2(-0.06, 0.05), Vec2(0.02, -0.09), Vec2(-0.1, 0.0)}) {
    double L_F = 0;
    const FootDiscs d = paperDiscs(p_QC, mu, W, &L_F);
    const double M_break = 1.0 / loadFactor(d, {Vec2::Zero(), 1.0}).s;
    const double brute = bruteForceWeberMin(d);
    EXPECT_NEAR(M_break, brute, 1e-9 * brute) << p_QC.transpose();
    EXPECT_LE(M_break, mu * W * L_F * (1 + 1e-12));
    if (p_QC.y() != 0) {
      EXPECT_LT(M_break, 0.999 * mu * W * L_F) << "paper arm " << L_F << " m";
    }
  }
}

// A pure force at the COM breaks away at mu m g in every direction, for any Appendix loads (their
// weighted centroid is the COM), with a pure translation.
TEST(PerFootLimitSurface, PureForceBreaksAtMuMg) {
  const double W = 10.858 * kG, mu = 0.3;
  for (const Vec2& p_QC : {Vec2(-0.0155, 0.0), Vec2(-0.06, 0.05), Vec2(0.03, -0.08)}) {
    const FootDiscs d = paperDiscs(p_QC, mu, W);
    for (int k = 0; k < 8; ++k) {
      const double a = k * M_PI / 4 + 0.1;
      const LoadFactor lf = loadFactor(d, {mu * W * Vec2(std::cos(a), std::sin(a)), 0.0});
      EXPECT_NEAR(lf.s, 1.0, 1e-12);
      EXPECT_NEAR(lf.direction.w, 0.0, 1e-9);
    }
  }
}

// The paper holds a moment and a force independently (each below its own limit); four discs do
// not: 0.7 of each breaks away (0.6 of each is still held), with a certificate twist W . xi > h(xi).
TEST(PerFootLimitSurface, CombinedLoadThePaperHoldsBreaksAway) {
  const double W = 10.858 * kG, mu = 0.3;
  double L_F = 0;
  const FootDiscs d = paperDiscs(Vec2(-0.0155, 0.0), mu, W, &L_F);
  EXPECT_LT(loadFactor(d, {Vec2(0.0, 0.6 * mu * W), 0.6 * mu * W * L_F}).s, 1.0);
  const Wrench2 w{Vec2(0.0, 0.7 * mu * W), 0.7 * mu * W * L_F};
  const LoadFactor lf = loadFactor(d, w);
  EXPECT_GT(lf.s, 1.0);
  const double power = w.F.dot(lf.direction.v) + w.M * lf.direction.w;
  EXPECT_NEAR(power / limitSupport(d, lf.direction), lf.s, 1e-12);
}

// Every maximum-dissipation wrench lies on the surface (s = 1) with its own twist as the
// breakaway direction, and every set of forces inside the discs gives s <= 1 (seeded, random).
TEST(PerFootLimitSurface, SurfaceAndInsideRandom) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1), pos(0.1, 1);
  for (int n = 0; n < 2000; ++n) {
    const Vec2 p_QC(-0.0155 + 0.12 * u(rng), 0.1 * u(rng));
    FootDiscs d = paperDiscs(p_QC, 0.3, 100.0);
    const Twist2 xi{Vec2(u(rng), u(rng)), 5 * u(rng)};
    const Wrench2 w = maxDissipationWrench(d, xi);
    const LoadFactor lf = loadFactor(d, w);
    ASSERT_NEAR(lf.s, 1.0, 1e-9) << n;
    // Direction: power at the returned twist equals h there (it is a maximizer).
    ASSERT_NEAR(w.F.dot(lf.direction.v) + w.M * lf.direction.w, limitSupport(d, lf.direction),
                1e-8 * limitSupport(d, lf.direction)) << n;
    Wrench2 inside;
    for (int i = 0; i < 4; ++i) {
      const double a = M_PI * u(rng);
      const Vec2 f = pos(rng) * d.c[i] * Vec2(std::cos(a), std::sin(a));
      inside.F += f;
      inside.M += cross2(d.r[i], f);
    }
    ASSERT_LE(loadFactor(d, inside).s, 1.0 + 1e-12) << n;
    // The held distribution reproduces the wrench.
    const auto Fi = heldFootForces(d, inside);
    Wrench2 back;
    for (int i = 0; i < 4; ++i) back.F += Fi[i], back.M += cross2(d.r[i], Fi[i]);
    ASSERT_NEAR((back.F - inside.F).norm(), 0.0, 1e-9);
    ASSERT_NEAR(back.M, inside.M, 1e-9);
  }
}

// mu = 0: no friction at any foot, so the model is the exact-coupling analytic model.
TEST(PerFootModel, ZeroFrictionEqualsExactCouplingAnalytic) {
  for (int n : {1, 6}) {
    RobotParams r = paperRobot(n, 0.1405);
    r.friction.mu_s = r.friction.mu_d = 0.0;
    const TailTrajectory tr = sameMove(n, 0, n == 1 ? -90 : -30, 0.25, 0.25);
    AnalyticSettings as;
    as.coupling = Coupling::kExact;
    const RunResult a = simulateAnalytic(r, tr, as, {}, {});
    const RunResult p = simulatePerFoot(r, tr, {}, {}, {});
    ASSERT_TRUE(a.summary.ok && p.summary.ok) << p.summary.error;
    EXPECT_NEAR(p.summary.phi_net_deg, a.summary.phi_net_deg, 1e-6) << n;
    EXPECT_NEAR(p.summary.extra.at("final_x_m"), a.summary.extra.at("final_x_m"), 1e-8);
    EXPECT_NEAR(p.summary.extra.at("final_y_m"), a.summary.extra.at("final_y_m"), 1e-8);
    const auto& pa = a.series.values("phi_deg");
    const auto& pp = p.series.values("phi_deg");
    ASSERT_EQ(pa.size(), pp.size());
    for (size_t k = 0; k < pa.size(); ++k) ASSERT_NEAR(pp[k], pa[k], 1e-6) << k;
  }
}

// A body sliding in pure translation decelerates at mu_d g and stops after v0^2 / (2 mu_d g),
// at t = v0 / (mu_d g), without turning (the Appendix loads' centroid is the COM).
TEST(PerFootModel, SlidingBodyDeceleratesAtMuG) {
  const RobotParams r = paperRobot(1);
  const TailTrajectory tr = sameMove(1, 0, 0, 0.25, 0.25);  // tail held straight
  const double v0 = 0.5, a = r.friction.mu_d * kG;
  const RunResult p = simulatePerFoot(r, tr, slideSettings(v0), {}, {});
  ASSERT_TRUE(p.summary.ok) << p.summary.error;
  EXPECT_NEAR(p.summary.extra.at("final_x_m"), v0 * v0 / (2 * a), 1e-6);
  EXPECT_NEAR(p.summary.t_stop_s, v0 / a, 1e-4);
  EXPECT_NEAR(p.summary.phi_net_deg, 0.0, 1e-9);
  const auto& x = p.series.values("x_m");
  const auto& t = p.series.values("t_s");
  for (size_t k = 0; k < t.size() && t[k] < 0.15; ++k) ASSERT_NEAR(x[k], v0 * t[k] - 0.5 * a * t[k] * t[k], 1e-7) << t[k];
  // Each foot carries mu_d N_i against the motion.
  const auto& F1 = p.series.values("F1x_N");
  const auto& N1 = p.series.values("N1_N");
  EXPECT_NEAR(F1[50], -r.friction.mu_d * N1[50], 1e-9);
}

// Prescribed normal loads (the diagnostic input of bench_gap_attribution): equal loads summing to
// twice the weight until t = 0.05 s, then to the weight, ramped linearly over 0.05-0.06 s. The
// slide then decelerates at 2 mu_d g, then mu_d g (the trapezoid between the two given samples),
// and each foot carries its prescribed load.
TEST(PerFootModel, PrescribedNormalLoadsDriveTheSlide) {
  const RobotParams r = paperRobot(1);
  const double W = r.systemMass() * r.gravity_mps2, mu = r.friction.mu_d, v0 = 0.5;
  PrescribedNormalLoads L;
  L.t_s = {0.0, 0.05, 0.06};
  L.N = {{W / 2, W / 2, W / 2, W / 2}, {W / 2, W / 2, W / 2, W / 2}, {W / 4, W / 4, W / 4, W / 4}};
  const RunResult p = simulatePerFoot(r, sameMove(1, 0, 0, 0.25, 0.25), slideSettings(v0), {}, {}, L);
  ASSERT_TRUE(p.summary.ok) << p.summary.error;
  const double a2 = 2 * mu * kG, a1 = mu * kG;
  const double v_ramp_end = v0 - a2 * 0.05 - 0.5 * (a2 + a1) * 0.01;  // speed at t = 0.06 s
  const auto& t = p.series.values("t_s");
  const auto& x = p.series.values("x_m");
  const auto& N3 = p.series.values("N3_N");
  for (size_t k = 0; k < t.size() && t[k] <= 0.05 + 1e-12; ++k) {
    ASSERT_NEAR(x[k], v0 * t[k] - 0.5 * a2 * t[k] * t[k], 1e-7) << t[k];
    ASSERT_NEAR(N3[k], W / 2, 1e-9) << t[k];
  }
  EXPECT_NEAR(N3[100], W / 4, 1e-9);  // t = 0.1 s: held at the last sample
  EXPECT_NEAR(p.summary.t_stop_s, 0.06 + v_ramp_end / a1, 1e-4);
  EXPECT_NEAR(p.summary.phi_net_deg, 0.0, 1e-9);
  // The input is checked: times must ascend.
  L.t_s = {0.0, 0.05, 0.05};
  EXPECT_THROW(simulatePerFoot(r, sameMove(1, 0, 0, 0.25, 0.25), slideSettings(v0), {}, {}, L), std::invalid_argument);
}

// The ADAMS law per foot: above v_d the coefficient is mu_d, so a fast slide decelerates at
// mu_d g until v_d; mu(0) = 0, so it never sticks.
TEST(PerFootModel, AdamsLawSlideDeceleratesAtMuDAboveVd) {
  const RobotParams r = paperRobot(1);
  Effects e;
  e.friction = FrictionLaw::kContinuous;
  const double v0 = 1.5, a = r.friction.mu_d * kG;  // reaches v_d = 0.5 m/s at t = 0.34 s
  const RunResult p = simulatePerFoot(r, sameMove(1, 0, 0, 0.25, 0.25), slideSettings(v0), e, {});
  ASSERT_TRUE(p.summary.ok) << p.summary.error;
  const auto& x = p.series.values("x_m");
  const auto& t = p.series.values("t_s");
  for (size_t k = 0; k < t.size() && t[k] < 0.33; ++k) ASSERT_NEAR(x[k], v0 * t[k] - 0.5 * a * t[k] * t[k], 1e-7);
  EXPECT_TRUE(std::isnan(p.series.values("rot_state")[0]));
}

// Load transfer: friction at the ground, h below the COM, moves the centre of pressure forward by
// h mu_d g / g while braking: the front pair carries h mu_d / l_F of the weight more.
TEST(PerFootModel, LoadTransferShiftsLoadToTheFrontWhileBraking) {
  const RobotParams r = paperRobot(1);
  const TailTrajectory tr = sameMove(1, 0, 0, 0.25, 0.25);
  PerFootSettings qs = slideSettings(0.5), lt = qs;
  lt.normal_loads = NormalLoadModel::kLoadTransfer;
  EXPECT_EQ(r.quadruped.com_height_m, 0.15);  // the robot's COM height (default)
  const RunResult a = simulatePerFoot(r, tr, qs, {}, {});
  const RunResult b = simulatePerFoot(r, tr, lt, {}, {});
  ASSERT_TRUE(a.summary.ok && b.summary.ok) << b.summary.error;
  const double W = r.systemMass() * kG;
  const size_t k = 50;  // t = 0.05 s, sliding
  const double front_a = a.series.values("N1_N")[k] + a.series.values("N2_N")[k];
  const double front_b = b.series.values("N1_N")[k] + b.series.values("N2_N")[k];
  EXPECT_NEAR(front_b - front_a, W * 0.15 * r.friction.mu_d / r.quadruped.l_F_m, 1e-9 * W);
  // The summed friction is still mu_d m g: the slide is the same.
  EXPECT_NEAR(b.summary.extra.at("final_x_m"), a.summary.extra.at("final_x_m"), 1e-9);
}

// Mirror symmetry: theta0 and dtheta negated mirror the run: phi_net and y negated, x equal.
TEST(PerFootModel, MirrorSymmetry) {
  for (FrictionLaw law : {FrictionLaw::kStiction, FrictionLaw::kContinuous}) {
    Effects e;
    e.friction = law;
    for (int n : {1, 3}) {
      const RobotParams r = paperRobot(n);
      const RunResult a = simulatePerFoot(r, sameMove(n, 30, -90, 0.2, 0.3), {}, e, {});
      const RunResult b = simulatePerFoot(r, sameMove(n, -30, 90, 0.2, 0.3), {}, e, {});
      ASSERT_TRUE(a.summary.ok && b.summary.ok) << a.summary.error << b.summary.error;
      EXPECT_GT(std::abs(a.summary.phi_net_deg), 1.0);
      // As the analytic model's random sweep: the adaptive steps are not mirror images bit for bit.
      EXPECT_NEAR(b.summary.phi_net_deg, -a.summary.phi_net_deg, 1e-6 * (1 + std::abs(a.summary.phi_net_deg)));
      EXPECT_NEAR(b.summary.extra.at("final_y_m"), -a.summary.extra.at("final_y_m"), 1e-7);
      EXPECT_NEAR(b.summary.extra.at("final_x_m"), a.summary.extra.at("final_x_m"), 1e-7);
      EXPECT_EQ(b.summary.stick_slip_events, a.summary.stick_slip_events);
    }
  }
}

// Breakaway and re-stick located to event_tol_s: phi_net converges as the tolerance tightens.
TEST(PerFootModel, EventLocationConverges) {
  const RobotParams r = paperRobot(1);
  const TailTrajectory tr = sameMove(1, 0, -90, 0.25, 0.25);  // Fig. 7
  std::vector<double> phi;
  for (double tol : {1e-4, 1e-6, 1e-9, 1e-12}) {
    PerFootSettings s;
    s.event_tol_s = tol;
    const RunResult p = simulatePerFoot(r, tr, s, {}, {});
    ASSERT_TRUE(p.summary.ok) << p.summary.error;
    EXPECT_GE(p.summary.stick_slip_events, 2);
    phi.push_back(p.summary.phi_net_deg);
  }
  const double ref = phi.back();
  EXPECT_LE(std::abs(phi[2] - ref), 1e-7);
  EXPECT_LE(std::abs(phi[2] - ref), std::abs(phi[0] - ref) + 1e-12);
  EXPECT_LE(std::abs(phi[1] - ref), 1e-5);
}

// The time series has the analytic model's columns where they exist, plus the per-foot ones; a
// held body's per-foot forces add up to its friction wrench.
TEST(PerFootModel, ColumnsAndHeldForces) {
  const RobotParams r = paperRobot(1);
  const RunResult p = simulatePerFoot(r, sameMove(1, 0, -90, 0.25, 0.25), {}, {}, {});
  const RunResult a = simulateAnalytic(r, sameMove(1, 0, -90, 0.25, 0.25), {}, {}, {});
  for (const auto& name : a.series.names()) EXPECT_TRUE(p.series.has(name)) << name;
  for (const char* c : {"F1x_N", "F4y_N", "N1_N", "N4_N", "load_factor"}) EXPECT_TRUE(p.series.has(c)) << c;
  EXPECT_EQ(p.series.numRows(), a.series.numRows());
  EXPECT_EQ(p.summary.model, "perfoot");
  const auto& st = p.series.values("rot_state");
  size_t k = 0;
  while (k < st.size() && st[k] != 0.0) ++k;
  ASSERT_LT(k, st.size());
  double fx = 0, n = 0;
  for (int i = 1; i <= 4; ++i) {
    fx += p.series.values("F" + std::to_string(i) + "x_N")[k];
    n += p.series.values("N" + std::to_string(i) + "_N")[k];
  }
  EXPECT_NEAR(fx, p.series.values("FFx_N")[k], 1e-9);
  EXPECT_NEAR(n, r.systemMass() * kG, 1e-9);
}

// Seeded random sweep: no NaN, bounded step counts, the result within physical bounds.
TEST(PerFootModel, RandomSweepNoNanBoundedSteps) {
  std::mt19937 rng(1111);
  std::uniform_real_distribution<double> u(0, 1);
  int ok = 0;
  std::vector<long> steps;
  for (int c = 0; c < 1000; ++c) {
    const int n = 1 + static_cast<int>(u(rng) * 6);
    const RobotParams r = paperRobot(n, 0.05 + 0.15 * u(rng));
    const TailTrajectory tr = sameMove(n, -90 + 180 * u(rng), (-360 + 720 * u(rng)) / n, 0.05 + 0.6 * u(rng),
                                       0.05 + 0.9 * u(rng));
    Effects e;
    e.friction = u(rng) < 0.7 ? FrictionLaw::kStiction : FrictionLaw::kContinuous;
    PerFootSettings s;
    if (u(rng) < 0.3) s.normal_loads = NormalLoadModel::kLoadTransfer;
    OutputSettings o;
    o.sample_dt_s = 0.05;
    const RunResult p = simulatePerFoot(r, tr, s, e, o);
    if (!p.summary.ok) {
      ASSERT_NE(p.summary.error.find("tips"), std::string::npos)
          << c << ": " << p.summary.error << " n " << n << " law " << int(e.friction) << " loads "
          << int(s.normal_loads) << " theta0 " << tr.joints[0].params().theta0_rad << " dtheta "
          << tr.joints[0].params().dtheta_rad << " dT " << tr.joints[0].params().dT_s << " wss "
          << tr.joints[0].params().w_ss << " dQ2B " << r.quadruped.d_Q2B_m;
      continue;
    }
    ++ok;
    ASSERT_TRUE(std::isfinite(p.summary.phi_net_deg)) << c;
    ASSERT_LT(p.summary.solver_steps, 200000) << c;
    steps.push_back(p.summary.solver_steps);
    for (const auto& name : p.series.names())
      for (double v : p.series.values(name))
        if (name != "load_factor" && name != "rot_state" && name != "trans_state" && name.rfind("MzT_", 0) != 0) {
          ASSERT_TRUE(std::isfinite(v)) << c << " " << name;
        }
  }
  EXPECT_GT(ok, 900);
  std::sort(steps.begin(), steps.end());
  std::printf("perfoot random sweep: %d cases ran, steps median %ld, max %ld\n", ok, steps[steps.size() / 2],
              steps.back());
}

// The per-foot model's stuck scan runs in chunks of the run's shortest phase / 8, sampled every
// shortest phase / 32. Joint 2 (which moves only from 0.1 s) sets that phase to 7.96 ms, so the
// chunk boundary at 4 x 0.995 = 3.98 ms lies just before joint 1's load peak at 4 ms and its sample
// is the lowest near the peak (the next one is at 4.229 ms): the dip lies across the boundary
// (docs/accuracy.md "A dip across a step boundary"). The critical coefficient comes from a run
// that holds (mu = 1): the load factor s is proportional to 1 / mu (the discs' radii are mu N_i),
// so mu_crit = s_max, the largest load_factor of 1 us rows. Just below it the body must break
// away; just above it nothing may move.
TEST(PerFootModel, LoadPeakAtAChunkBoundaryBreaksStiction) {
  RobotParams r = paperRobot(2);
  TailTrajectory tr;
  tr.joints.emplace_back(SplitCycleParams{0.0, -0.2 * M_PI / 180, 0.04, 0.2, 0.0});
  tr.joints.emplace_back(SplitCycleParams{0.0, -0.01 * M_PI / 180, 0.0398, 0.2, 0.1});  // 20x smaller loads
  r.friction.mu_s = r.friction.mu_d = 1.0;
  OutputSettings fine;
  fine.sample_dt_s = 1e-6;
  fine.duration_s = 0.02;
  const RunResult held = simulatePerFoot(r, tr, {}, {}, fine);
  ASSERT_TRUE(held.summary.ok) << held.summary.error;
  const auto& s = held.series.values("load_factor");
  const auto& t = held.series.values("t_s");
  const size_t i_max = static_cast<size_t>(std::max_element(s.begin(), s.end()) - s.begin());
  const double crit = s[i_max];  // x mu = 1
  std::printf("per-foot critical mu %.9f at t = %.6f s\n", crit, t[i_max]);
  ASSERT_NEAR(t[i_max], 0.004, 2e-6);  // 20 us after the chunk boundary
  for (const double f : {1.0 - 1e-5, 1.0 + 1e-5}) {
    r.friction.mu_s = r.friction.mu_d = f * crit;
    const RunResult res = simulatePerFoot(r, tr, {}, {}, {});
    ASSERT_TRUE(res.summary.ok) << res.summary.error;
    if (f < 1)
      EXPECT_GE(res.summary.stick_slip_events, 1) << "mu = (1 - 1e-5) x critical";
    else
      EXPECT_EQ(res.summary.stick_slip_events, 0) << "mu = (1 + 1e-5) x critical";
  }
}

// The held load factor the model's stuck margin uses, at any time, equals the time series' column.
TEST(PerFootModel, HeldLoadFactorMatchesTheTimeSeries) {
  RobotParams r = paperRobot(2);
  r.friction.mu_s = r.friction.mu_d = 5.0;  // holds throughout
  const TailTrajectory tr = sameMove(2, 10, -40, 0.3, 0.3);
  const RunResult run = simulatePerFoot(r, tr, {}, {}, {});
  ASSERT_TRUE(run.summary.ok) << run.summary.error;
  ASSERT_EQ(run.summary.stick_slip_events, 0);
  const auto& t = run.series.values("t_s");
  const auto& s = run.series.values("load_factor");
  const std::vector<double> s2 = perFootHeldLoadFactor(r, tr, {}, t);
  ASSERT_EQ(s2.size(), s.size());
  for (size_t i = 0; i < s.size(); ++i) EXPECT_EQ(s2[i], s[i]) << t[i];
  EXPECT_GT(*std::max_element(s.begin(), s.end()), 0.01);
}

// Seeded random strokes at the edge of stiction, per-foot model (the analytic model's test of the
// same name): the critical coefficient is the largest held load factor at mu = 1 (s scales as
// 1 / mu), found from perFootHeldLoadFactor alone (samples every 20 us and at both sides of every
// breakpoint, golden section around the five highest local maxima), not from a run. At (1 - 1e-6)
// times it the body must break away; at (1 + 1e-6) times it nothing may move.
TEST(PerFootModel, RandomStrokesAtTheEdgeOfStictionBreakExactlyBelowIt) {
  RandomCases cases(11262026);
  int tested = 0;
  for (int k = 0; k < 12; ++k) {
    RandomCase c = cases.next();
    c.effects.friction = FrictionLaw::kStiction;
    c.robot.friction.mu_s = c.robot.friction.mu_d = 1.0;
    const TailTrajectory& tr = c.trajectory;
    auto s = [&](double t) { return perFootHeldLoadFactor(c.robot, tr, c.effects, {t})[0]; };
    auto many = [&](const std::vector<double>& times) { return perFootHeldLoadFactor(c.robot, tr, c.effects, times); };
    double crit = 0;
    try {
      crit = strokeMaximum(tr, 2e-5, s, many);
    } catch (const TippingError&) {
      continue;  // tips over: no stiction edge to test
    }
    if (!(crit > 1e-6)) continue;
    ++tested;
    for (const double f : {1.0 - 1e-6, 1.0 + 1e-6}) {
      c.robot.friction.mu_s = c.robot.friction.mu_d = f * crit;
      const RunResult res = simulatePerFoot(c.robot, tr, {}, c.effects, {});
      ASSERT_TRUE(res.summary.ok) << describe(c) << ": " << res.summary.error;
      if (f < 1)
        EXPECT_GE(res.summary.stick_slip_events, 1) << "case " << k << " (" << describe(c) << "), mu = (1 - 1e-6) x " << crit;
      else
        EXPECT_EQ(res.summary.stick_slip_events, 0) << "case " << k << " (" << describe(c) << "), mu = (1 + 1e-6) x " << crit;
    }
  }
  std::printf("%d strokes tested at their critical coefficient\n", tested);
  EXPECT_GE(tested, 8);
}

// max_load_factor_stuck is the largest load factor while held, and a held body has s <= 1 (it breaks
// away where s reaches 1). A chunk that broke away used to contribute s at its end, after the
// breakaway: up to 60 over these runs.
TEST(PerFootModel, MaxLoadFactorWhileHeldIsAtMostOne) {
  RandomCases gen(12345);
  int checked = 0;
  for (int k = 0; k < 400; ++k) {
    const RandomCase c = gen.next();
    if (c.robot.numLinks() > 3 || c.effects.friction != FrictionLaw::kStiction) continue;
    const RunResult r = simulatePerFoot(c.robot, c.trajectory, {}, c.effects, {});
    if (!r.summary.ok) continue;
    const double s = r.summary.extra.at("max_load_factor_stuck");
    EXPECT_LE(s, 1.0 + 1e-6) << "case " << k << ": " << describe(c);
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

// A warm start (the result for a nearby wrench) finds the start scan's load factor: along slowly
// turning random wrenches on random discs, each warm-started from the last, s agrees to round-off
// and the breakaway twist's sense and centre agree.
TEST(PerFootLimitSurface, WarmStartFindsTheScannedMaximum) {
  std::mt19937 rng(35);
  std::uniform_real_distribution<double> u(-1, 1);
  int rotations = 0;
  for (int n = 0; n < 200; ++n) {
    const Vec2 p_QC(-0.0155 + 0.12 * u(rng), 0.1 * u(rng));
    const FootDiscs d = paperDiscs(p_QC, 0.3 + 0.2 * u(rng), 100.0);
    const Vec2 F0(20 * u(rng), 20 * u(rng)), dF(2 * u(rng), 2 * u(rng));
    const double M0 = 5 * u(rng), dM = 0.5 * u(rng);
    LoadFactor last = loadFactor(d, {F0, M0});
    for (int k = 1; k <= 20; ++k) {
      const Wrench2 w{F0 + 0.05 * k * dF, M0 + 0.05 * k * dM};
      const LoadFactor cold = loadFactor(d, w);
      const LoadFactor warm = loadFactor(d, w, &last);
      ASSERT_NEAR(warm.s, cold.s, 1e-12 * cold.s) << n << " " << k;
      if (cold.sigma != 0.0 && cold.pivot_foot < 0 && cold.s > (w.F.norm() / (d.c[0] + d.c[1] + d.c[2] + d.c[3])) * 1.001) {
        ++rotations;
        EXPECT_EQ(warm.sigma, cold.sigma) << n << " " << k;
        EXPECT_LT((warm.centre - cold.centre).norm(), 1e-5) << n << " " << k;
      }
      last = warm;
    }
  }
  EXPECT_GT(rotations, 1000);
}

// Work count: a held stroke's stick/slip scan warm-starts the load factor instead of scanning
// candidate centres at every sample; the start scan runs only at the first sample and where a
// margin is near 0. Its answer is the start scan's: phi_net 0, and the same largest load factor.
TEST(PerFootModel, HeldScanWarmStartsTheLoadFactor) {
  RobotParams r = paperRobot(2);
  r.friction.mu_s = r.friction.mu_d = 5.0;  // holds throughout
  const TailTrajectory tr = sameMove(2, 10, -40, 0.3, 0.3);
  OutputSettings out;  // two rows, t = 0 and the end, as a search runs it
  out.sample_dt_s = tr.endTime() + out.settle_s;
  const RunResult run = simulatePerFoot(r, tr, {}, {}, out);
  ASSERT_TRUE(run.summary.ok) << run.summary.error;
  ASSERT_EQ(run.summary.stick_slip_events, 0);
  EXPECT_EQ(run.summary.phi_net_deg, 0.0);
  const double evaluations = run.summary.extra.at("load_factor_evaluations");
  const double scans = run.summary.extra.at("load_factor_start_scans");
  EXPECT_GT(evaluations, 100);
  // The first sample, the two rows (not warm) and the few samples held by a pure translation run
  // the start scan; the other samples are warm-started (before: every one scanned).
  EXPECT_LT(scans, 0.1 * evaluations) << evaluations << " load factors";
}
