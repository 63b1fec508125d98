// Tipping over under the per-foot model's load transfer (docs/per-foot-model.md "Normal loads"):
// the shifted centre of pressure depends on the state, so it is scanned along the solution, not
// checked before the run, and the verdict must not depend on the rows the run records.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "models/perfoot/per_foot_model.h"
#include "analytic_test_util.h"
#include "random_cases.h"

using namespace tailsim;
using namespace tailsim::testing;

namespace {

// The support margin of every row: the distance of the centre of pressure to the nearest edge
// (>= 0 inside), from the rows' normal loads alone: f_i = N_i / (m g) gives it back, x_e =
// l_F (f1 + f2 - f3 - f4) / 2, y_e = w_F (f1 - f2 - f3 + f4) / 2 (Eqs. A4-A5; the clipping's
// lambda (1, -1, 1, -1) cancels). A load of a centre of pressure outside would be the nearest
// point's, on the edge: margin 0.
std::vector<double> rowMargins(const RobotParams& robot, const RunResult& r) {
  const QuadrupedParams& q = robot.quadruped;
  const double W = robot.systemMass() * robot.gravity_mps2;
  std::vector<double> m;
  for (size_t i = 0; i < r.series.numRows(); ++i) {
    double f[4];
    for (int j = 0; j < 4; ++j) f[j] = r.series.values("N" + std::to_string(j + 1) + "_N")[i] / W;
    const double x = 0.5 * q.l_F_m * (f[0] + f[1] - f[2] - f[3]), y = 0.5 * q.w_F_m * (f[0] - f[1] - f[2] + f[3]);
    m.push_back(std::min(0.5 * q.l_F_m - std::abs(x), 0.5 * q.w_F_m - std::abs(y)));
  }
  return m;
}

// The time in a TippingError message ("... the robot tips over at t = 0.123 s"), or NaN.
double exitTime(const RunResult& r) {
  const std::string key = "tips over at t = ";
  const size_t k = r.summary.error.find(key);
  return k == std::string::npos ? std::nan("") : std::stod(r.summary.error.substr(k + key.size()));
}

// The support margin just before an exit at t_A: the last rows of runs that end 1 us and 0.1 us
// before it (the rows do not change the solution). runTo(o) runs the case with output o; a run
// that fails is a test failure (margins NaN).
template <class RunTo>
std::array<double, 2> marginsBefore(const RobotParams& robot, const RunTo& runTo, const OutputSettings& base, double t_A) {
  std::array<double, 2> g{std::nan(""), std::nan("")};
  for (int j = 0; j < 2; ++j) {
    OutputSettings o = base;
    o.duration_s = t_A - (j == 0 ? 1e-6 : 1e-7);
    o.sample_dt_s = o.duration_s / 4;
    const RunResult r = runTo(o);
    if (!r.summary.ok) {
      ADD_FAILURE() << "the run to " << o.duration_s << " s failed: " << r.summary.error;
      return g;
    }
    g[j] = rowMargins(robot, r).back();
  }
  return g;
}

// Two links, stiction (mu 1.5: the body is held through the stroke), COM h high: the held
// force shifts the centre of pressure backwards while the tail accelerates, and at h = 0.46153 m
// it leaves the rear edge from t = 0.06197 s for about 1.4 ms, at most 22 um beyond (measured from
// the N_i rows of 1 us runs at h = 0.30 and 0.35 m, the held shift being linear in h). Found by a
// search (critical heights by bisection, before the scan): with 1 ms rows the run failed from
// h = 0.461465 m, with two rows (time_series: none) only from h = 0.461589 m.
struct BriefExit {
  RobotParams robot = paperRobot(2, 0.13);
  TailTrajectory trajectory = sameMove(2, 43.5, 37, 0.24, 0.5);
  PerFootSettings settings;
  BriefExit(double h) {
    robot.friction.mu_s = robot.friction.mu_d = 1.5;
    robot.quadruped.com_height_m = h;
    settings.normal_loads = NormalLoadModel::kLoadTransfer;
  }
  RunResult run(bool two_rows) const {
    OutputSettings o;
    if (two_rows) o.sample_dt_s = trajectory.endTime() + o.settle_s;  // what time_series: none records
    return simulatePerFoot(robot, trajectory, settings, {}, o);
  }
};

}  // namespace

TEST(PerFootTipping, ABriefExitBetweenRowsFailsWhateverTheRunRecords) {
  const BriefExit c(0.46153);
  const RunResult full = c.run(false), none = c.run(true);
  EXPECT_EQ(none.series.numRows(), 0u);  // a failed run keeps no rows
  ASSERT_FALSE(full.summary.ok);
  ASSERT_FALSE(none.summary.ok) << "two rows: the run passed";
  std::printf("full: %s\n", full.summary.error.c_str());
  EXPECT_NE(full.summary.error.find("centre of pressure (load transfer) at (-0.15"), std::string::npos)
      << full.summary.error;
  EXPECT_NE(full.summary.error.find("beyond its rear edge"), std::string::npos) << full.summary.error;
  EXPECT_NEAR(exitTime(full), 0.06197, 1e-4) << full.summary.error;
  EXPECT_NEAR(exitTime(full), exitTime(none), 1e-9) << full.summary.error << "\n" << none.summary.error;
  // With h 0.13 mm lower (0.4614 m) the dip stays 12 um inside: both stand.
  const BriefExit inside(0.4614);
  for (bool two_rows : {false, true}) EXPECT_TRUE(inside.run(two_rows).summary.ok) << two_rows;
}


// Seeded random per-foot load-transfer runs (both laws) against a brute-force scan of the support
// margin along the same solution, rows every 20 us (the rows do not change the solution). Each
// case's COM height is set by bisection (two-row runs) to where the centre of pressure just
// reaches an edge, h_c, and run at h_c (1 -+ 1e-4): just inside and just beyond it, where a
// sampled check is most easily fooled. A run that stands: every row's margin is > 0 (a row
// outside would read 0). A run that tips at t_A: the rows up to t_A - 20 us are all inside, and
// the margin 0.1 us before t_A is positive and about a tenth of that 1 us before (a linear
// approach to the edge at t_A: located to well below 0.1 us).
TEST(PerFootTipping, AgreesWithADenseScanOfTheSolution) {
  RandomCases gen(20260412);
  int tipped = 0, stood = 0;
  double worst = 0;
  for (int k = 0; k < 200 && tipped + stood < 24; ++k) {
    RandomCase c = gen.next();
    if (c.effects.friction == FrictionLaw::kNone) c.effects.friction = FrictionLaw::kStiction;
    PerFootSettings s;
    s.normal_loads = NormalLoadModel::kLoadTransfer;
    OutputSettings none;
    none.settle_s = 0.1;
    none.sample_dt_s = c.trajectory.endTime() + none.settle_s;
    auto run = [&](double h, const OutputSettings& o) {
      c.robot.quadruped.com_height_m = h;
      return simulatePerFoot(c.robot, c.trajectory, s, c.effects, o);
    };
    auto tipsByCop = [&](const RunResult& r) { return r.summary.error.find("centre of pressure") != std::string::npos; };
    // Heights up to 0.9 l_F / mu: the load transfer's fixed point contracts by about mu h / l_F.
    const double mu = std::max(c.robot.friction.mu_s, c.robot.friction.mu_d);
    double lo = 0.01, hi = std::min(2.0, 0.9 * c.robot.quadruped.l_F_m / mu);
    if (!run(lo, none).summary.ok || !tipsByCop(run(hi, none))) continue;  // the COM itself tips, or nothing does
    bool other = false;
    for (int it = 0; it < 30 && !other; ++it) {
      const double h = 0.5 * (lo + hi);
      const RunResult r = run(h, none);
      other = !r.summary.ok && !tipsByCop(r);
      (r.summary.ok ? lo : hi) = h;
    }
    if (other) continue;
    for (const double f : {1.0 - 1e-4, 1.0 + 1e-4}) {
      const double h = 0.5 * (lo + hi) * f;
      const RunResult a = run(h, none);
      if (!a.summary.ok) {
        ASSERT_TRUE(tipsByCop(a)) << a.summary.error;
      }
      const double t_A = a.summary.ok ? none.sample_dt_s : exitTime(a);
      ASSERT_TRUE(std::isfinite(t_A)) << a.summary.error;
      if (!a.summary.ok && t_A < 5e-5) continue;  // outside at once: nothing to scan
      OutputSettings dense = none;
      dense.sample_dt_s = 2e-5;
      dense.duration_s = a.summary.ok ? t_A : t_A - 2e-5;
      const RunResult b = run(h, dense);
      ASSERT_TRUE(b.summary.ok) << k << " " << describe(c) << " h " << h << ": " << b.summary.error;
      const std::vector<double> m = rowMargins(c.robot, b);
      const auto& t = b.series.values("t_s");
      const size_t low = static_cast<size_t>(std::min_element(m.begin(), m.end()) - m.begin());
      ASSERT_GT(m[low], 1e-12) << k << " " << describe(c) << " h " << h << ": a row outside at t = " << t[low]
                               << ", the run " << (a.summary.ok ? "stood" : a.summary.error);
      if (a.summary.ok) {
        ++stood;
        continue;
      }
      ++tipped;
      // Just before t_A the centre of pressure is inside and reaching the edge.
      const std::array<double, 2> g = marginsBefore(c.robot, [&](const OutputSettings& o) { return run(h, o); }, none, t_A);
      ASSERT_FALSE(HasFailure()) << k << " " << describe(c) << " h " << h;
      EXPECT_GT(g[1], 0.0) << k << " " << describe(c) << " h " << h;
      EXPECT_LT(g[1], 0.2 * g[0]) << k << " " << describe(c) << " h " << h;  // linear: 0.1 g[0]
      worst = std::max(worst, g[1]);
    }
  }
  std::printf("%d runs tipped (0.1 us before the exit at most %.2e m inside), %d stood\n", tipped, worst, stood);
  EXPECT_GE(tipped, 8);
  EXPECT_GE(stood, 8);
}


// An exit while the body slides (every other test's exits happen while it is held). The body
// starts sliding forward at 0.6 m/s (PerFootSettings::initial_velocity) under a one-link stroke;
// sliding friction at every foot shifts the centre of pressure by up to h mu_d, and as the body
// slows and turns the shift swings onto the side edge at about t = 0.34 s, after the tail has
// stopped (0.3 s), while the body still slides and turns. The critical height (bisection on two-row
// runs, about 0.5285 m) splits runs that stand from runs that tip; just beyond it the full and the
// two-row runs fail at the same time, the state just before is sliding, and rows every 20 us up
// to the exit stay inside, the margin falling linearly onto the edge.
TEST(PerFootTipping, AnExitWhileSlidingIsLocatedWhateverTheRunRecords) {
  RobotParams robot = paperRobot(1);
  const TailTrajectory tr = sameMove(1, 60, -120, 0.3, 0.25);
  PerFootSettings s;
  s.normal_loads = NormalLoadModel::kLoadTransfer;
  s.initial_velocity = {0.6, 0.0, 0.0};
  OutputSettings none;
  none.sample_dt_s = tr.endTime() + none.settle_s;  // what time_series: none records
  auto run = [&](double h, const OutputSettings& o) {
    robot.quadruped.com_height_m = h;
    return simulatePerFoot(robot, tr, s, {}, o);
  };
  auto tipsByCop = [](const RunResult& r) { return r.summary.error.find("centre of pressure") != std::string::npos; };
  // Higher COMs tip too, located like any other exit. (The load transfer's fixed point used to
  // cycle there without converging: its solution sat on the edge, where the loads of a centre of
  // pressure outside jumped by clamping to the bare edge instead of the accepted rectangle.)
  for (double h : {0.54, 0.55, 0.56}) {
    const RunResult r = run(h, none);
    EXPECT_TRUE(tipsByCop(r)) << h << ": " << r.summary.error;
    EXPECT_GT(exitTime(r), 0.1) << h << ": " << r.summary.error;  // while sliding, not at once
    std::printf("h %.2f m: tips at t = %.6f s\n", h, exitTime(r));
  }
  EXPECT_EQ(exitTime(run(0.6, none)), 0.0);  // h mu_d v-direction shift 0.18 m > l_F / 2: at once
  double lo = 0.5, hi = 0.529;
  ASSERT_TRUE(run(lo, none).summary.ok) << run(lo, none).summary.error;
  ASSERT_TRUE(tipsByCop(run(hi, none))) << run(hi, none).summary.error;
  for (int it = 0; it < 30; ++it) {
    const double h = 0.5 * (lo + hi);
    const RunResult r = run(h, none);
    ASSERT_TRUE(r.summary.ok || tipsByCop(r)) << h << ": " << r.summary.error;
    (r.summary.ok ? lo : hi) = h;
  }
  const double h_c = 0.5 * (lo + hi);
  EXPECT_NEAR(h_c, 0.5285, 1e-3);
  for (const OutputSettings& o : {none, OutputSettings{}}) EXPECT_TRUE(run(h_c * (1 - 1e-4), o).summary.ok);
  const double h = h_c * (1 + 1e-4);
  const RunResult a = run(h, none), full = run(h, OutputSettings{});
  ASSERT_TRUE(tipsByCop(a)) << a.summary.error;
  ASSERT_TRUE(tipsByCop(full)) << full.summary.error;
  const double t_A = exitTime(a);
  EXPECT_NEAR(t_A, 0.344, 0.01) << a.summary.error;
  EXPECT_GT(t_A, tr.endTime());
  EXPECT_NEAR(exitTime(full), t_A, 1e-9) << full.summary.error;
  // Rows every 20 us up to just before the exit: all inside, the body sliding and turning there.
  OutputSettings dense = none;
  dense.sample_dt_s = 2e-5;
  dense.duration_s = t_A - 2e-5;
  const RunResult b = run(h, dense);
  ASSERT_TRUE(b.summary.ok) << b.summary.error;
  EXPECT_EQ(b.series.values("trans_state").back(), 1.0);
  EXPECT_EQ(b.series.values("rot_state").back(), 1.0);
  EXPECT_GT(b.summary.extra.at("final_speed_mps"), 1e-3);
  const std::vector<double> m = rowMargins(robot, b);
  EXPECT_GT(*std::min_element(m.begin(), m.end()), 0.0);
  const std::array<double, 2> g = marginsBefore(robot, [&](const OutputSettings& o) { return run(h, o); }, none, t_A);
  ASSERT_FALSE(HasFailure());
  EXPECT_GT(g[1], 0.0);
  EXPECT_LT(g[1], 0.2 * g[0]);  // linear onto the edge: 0.1 g[0]
  std::printf("h_c %.6f m, exit at t = %.6f s while sliding; margin 1 us / 0.1 us before: %.3g / %.3g m\n", h_c, t_A,
              g[0], g[1]);
}

// The load transfer's normal loads solve their own equation in every row, whichever way they were
// found: N_i = m g f_i(p), f from the Appendix distribution (footLoads) at the centre of pressure
// p = p_QC + R(-phi) (-h F / (m g)), F the summed foot friction (the rows' FFx, FFy). Random strokes
// at random COM heights, every other one sliding from the start, every other pair on other feet
// (l_F, w_F, d_Q2C drawn): where the fixed-point iteration does not converge Newton's method solves
// the loads (extra.load_transfer_newton_solves, also reported by runs that then tip). Every run
// stands or tips at a located time; none fails for want of loads (33 of these 400 did before, on
// the paper's feet), and none tips at a "system COM" outside, which a centre of pressure clamped
// onto an edge and turned back into p_QC could (1 ulp outside the rectangle).
TEST(PerFootTipping, LoadTransferLoadsSolveTheirEquationInEveryRow) {
  RandomCases rc(4242);
  std::mt19937 g(99);
  std::uniform_real_distribution<double> uh(0.05, 0.7), uv(0.0, 0.8), ua(-M_PI, M_PI), u01(0.0, 1.0);
  int newton_runs = 0, rows_checked = 0, tipped = 0, newton_rows = 0;
  double worst = 0.0;
  for (int k = 0; k < 600; ++k) {
    RandomCase c = rc.next();
    PerFootSettings s;
    s.normal_loads = NormalLoadModel::kLoadTransfer;
    c.robot.quadruped.com_height_m = uh(g);
    if (k % 2) {
      const double v = uv(g), a = ua(g);
      s.initial_velocity = {v * std::cos(a), v * std::sin(a), 0.0};
    }
    if (k % 4 >= 2) {
      c.robot.quadruped.l_F_m = 0.15 + 0.25 * u01(g);
      c.robot.quadruped.w_F_m = 0.15 + 0.2 * u01(g);
      c.robot.quadruped.d_Q2C_m = -0.05 + 0.1 * u01(g);
    }
    const RunResult r = simulatePerFoot(c.robot, c.trajectory, s, c.effects, {});
    const bool newton = r.summary.extra.at("load_transfer_newton_solves") > 0;
    newton_runs += newton;
    if (!r.summary.ok) {
      // The centre of pressure leaves at a located time, or (other feet) the system COM is
      // outside before the run: both messages give the time. (A spurious exit of an evaluation's
      // clamped point has no time: it is no located event.)
      const bool cop = r.summary.error.find("centre of pressure (load transfer)") != std::string::npos;
      ASSERT_TRUE(cop || r.summary.error.find("system COM") != std::string::npos)
          << k << " " << describe(c) << ": " << r.summary.error;
      ASSERT_NE(r.summary.error.find("tips over at t = "), std::string::npos)
          << k << " " << describe(c) << ": " << r.summary.error;
      ++tipped;
      continue;
    }
    newton_rows += newton ? static_cast<int>(r.series.numRows()) : 0;
    if (c.effects.friction == FrictionLaw::kNone) continue;  // no friction: no normal loads either (N = 0)
    const QuadrupedParams& q = c.robot.quadruped;
    const double W = c.robot.systemMass() * c.robot.gravity_mps2;
    const double F_cap = breakawayCoefficient(c.robot.friction) * W;
    const TimeSeries& ts = r.series;
    const size_t n = c.trajectory.joints.size();
    for (size_t i = 0; i < ts.numRows(); ++i) {
      const Vec2 F(ts.values("FFx_N")[i], ts.values("FFy_N")[i]);
      if (!(F.norm() <= F_cap)) continue;  // held beyond the cap: the loads take the capped force
      std::vector<JointState> js(n);
      for (size_t j = 0; j < n; ++j) js[j].theta = ts.values("theta" + std::to_string(j + 1) + "_deg")[i] * M_PI / 180;
      const SystemLoads sl = systemLoads(c.robot, js, false);
      const double phi = ts.values("phi_deg")[i] * M_PI / 180;
      const Vec2 p = sl.p_QC + rotate(-phi, Vec2(-q.com_height_m * F / W));
      if (supportMargin(q, comFromFootCentroid(q, p)) < 0) continue;
      const FootLoads fl = footLoads(q, p);
      for (int j = 0; j < 4; ++j) {
        const double e = std::abs(ts.values("N" + std::to_string(j + 1) + "_N")[i] - W * fl.f_C[j]) / W;
        if (e > worst && e > 1e-12) std::printf("row %zu of run %d (%s): error %.3g\n", i, k, describe(c).c_str(), e);
        worst = std::max(worst, e);
      }
      ++rows_checked;
    }
  }
  std::printf("%d runs needed Newton's method (%d rows of those that stood); %d rows checked, worst |N - m g f| / "
              "(m g) %.2e; %d runs tipped\n", newton_runs, newton_rows, rows_checked, worst, tipped);
  EXPECT_GE(newton_runs, 8);
  EXPECT_GE(newton_rows, 500);
  EXPECT_GE(rows_checked, 500);
  EXPECT_LT(worst, 1e-12);  // Newton's method polishes to round-off (its tolerance is 1e-10 m g)
}
