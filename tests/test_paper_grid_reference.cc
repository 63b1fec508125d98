// The analytic model's final state on the whole paper grid (every simulated paper case), checked against
// an independent algorithm: Moreau-type time stepping of the same equations (paper coupling,
// Eqs. 9, 13-16), where each step projects the velocity onto the friction cone in closed form
// (stick if the step's impulse stays inside the static limit, else slide with mu_d against the
// trial velocity). It has no events, no dense output and no root finding, so it cannot share the
// event-driven solver's bugs (a breakaway missed between two samples, a DOF hidden behind
// another's switch). First order in h; two step sizes give a Richardson estimate and its error.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "models/analytic/analytic_simulation.h"
#include "models/planar/foot_loads.h"
#include "models/planar/system_loads.h"
#include "models/planar/tail_dynamics.h"
#include "experiments/experiment_loader.h"

using namespace tailsim;

namespace {

struct Final {
  double phi_deg = 0, x = 0, y = 0;
};

Final timeStep(const ExperimentCase& c, double h) {
  const RobotParams& r = c.robot;
  const TailTrajectory tr = c.trajectory();
  const double W = r.systemMass() * r.gravity_mps2;
  const double mu_b = breakawayCoefficient(r.friction), mu_d = r.friction.mu_d;
  const long n = std::lround(c.simDuration() / h);
  std::vector<JointState> js;
  SystemLoads L;
  LoadScratch scratch;
  double phi = 0, w = 0;
  Vec2 p = Vec2::Zero(), v = Vec2::Zero();
  for (long k = 1; k <= n; ++k) {
    tr.evaluate(k * h, js);
    systemLoads(r, js, false, L, scratch);
    const double LF = footLoads(r.quadruped, L.p_QC).L_F;
    // Rotation, Eq. (16): friction impulse limit h mu W L_F.
    const double w_trial = w + h * L.MzT / L.Izz_kgm2;
    if (std::abs(w_trial) * L.Izz_kgm2 <= h * mu_b * W * LF) w = 0;
    else w = w_trial - std::copysign(h * mu_d * W * LF / L.Izz_kgm2, w_trial);
    phi += h * w;
    // Translation, Eqs. (14)-(15), world frame.
    const Vec2 v_trial = v + h * rotate(phi, L.F_T_Q) / L.mass_kg;
    const double s = v_trial.norm();
    if (s * L.mass_kg <= h * mu_b * W) v = Vec2::Zero();
    else v = v_trial * (1.0 - h * mu_d * W / (L.mass_kg * s));
    p += h * v;
  }
  return {phi * 180 / M_PI, p.x(), p.y()};
}

// Every simulated case of the paper suite that uses the paper's equations (paper coupling,
// stiction, distributed foot loads), i.e. all of Figs. 6, 7, 9, 11-14 and the friction swap.
std::vector<ExperimentCase> paperGrid() {
  std::vector<ExperimentCase> out;
  for (const Experiment& e : loadExperimentSuite(TAILSIM_SOURCE_DIR "/configs/paper/all.yaml"))
    for (const ExperimentCase& c : e.cases)
      if (c.kind == CaseKind::kSimulate && c.analytic.coupling == Coupling::kPaper &&
          c.effects.friction == FrictionLaw::kStiction && c.effects.foot_loads == FootLoadModel::kDistributed &&
          c.effects.translation && c.effects.gravity)
        out.push_back(c);
  return out;
}

}  // namespace

TEST(PaperGridReference, FinalPositionAndYawMatchTimeStepping) {
  const std::vector<ExperimentCase> cases = paperGrid();
  ASSERT_GE(cases.size(), 125u);  // 130 when written
  const double h = 2e-5;
  int within = 0, moved = 0;
  double worst_rel = 0, worst_phi = 0;
  for (const ExperimentCase& c : cases) {
    SCOPED_TRACE(c.experiment + "/" + c.name);
    const RunResult res = simulateAnalytic(c.robot, c.trajectory(), c.analytic, c.effects, c.output);
    ASSERT_TRUE(res.summary.ok) << res.summary.error;
    const Final a = timeStep(c, h), b = timeStep(c, h / 2);
    // Richardson (first order): 2 b - a, with |b - a| as the reference's own error.
    const Final ref{2 * b.phi_deg - a.phi_deg, 2 * b.x - a.x, 2 * b.y - a.y};
    const double ref_err = std::hypot(b.x - a.x, b.y - a.y);
    const double x = res.summary.extra.at("final_x_m"), y = res.summary.extra.at("final_y_m");
    const double disp = std::hypot(ref.x, ref.y), err = std::hypot(x - ref.x, y - ref.y);
    const double tol = std::max(0.01 * disp, 1e-3);
    EXPECT_LT(ref_err, 0.2 * tol) << "reference not converged";
    EXPECT_LT(err, tol) << "x, y = " << x << ", " << y << " m; reference " << ref.x << ", " << ref.y;
    // Also the last CSV row: the time series ends where the summary says.
    EXPECT_NEAR(res.series.values("x_m").back(), x, 1e-12);
    EXPECT_NEAR(res.series.values("y_m").back(), y, 1e-12);
    EXPECT_NEAR(res.summary.phi_net_deg, ref.phi_deg, std::max(0.01 * std::abs(ref.phi_deg), 0.01));
    EXPECT_EQ(res.summary.extra.at("final_speed_mps"), 0.0);
    EXPECT_EQ(res.summary.extra.at("final_phidot_dps"), 0.0);
    within += err < tol;
    moved += disp > 1e-3;
    worst_rel = std::max(worst_rel, err / std::max(disp, 1e-3));
    worst_phi = std::max(worst_phi, std::abs(res.summary.phi_net_deg - ref.phi_deg));
  }
  std::printf("paper grid: %d of %zu cases within max(1 %% of displacement, 1 mm) of the time-stepping reference "
              "(%d moved > 1 mm); worst error %.3g of max(displacement, 1 mm); worst phi_net difference %.3g deg\n",
              within, cases.size(), moved, worst_rel, worst_phi);
}

// The fixed-step solver on the same grid: every run ends at rest (no creep after the tail stops),
// and phi_net does not depend on how long the run continues after it.
TEST(PaperGridReference, FixedStepSolverComesToRest) {
  int cases = 0;
  double worst_vs_adaptive = 0;
  for (const ExperimentCase& c : paperGrid()) {
    SCOPED_TRACE(c.experiment + "/" + c.name);
    AnalyticSettings fixed = c.analytic;
    fixed.solver = AnalyticSolver::kFixed;
    const RunResult adaptive = simulateAnalytic(c.robot, c.trajectory(), c.analytic, c.effects, c.output);
    double phi_first = NAN;
    for (double duration : {c.simDuration(), 5.0}) {
      OutputSettings o = c.output;
      o.duration_s = duration;
      o.sample_dt_s = 0.01;
      const RunResult r = simulateAnalytic(c.robot, c.trajectory(), fixed, c.effects, o);
      ASSERT_TRUE(r.summary.ok) << r.summary.error;
      EXPECT_EQ(r.summary.extra.at("final_phidot_dps"), 0.0) << "duration " << duration;
      EXPECT_EQ(r.summary.extra.at("final_speed_mps"), 0.0) << "duration " << duration;
      if (std::isnan(phi_first)) phi_first = r.summary.phi_net_deg;
      else EXPECT_EQ(r.summary.phi_net_deg, phi_first) << "phi_net changes with the run's length";
    }
    worst_vs_adaptive = std::max(worst_vs_adaptive, std::abs(phi_first - adaptive.summary.phi_net_deg));
    ++cases;
  }
  std::printf("fixed-step RK4 (1e-4 s): %d cases at rest, phi_net within %.3g deg of the adaptive solver\n", cases,
              worst_vs_adaptive);
  EXPECT_LT(worst_vs_adaptive, 0.05);
}
