// The MuJoCo contact model's runs: tracking, stability on the hard cases, conservation of
// angular momentum without friction, and Newton-Euler consistency of the logged loads.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "models/mujoco/mjcf_generator.h"
#include "models/mujoco/mujoco_handles.h"
#include "models/mujoco/mujoco_simulation.h"
#include "random_robots.h"
#include "series_compare.h"

using namespace tailsim;

namespace {

constexpr double kDeg = M_PI / 180.0;

TailTrajectory sameForAllJoints(int n, const SplitCycleParams& sp) {
  TailTrajectory t;
  for (int i = 0; i < n; ++i) t.joints.emplace_back(sp);
  return t;
}

// Fig. 6 cases (Sec. 4.2): dT = 0.25 s, theta_0 = 0, w_ss = 0.25, d_Q2B = 0.1405 m.
SplitCycleParams fig6(double dtheta_deg) {
  SplitCycleParams sp;
  sp.theta0_rad = 0.0;
  sp.dtheta_rad = dtheta_deg * kDeg;
  sp.dT_s = 0.25;
  sp.w_ss = 0.25;
  return sp;
}

void expectCleanRun(const RunResult& r) {
  ASSERT_TRUE(r.summary.ok) << r.summary.error;
  EXPECT_EQ(r.summary.extra.at("mujoco_warnings"), 0.0);
  for (const std::string& name : r.series.names())
    for (double v : r.series.values(name)) ASSERT_TRUE(std::isfinite(v)) << name;
}

}  // namespace

class Fig6Tracking : public ::testing::TestWithParam<std::pair<int, double>> {};

TEST_P(Fig6Tracking, RmsBelowOnePercentOfStroke) {
  const auto [n, dtheta_deg] = GetParam();
  RobotParams p = paperRobot(n);
  p.quadruped.d_Q2B_m = 0.1405;
  OutputSettings out;
  const RunResult r = simulateMujoco(p, sameForAllJoints(n, fig6(dtheta_deg)), MujocoSettings{}, Effects{}, out);
  expectCleanRun(r);
  for (int i = 1; i <= n; ++i) {
    const double rms = r.summary.extra.at("tracking_rms_deg_j" + std::to_string(i));
    EXPECT_LT(rms, 0.01 * std::abs(dtheta_deg)) << "joint " << i;
    // The logged error column agrees with the controller's own statistics.
    double mx = 0.0;
    for (double e : r.series.values("track_err" + std::to_string(i) + "_deg")) mx = std::max(mx, std::abs(e));
    EXPECT_LE(mx, r.summary.extra.at("tracking_max_deg_j" + std::to_string(i)) + 1e-12);
  }
  // Output grid: t_k = k * sample_dt exactly, through trajectory end + settle.
  const std::vector<double>& t = r.series.values("t_s");
  ASSERT_EQ(t.size(), static_cast<size_t>(std::lround((0.25 + out.settle_s) / out.sample_dt_s)) + 1);
  for (size_t k = 0; k < t.size(); ++k) EXPECT_EQ(t[k], k * out.sample_dt_s);
  // The tail ends where the trajectory ends.
  for (int i = 1; i <= n; ++i)
    EXPECT_NEAR(r.series.values("theta" + std::to_string(i) + "_deg").back(), dtheta_deg, 0.01 * std::abs(dtheta_deg));
  // The body turned (Sec. 4.2: the contact model rotates) and came to rest before the end.
  EXPECT_GT(std::abs(r.summary.phi_net_deg), 1.0);
  EXPECT_LT(r.summary.t_stop_s, t.back());
}

INSTANTIATE_TEST_SUITE_P(PaperCases, Fig6Tracking,
                         ::testing::Values(std::make_pair(1, -90.0), std::make_pair(6, -30.0)));

TEST(MujocoSimulation, HardCasesRunWithoutWarnings) {
  // 6 links on the Eq. 25 trajectory (peak 10.47 rad/s) and the 1-link tail swinging 180 deg in 0.1 s.
  {
    const SplitCycleParams sp = equalPeakSpeedParams(6, 10.47, 0.25);
    const RunResult r = simulateMujoco(paperRobot(6), sameForAllJoints(6, sp), MujocoSettings{}, Effects{}, {});
    expectCleanRun(r);
  }
  for (FrictionLaw f : {FrictionLaw::kStiction, FrictionLaw::kContinuous, FrictionLaw::kNone}) {
    SplitCycleParams sp;
    sp.dtheta_rad = -M_PI;
    sp.dT_s = 0.1;
    sp.w_ss = 0.25;
    Effects e;
    e.friction = f;
    const RunResult r = simulateMujoco(paperRobot(1), sameForAllJoints(1, sp), MujocoSettings{}, e, {});
    expectCleanRun(r);
  }
}

TEST(MujocoSimulation, InstabilityIsReportedNamingTheSetting) {
  MujocoSettings s;
  s.integrator = MujocoIntegrator::kEuler;  // explicit servo damping on a 6-link chain: unstable (docs/mujoco-model.md)
  const SplitCycleParams sp = equalPeakSpeedParams(6, 10.47, 0.25);
  const RunResult r = simulateMujoco(paperRobot(6), sameForAllJoints(6, sp), s, Effects{}, {});
  ASSERT_FALSE(r.summary.ok);
  EXPECT_NE(r.summary.error.find("timestep_s="), std::string::npos) << r.summary.error;
  EXPECT_NE(r.summary.error.find("unstable"), std::string::npos) << r.summary.error;
}

TEST(MujocoSimulation, RestingRobotCarriesItsWeightOnItsFeet) {
  // At t = 0 (after settling) the normal forces carry m g, the friction is zero, the tail load is
  // zero and Izz is Eq. (11) for the initial pose. The load columns average over each output
  // interval (row 0: [0, dt/2)) and the tail starts at t = 0: an output grid of one timestep makes
  // row 0 the single step from the rest state.
  const RobotParams p = paperRobot(1);
  OutputSettings out;
  out.sample_dt_s = MujocoSettings{}.timestep_s;
  const RunResult r = simulateMujoco(p, sameForAllJoints(1, fig6(-90)), MujocoSettings{}, Effects{}, out);
  expectCleanRun(r);
  double fn = 0.0;
  for (int k = 1; k <= 4; ++k) fn += r.series.values("foot" + std::to_string(k) + "_Fn_N")[0];
  // The soft first millimetre of the contact (docs/mujoco-model.md "Contact settings: the rule and
  // its evidence") bounces the body on its feet at ~110 rad/s, damping ratio ~0.9: after the 0.1 s
  // pre-roll 1e-5 of m g is left of the 0.15 mm drop into the floor (measured 1.0e-5).
  EXPECT_NEAR(fn, p.systemMass() * p.gravity_mps2, 5e-5 * fn);
  EXPECT_NEAR(r.series.values("MzT_Nm")[0], 0.0, 1e-8);
  EXPECT_NEAR(r.series.values("MzF_Nm")[0], 0.0, 1e-8);
  // Symmetric pose: left and right feet carry the same load; rear feet more (tail behind).
  EXPECT_NEAR(r.series.values("foot1_Fn_N")[0], r.series.values("foot2_Fn_N")[0], 1e-6);
  EXPECT_GT(r.series.values("foot3_Fn_N")[0], r.series.values("foot2_Fn_N")[0]);
}

// Without friction the only external forces (gravity, frictionless normals) are vertical, so the
// system's angular momentum about the vertical through its COM stays zero. Measured with MuJoCo's
// own momentum (mj_subtreeVel) on each sampled state; the integrator (semi-implicit) leaves an
// O(h) drift, so the test also checks that halving the step halves it.
TEST(MujocoSimulation, FrictionlessRunConservesAngularMomentum) {
  const int n = 6;
  const SplitCycleParams sp = equalPeakSpeedParams(n, 10.47, 0.25);
  Effects e;
  e.friction = FrictionLaw::kNone;
  std::vector<double> drift;
  for (double h : {2e-4, 1e-4}) {
    MujocoSettings s;
    s.timestep_s = h;
    s.servo_wn_dt = 1000.0 * h;  // the same servo in both runs
    ModelPtr scratch_model;
    DataPtr scratch;
    double lz_max = 0.0, body_scale = 0.0;
    const RunResult r = simulateMujoco(
        paperRobot(n), sameForAllJoints(n, sp), s, e, {},
        [&](double, const mjModel* m, const mjData* d) {
          if (!scratch) scratch = makeData(m);
          mj_copyData(scratch.get(), m, d);
          mj_forward(m, scratch.get());
          mj_subtreeVel(m, scratch.get());
          const int q = mj_name2id(m, mjOBJ_BODY, "quadruped");
          lz_max = std::max(lz_max, std::abs(scratch->subtree_angmom[3 * q + 2]));
          // Scale: the angular momentum of the quadruped body alone about its own COM.
          const double wz = scratch->cvel[6 * q + 2];
          body_scale = std::max(body_scale, std::abs(m->body_inertia[3 * q + 2] * wz));
        });
    expectCleanRun(r);
    ASSERT_GT(body_scale, 0.1);  // the body really spins (about 0.2 kg m^2/s at the peak)
    drift.push_back(lz_max / body_scale);
  }
  EXPECT_LT(drift[0], 0.03);
  EXPECT_LT(drift[1], 0.015);
  EXPECT_NEAR(drift[0] / drift[1], 2.0, 0.3);  // first-order integrator error, not a model error
}

// The logged tail loads obey Newton-Euler for the quadruped body alone, with the system COM from
// the planar kinematics of Eqs. (2)-(3), (10): m_Q a_Q = F_T + F_F and
// I_zz,Q phi_ddot = M_z,T + M_z,F + ((p_COM - p_Q) x (F_T + F_F))_z. Run without friction: the
// foot forces are then smooth and vertical (F_F = 0, M_z,F = 0); with friction they chatter
// (docs/mujoco-model.md) and a 1 ms sample of them does not represent the step-to-step impulses.
TEST(MujocoSimulation, LoggedTailLoadsSatisfyNewtonEulerOfTheBody) {
  const int n = 2;
  RobotParams p = paperRobot(n);
  SplitCycleParams sp = fig6(-60);
  sp.theta0_rad = 20 * kDeg;
  Effects e;
  e.friction = FrictionLaw::kNone;
  const RunResult r = simulateMujoco(p, sameForAllJoints(n, sp), MujocoSettings{}, e, {});
  expectCleanRun(r);
  const TimeSeries& ts = r.series;
  const auto& t = ts.values("t_s");
  const auto& x = ts.values("x_m");
  const auto& y = ts.values("y_m");
  const auto& phi = ts.values("phi_deg");
  const auto& phidd = ts.values("phiddot_dps2");
  const auto& mzt = ts.values("MzT_Nm");
  const auto& mzf = ts.values("MzF_Nm");
  const auto& ftx = ts.values("FTx_N");
  const auto& fty = ts.values("FTy_N");
  const auto& ffx = ts.values("FFx_N");
  const auto& ffy = ts.values("FFy_N");
  const double dt = t[1] - t[0];
  double peak_f = 0, peak_m = 0, err_f = 0, err_m = 0;
  for (size_t k = 1; k + 1 < t.size(); ++k) {
    const double ax = (x[k + 1] - 2 * x[k] + x[k - 1]) / (dt * dt);
    const double ay = (y[k + 1] - 2 * y[k] + y[k - 1]) / (dt * dt);
    const double Fx = ftx[k] + ffx[k], Fy = fty[k] + ffy[k];
    peak_f = std::max(peak_f, std::hypot(ftx[k], fty[k]));
    err_f = std::max(err_f, std::hypot(p.quadruped.mass_kg * ax - Fx, p.quadruped.mass_kg * ay - Fy));
    // System COM relative to p_Q in world axes (planar, Eqs. 2, 3, 10).
    const double ph = phi[k] * kDeg;
    double cx = 0, cy = 0, ang = ph + M_PI;  // R_B = R_Q R_Z(180 deg)
    double jx = -p.quadruped.d_Q2B_m * std::cos(ph), jy = -p.quadruped.d_Q2B_m * std::sin(ph);
    for (int i = 1; i <= n; ++i) {
      const TailLink& l = p.tail[i - 1];
      ang += ts.values("theta" + std::to_string(i) + "_deg")[k] * kDeg;
      cx += l.mass_kg * (jx + l.com_offset_m * std::cos(ang));
      cy += l.mass_kg * (jy + l.com_offset_m * std::sin(ang));
      jx += l.length_m * std::cos(ang);
      jy += l.length_m * std::sin(ang);
    }
    cx /= p.systemMass();
    cy /= p.systemMass();
    const double mq = mzt[k] + mzf[k] + (cx * Fy - cy * Fx);
    peak_m = std::max(peak_m, std::abs(mzt[k]));
    err_m = std::max(err_m, std::abs(p.quadruped.izz_kgm2 * phidd[k] * kDeg - mq));
    EXPECT_EQ(mzf[k], 0.0);
  }
  ASSERT_GT(peak_f, 10.0);
  ASSERT_GT(peak_m, 1.0);
  EXPECT_LT(err_f, 0.02 * peak_f) << "peak |F_T| " << peak_f;
  EXPECT_LT(err_m, 0.02 * peak_m) << "peak |M_zT| " << peak_m;
}

// Foot friction dissipates: its moment works against the yaw rate, sum of M_zF * phi_dot < 0,
// and the frictionless body turns further.
TEST(MujocoSimulation, FootFrictionOpposesTheYawRate) {
  RobotParams p = paperRobot(1);
  Effects e;
  const RunResult r = simulateMujoco(p, sameForAllJoints(1, fig6(-90)), MujocoSettings{}, e, {});
  expectCleanRun(r);
  const auto& mzf = r.series.values("MzF_Nm");
  const auto& pd = r.series.values("phidot_dps");
  double power = 0.0, scale = 0.0;
  for (size_t k = 0; k < pd.size(); ++k) {
    power += mzf[k] * pd[k];
    scale += std::abs(mzf[k] * pd[k]);
  }
  EXPECT_LT(power, -0.5 * scale);
  e.friction = FrictionLaw::kNone;
  const RunResult f = simulateMujoco(p, sameForAllJoints(1, fig6(-90)), MujocoSettings{}, e, {});
  EXPECT_GT(std::abs(f.summary.phi_net_deg), 2.0 * std::abs(r.summary.phi_net_deg));
}

TEST(MujocoSimulation, ContinuousFrictionLawStopsLaterThanStiction) {
  // mu(0) = 0 in the ADAMS law: the body coasts longer before it comes to rest (Sec. 4.2).
  RobotParams p = paperRobot(1);
  p.quadruped.d_Q2B_m = 0.1405;
  Effects e;
  const RunResult a = simulateMujoco(p, sameForAllJoints(1, fig6(-90)), MujocoSettings{}, e, {});
  e.friction = FrictionLaw::kContinuous;
  const RunResult b = simulateMujoco(p, sameForAllJoints(1, fig6(-90)), MujocoSettings{}, e, {});
  expectCleanRun(a);
  expectCleanRun(b);
  EXPECT_GT(b.summary.t_stop_s, a.summary.t_stop_s);
  EXPECT_GT(std::abs(b.summary.phi_net_deg), std::abs(a.summary.phi_net_deg));
}

// The force and moment columns are impulse averages over each output interval (docs/mujoco-model.md
// "Force and moment columns"). Conservation check against MuJoCo's own dynamics: the friction
// moment about the system COM, integrated over the run, equals the change of the robot's angular
// momentum about its COM (gravity has no moment about the COM, the tail's moments are internal),
// and the friction force integrated equals the change of linear momentum, at every output time.
// Measured: worst error 1.2 % (moment) and 1.8 % (force) of the peak change; the single samples
// written before gave 19 % and 45 % (the contact forces chatter, docs/mujoco-model.md).
TEST(MujocoSimulation, ImpulseAveragedContactLoadsIntegrateToTheMomentumChange) {
  RobotParams p = paperRobot(1);
  std::vector<double> hz, px;  // angular momentum about the system COM (z), linear momentum (x)
  const RunResult r = simulateMujoco(
      p, sameForAllJoints(1, fig6(-90)), MujocoSettings{}, Effects{}, {},
      [&](double, const mjModel* m, const mjData* d) {
        DataPtr scratch = makeData(m);
        mjData* s = scratch.get();
        std::copy(d->qpos, d->qpos + m->nq, s->qpos);
        std::copy(d->qvel, d->qvel + m->nv, s->qvel);
        mj_kinematics(m, s);
        mj_comPos(m, s);
        mj_comVel(m, s);
        mj_subtreeVel(m, s);
        const int root = mj_name2id(m, mjOBJ_BODY, mjcf::kQuadrupedBody);
        hz.push_back(s->subtree_angmom[3 * root + 2]);
        double mass = 0.0;
        for (int b = root; b < m->nbody; ++b) mass += m->body_rootid[b] == root ? m->body_mass[b] : 0.0;
        px.push_back(mass * s->subtree_linvel[3 * root]);
      });
  expectCleanRun(r);
  const auto& t = r.series.values("t_s");
  const auto& mzf = r.series.values("MzF_Nm");
  const auto& ffx = r.series.values("FFx_N");
  ASSERT_EQ(hz.size(), t.size());
  const double dt = t[1] - t[0];
  // Row k's average covers [t_k - dt/2, t_k + dt/2) (row 0 from t = 0): the running integral
  // through row k is the momentum change up to t_k + dt/2, halfway between two samples.
  double impulse_m = 0.0, impulse_f = 0.0, err_m = 0.0, err_f = 0.0, peak_h = 0.0, peak_p = 0.0;
  for (size_t k = 0; k + 1 < t.size(); ++k) {
    const double w = k == 0 ? 0.5 * dt : dt;
    impulse_m += mzf[k] * w;
    impulse_f += ffx[k] * w;
    const double dh = 0.5 * (hz[k] + hz[k + 1]) - hz[0], dp = 0.5 * (px[k] + px[k + 1]) - px[0];
    peak_h = std::max(peak_h, std::abs(dh));
    peak_p = std::max(peak_p, std::abs(dp));
    err_m = std::max(err_m, std::abs(impulse_m - dh));
    err_f = std::max(err_f, std::abs(impulse_f - dp));
  }
  ASSERT_GT(peak_h, 0.05) << "the friction must turn the body's angular momentum for this check to mean anything";
  ASSERT_GT(peak_p, 0.05);
  EXPECT_LT(err_m, 0.03 * peak_h) << "peak |dH_z| " << peak_h << " kg m^2/s";
  EXPECT_LT(err_f, 0.03 * peak_p) << "peak |dp_x| " << peak_p << " kg m/s";
}

// Contact fidelity figures (docs/mujoco-model.md "Contact fidelity"): airborne_fraction and
// peak_normal_force_over_mg, checked against what the impulse-averaged foot columns imply, and the
// warning above the limits of common/work_limits.h.
TEST(MujocoSimulation, ContactFidelityFiguresAndTheirWarning) {
  const RobotParams p = paperRobot(1);
  SplitCycleParams sp = fig6(-90.0);
  const TailTrajectory tr = sameForAllJoints(1, sp);
  const double weight = p.systemMass() * p.gravity_mps2;
  auto summedFn = [](const RunResult& r) {
    std::vector<double> s(r.series.numRows(), 0.0);
    for (int k = 1; k <= 4; ++k) {
      const std::vector<double>& f = r.series.values("foot" + std::to_string(k) + "_Fn_N");
      for (size_t i = 0; i < s.size(); ++i) s[i] += f[i];
    }
    return s;
  };
  // Default contact (docs/mujoco-model.md "Contact settings: the rule and its evidence"): every
  // step has a loaded foot and the normal force has no spikes (the old hard contact: 17 % of the
  // steps airborne, peaks of 12.6 m g; below).
  const RunResult def = simulateMujoco(p, tr, MujocoSettings{}, Effects{}, {});
  ASSERT_TRUE(def.summary.ok) << def.summary.error;
  const double air = def.summary.extra.at("airborne_fraction"), peak = def.summary.extra.at("peak_normal_force_over_mg");
  const std::vector<double> fn = summedFn(def);
  double mean = 0.0, row_max = 0.0;
  size_t all_zero_rows = 0;
  for (double f : fn) mean += f / fn.size(), row_max = std::max(row_max, f), all_zero_rows += f == 0.0;
  EXPECT_NEAR(mean / weight, 1.0, 0.05);  // on average the feet carry the weight
  // A row is the mean over its steps: its peak cannot exceed the steps' peak.
  EXPECT_GE(peak, row_max / weight - 1e-9);
  EXPECT_EQ(air, 0.0);
  EXPECT_LT(peak, 1.5);  // measured 1.2
  EXPECT_TRUE(def.summary.warnings.empty()) << def.summary.warnings.front();

  // The old hard contact (impedance 0.95 at first touch, 0.99 from 1 mm, solref (0.002, 1), impratio 1,
  // 2e-4 s): the sliding feet are pushed off the floor.
  MujocoSettings hard;
  hard.timestep_s = 2e-4;
  hard.servo_wn_dt = 0.2;
  hard.impratio = 1.0;
  hard.solref = {0.002, 1.0};
  hard.solimp = {0.95, 0.99, 0.001, 0.5, 2.0};
  const RunResult hd = simulateMujoco(p, tr, hard, Effects{}, {});
  ASSERT_TRUE(hd.summary.ok) << hd.summary.error;
  const std::vector<double> hfn = summedFn(hd);
  size_t hard_zero_rows = 0;
  for (double f : hfn) hard_zero_rows += f == 0.0;
  const double hair = hd.summary.extra.at("airborne_fraction");
  // A row with no load at all has every step airborne.
  EXPECT_GE(hair, static_cast<double>(hard_zero_rows) / hfn.size() - 1e-9);
  EXPECT_GT(hair, 0.05);                                              // measured 0.17
  EXPECT_GT(hd.summary.extra.at("peak_normal_force_over_mg"), 3.0);  // measured 12.6
  EXPECT_LT(hair, limits::kMaxAirborneFraction);
  EXPECT_TRUE(hd.summary.warnings.empty()) << hd.summary.warnings.front();

  // Without friction the feet never leave the ground and carry about the weight.
  Effects frictionless;
  frictionless.friction = FrictionLaw::kNone;
  const RunResult fl = simulateMujoco(p, tr, MujocoSettings{}, frictionless, {});
  ASSERT_TRUE(fl.summary.ok) << fl.summary.error;
  EXPECT_EQ(fl.summary.extra.at("airborne_fraction"), 0.0);
  EXPECT_LT(fl.summary.extra.at("peak_normal_force_over_mg"), 1.5);

  // The old hard contact stiffer still (solref 0.001 s) chatters more: above the limit, and the run says so.
  MujocoSettings stiff = hard;
  stiff.solref[0] = 0.001;
  const RunResult st = simulateMujoco(p, tr, stiff, Effects{}, {});
  ASSERT_TRUE(st.summary.ok) << st.summary.error;
  EXPECT_GT(st.summary.extra.at("airborne_fraction"), limits::kMaxAirborneFraction);
  ASSERT_EQ(st.summary.warnings.size(), 1u);
  EXPECT_NE(st.summary.warnings[0].find("all four feet carry no load"), std::string::npos) << st.summary.warnings[0];
}

// Random robots (tests/random_robots.h, the corpus of tests/bench_trust.cc): at the default contact
// a standing robot always has a loaded foot and no normal-force spikes. The first six cases (two
// robots, 8.7 and 7.6 kg, 0.26 and 0.28 m, mu 0.34 and 0.53); the old hard contact left no foot
// loaded in up to 12 % of the steps of these (case 3: 12 %, peak 11 m g).
TEST(MujocoSimulation, RandomRobotsKeepAFootLoaded) {
  OutputSettings o;
  o.time_series = TimeSeriesOutput::kNone;
  for (int k = 0; k < 6; ++k) {
    const tailsim::testing::RandomRobotCase c = tailsim::testing::randomRobotCase(31, k);
    MujocoSettings s;
    s.body_height_m = c.robot.quadruped.com_height_m;
    const RunResult r = simulateMujoco(c.robot, c.trajectory, s, Effects{}, o);
    ASSERT_TRUE(r.summary.ok) << k << ": " << r.summary.error;
    EXPECT_LE(r.summary.extra.at("airborne_fraction"), 0.01) << k << ": " << tailsim::testing::describe(c);
    EXPECT_LT(r.summary.extra.at("peak_normal_force_over_mg"), 3.0) << k << ": " << tailsim::testing::describe(c);
  }
}

// The step schedule (docs/mujoco-model.md "Step schedule"): once the tail has stopped and the
// body rests, the run steps at rest_step_factor * timestep_s. Nothing moves there, so every output
// is what the fine step gives, on the same rows, for far fewer steps; where the coarse step does
// not divide the output spacing, the schedule stays fine.
TEST(MujocoSimulation, ARestingBodyStepsCoarserWithTheSameAnswer) {
  const RobotParams p = paperRobot(1);
  const TailTrajectory traj = sameForAllJoints(1, fig6(-90));
  MujocoSettings fine;
  fine.uncertainty = false;
  fine.rest_step_factor = 1;
  MujocoSettings coarse = fine;
  coarse.rest_step_factor = 5;
  const RunResult a = simulateMujoco(p, traj, fine, Effects{}, {});
  const RunResult b = simulateMujoco(p, traj, coarse, Effects{}, {});
  expectCleanRun(a);
  expectCleanRun(b);
  EXPECT_TRUE(b.summary.at_rest);
  // The stroke ends at 0.25 s, the run at 0.75 s: most of the last 0.5 s rests at 5 x the step.
  EXPECT_LT(b.summary.solver_steps, 0.7 * a.summary.solver_steps)
      << a.summary.solver_steps << " -> " << b.summary.solver_steps;
  EXPECT_NEAR(b.summary.phi_net_deg, a.summary.phi_net_deg, 1e-6);
  // Figures over the run's steps weigh a coarse step as the steps it stands for.
  for (const char* k : {"tracking_rms_deg_j1", "airborne_fraction", "longest_all_feet_off_s"})
    EXPECT_NEAR(b.summary.extra.at(k), a.summary.extra.at(k), 1e-3 * std::abs(a.summary.extra.at(k)) + 1e-12) << k;
  expectSameSeries(a.series, b.series, 1e-4);
  // A spacing of 0.3 ms is no multiple of the 0.5 ms rest step: every step stays at timestep_s.
  OutputSettings odd;
  odd.sample_dt_s = 3e-4;
  const RunResult c = simulateMujoco(p, traj, fine, Effects{}, odd);
  const RunResult d = simulateMujoco(p, traj, coarse, Effects{}, odd);
  EXPECT_EQ(c.summary.solver_steps, d.summary.solver_steps);
  EXPECT_EQ(c.summary.phi_net_deg, d.summary.phi_net_deg);
}

// The check run at twice the step (its own pre-roll) stops once the body rests after the stroke:
// it costs the stroke's steps at 2 h, not the whole run's again.
TEST(MujocoSimulation, TheCheckRunStopsOnceTheBodyRests) {
  MujocoSettings s;
  OutputSettings o;
  o.time_series = TimeSeriesOutput::kNone;
  const RunResult r = simulateMujoco(paperRobot(1), sameForAllJoints(1, fig6(-90)), s, Effects{}, o);
  ASSERT_TRUE(r.summary.ok) << r.summary.error;
  const double run_s = 0.25 + o.settle_s;  // the stroke's end + settle_s
  const double check_steps = r.summary.extra.at("uncertainty_solver_steps");
  EXPECT_LT(check_steps, 0.7 * run_s / (2.0 * s.timestep_s)) << check_steps;
  EXPECT_GT(check_steps, 0.25 / (2.0 * s.timestep_s));  // at least the stroke
  EXPECT_NEAR(r.summary.extra.at("phi_net_check_deg"), r.summary.phi_net_deg,
              r.summary.extra.at("phi_net_uncertainty_deg"));
}
