#include "experiments/accuracy_study.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>

#include "analytic_model/analytic_simulation.h"
#include "mujoco_model/mujoco_simulation.h"
#include "results/atomic_file.h"

namespace tailsim {
namespace {

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

double rmsDiff(const TimeSeries& a, const TimeSeries& b) {
  if (!a.has("phi_deg") || !b.has("phi_deg")) return NAN;
  const auto& x = a.values("phi_deg");
  const auto& y = b.values("phi_deg");
  const size_t n = std::min(x.size(), y.size());
  if (n == 0) return NAN;
  double s = 0;
  for (size_t i = 0; i < n; ++i) s += (x[i] - y[i]) * (x[i] - y[i]);
  return std::sqrt(s / n);
}

// Runs `run` `repeats` times (once if it is slow) and keeps the last result, median wall time.
RunResult timed(const std::function<RunResult()>& run, int repeats, double& wall) {
  std::vector<double> walls;
  RunResult r = run();
  walls.push_back(r.summary.wall_time_s);
  for (int k = 1; k < repeats && r.summary.wall_time_s < 0.5; ++k) {
    r = run();
    walls.push_back(r.summary.wall_time_s);
  }
  std::sort(walls.begin(), walls.end());
  wall = walls[walls.size() / 2];
  return r;
}

AccuracyRow makeRow(const std::string& model, const std::string& family, const std::string& setting, double value,
                    bool is_default, const RunResult& r, double wall, const RunResult& ref) {
  AccuracyRow row;
  row.model = model;
  row.family = family;
  row.setting = setting;
  row.value = value;
  row.is_default = is_default;
  row.ok = r.summary.ok && std::isfinite(r.summary.phi_net_deg);
  row.failure = r.summary.ok ? (row.ok ? "" : "non-finite phi_net") : r.summary.error;
  row.phi_net_deg = r.summary.phi_net_deg;
  row.err_phi_net_deg = std::abs(r.summary.phi_net_deg - ref.summary.phi_net_deg);
  row.rms_err_phi_deg = rmsDiff(r.series, ref.series);
  row.wall_s = wall;
  row.steps = r.summary.solver_steps;
  return row;
}

}  // namespace

std::vector<AccuracyStudy> runAccuracyStudy(const Experiment& e, const AccuracyOptions& opt) {
  std::vector<AccuracyStudy> out;
  for (const ExperimentCase& c : e.cases) {
    if (c.kind != "simulate") continue;
    AccuracyStudy st;
    st.case_name = e.name + (c.name == "base" ? "" : ":" + c.name);
    const TailTrajectory traj = c.trajectory();
    const AnalyticSettings defaults_a;
    const MujocoSettings defaults_m;

    // --- analytic: adaptive tolerances and fixed RK4 steps against rel_tol = 1e-12 --------------
    auto analytic = [&](const AnalyticSettings& s) { return simulateAnalytic(c.robot, traj, s, c.effects, c.output); };
    AnalyticSettings ref_s = c.analytic;
    ref_s.solver = "adaptive";
    ref_s.rel_tol = 1e-12;
    ref_s.abs_tol = 1e-14;
    const RunResult ref_a = analytic(ref_s);
    AnalyticSettings coarser = ref_s;
    coarser.rel_tol = 1e-11;
    coarser.abs_tol = 1e-13;
    st.analytic = {"adaptive rel_tol=1e-12 abs_tol=1e-14", ref_a.summary.phi_net_deg,
                   std::abs(analytic(coarser).summary.phi_net_deg - ref_a.summary.phi_net_deg)};
    const std::vector<double> tols = opt.quick ? std::vector<double>{1e-4, 1e-8}
                                               : std::vector<double>{1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11};
    for (double tol : tols) {
      AnalyticSettings s = c.analytic;
      s.solver = "adaptive";
      s.rel_tol = tol;
      s.abs_tol = tol * 1e-2;
      double wall = 0;
      const RunResult r = timed([&] { return analytic(s); }, opt.repeats, wall);
      const bool dflt = tol == defaults_a.rel_tol && s.abs_tol == defaults_a.abs_tol;
      st.rows.push_back(makeRow("analytic", "adaptive", "rel_tol=" + num(tol), tol, dflt, r, wall, ref_a));
    }
    const std::vector<double> hs = opt.quick ? std::vector<double>{1e-3}
                                             : std::vector<double>{1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5};
    for (double h : hs) {
      AnalyticSettings s = c.analytic;
      s.solver = "fixed";
      s.fixed_dt_s = h;
      double wall = 0;
      const RunResult r = timed([&] { return analytic(s); }, opt.repeats, wall);
      st.rows.push_back(makeRow("analytic", "fixed RK4", "fixed_dt_s=" + num(h), h, false, r, wall, ref_a));
    }

    // --- MuJoCo: timestep x integrator, then one family at a time around the defaults ------------
    if (opt.mujoco) {
      auto mujoco = [&](const MujocoSettings& s) {
        try {
          return simulateMujoco(c.robot, traj, s, c.effects, c.output);
        } catch (const std::exception& ex) {
          RunResult r;
          r.summary.ok = false;
          r.summary.error = ex.what();
          return r;
        }
      };
      const double h_ref = opt.quick ? 1e-4 : 2.5e-5;
      MujocoSettings ref_m = c.mujoco;
      ref_m.integrator = "implicit";
      ref_m.timestep_s = h_ref;
      const RunResult ref_mj = mujoco(ref_m);
      MujocoSettings coarse_m = ref_m;
      coarse_m.timestep_s = 2 * h_ref;
      const RunResult coarse_mj = mujoco(coarse_m);
      // First order in h: the reference's own error is about |phi(h) - phi(2h)|.
      st.mujoco = {"implicit timestep_s=" + num(h_ref), ref_mj.summary.phi_net_deg,
                   std::abs(coarse_mj.summary.phi_net_deg - ref_mj.summary.phi_net_deg)};
      auto add = [&](const std::string& family, const std::string& setting, double value, const MujocoSettings& s) {
        double wall = 0;
        const RunResult r = timed([&] { return mujoco(s); }, opt.repeats, wall);
        const bool dflt = s.timestep_s == defaults_m.timestep_s && s.integrator == defaults_m.integrator &&
                          s.solver == defaults_m.solver && s.iterations == defaults_m.iterations &&
                          s.tolerance == defaults_m.tolerance && s.cone == defaults_m.cone &&
                          s.noslip_iterations == defaults_m.noslip_iterations;
        st.rows.push_back(makeRow("mujoco", family, setting, value, dflt, r, wall, ref_mj));
      };
      const std::vector<double> steps = opt.quick ? std::vector<double>{5e-4, 2e-4}
                                                  : std::vector<double>{1e-3, 5e-4, 2e-4, 1e-4, 5e-5};
      for (const char* integ : {"implicit", "Euler", "RK4"})
        for (double h : steps) {
          MujocoSettings s = c.mujoco;
          s.integrator = integ;
          s.timestep_s = h;
          add(std::string("timestep/") + integ, std::string("integrator=") + integ + " timestep_s=" + num(h), h, s);
        }
      if (!opt.quick) {
        for (const char* solver : {"Newton", "CG", "PGS"}) {
          MujocoSettings s = c.mujoco;
          s.solver = solver;
          add("solver", std::string("solver=") + solver, 0, s);
        }
        for (auto [it, tol] : {std::pair<int, double>{100, 1e-10}, {20, 1e-6}, {5, 1e-3}}) {
          MujocoSettings s = c.mujoco;
          s.iterations = it;
          s.tolerance = tol;
          add("iterations", "iterations=" + std::to_string(it) + " tolerance=" + num(tol), tol, s);
        }
        for (const char* cone : {"elliptic", "pyramidal"}) {
          MujocoSettings s = c.mujoco;
          s.cone = cone;
          add("cone", std::string("cone=") + cone, 0, s);
        }
        for (int ns : {0, 10}) {
          MujocoSettings s = c.mujoco;
          s.noslip_iterations = ns;
          add("noslip", "noslip_iterations=" + std::to_string(ns), ns, s);
        }
      }
    }
    out.push_back(std::move(st));
  }
  return out;
}

void writeAccuracyTables(const std::vector<AccuracyStudy>& studies, const std::string& dir) {
  std::ostringstream csv, md;
  csv << "case,model,family,setting,value,is_default,ok,phi_net_deg,err_phi_net_deg,rms_err_phi_deg,wall_s,steps,"
         "failure\n";
  md << "# Work-precision study\n\nError of phi_net and RMS error of phi(t) on the output grid against a converged "
        "reference of the same model; wall time is the median of repeated runs (model time only). "
        "**Bold** rows are tailsim's defaults.\n";
  char b[512];
  for (const AccuracyStudy& st : studies) {
    md << "\n## " << st.case_name << "\n\n";
    std::snprintf(b, sizeof b,
                  "References: analytic %s: phi_net = %.9f deg (differs from rel_tol=1e-11 by %.1e deg); "
                  "MuJoCo %s: phi_net = %.6f deg (differs from twice the step by %.1e deg).\n\n",
                  st.analytic.setting.c_str(), st.analytic.phi_net_deg, st.analytic.uncertainty_deg,
                  st.mujoco.setting.c_str(), st.mujoco.phi_net_deg, st.mujoco.uncertainty_deg);
    md << b;
    md << "| model | family | setting | phi_net [deg] | phi_net error [deg] | RMS phi error [deg] | wall [ms] | steps | "
          "status |\n|---|---|---|---|---|---|---|---|---|\n";
    for (const AccuracyRow& r : st.rows) {
      std::string failure = r.failure;
      std::replace(failure.begin(), failure.end(), ',', ';');
      std::replace(failure.begin(), failure.end(), '\n', ' ');
      std::snprintf(b, sizeof b, "%s,%s,%s,%s,%g,%d,%d,%.12g,%.6g,%.6g,%.6g,%ld,%s\n", st.case_name.c_str(),
                    r.model.c_str(), r.family.c_str(), r.setting.c_str(), r.value, r.is_default, r.ok, r.phi_net_deg,
                    r.err_phi_net_deg, r.rms_err_phi_deg, r.wall_s, r.steps, failure.c_str());
      csv << b;
      const char* bo = r.is_default ? "**" : "";
      if (r.ok)
        std::snprintf(b, sizeof b, "| %s%s%s | %s | %s%s%s | %.6f | %.2e | %.2e | %.3f | %ld | ok |\n", bo,
                      r.model.c_str(), bo, r.family.c_str(), bo, r.setting.c_str(), bo, r.phi_net_deg,
                      r.err_phi_net_deg, r.rms_err_phi_deg, 1e3 * r.wall_s, r.steps);
      else
        std::snprintf(b, sizeof b, "| %s | %s | %s | - | - | - | %.3f | %ld | FAILED: %.120s |\n", r.model.c_str(),
                      r.family.c_str(), r.setting.c_str(), 1e3 * r.wall_s, r.steps, failure.c_str());
      md << b;
    }
  }
  writeFileAtomic(dir + "/accuracy.csv", csv.str());
  writeFileAtomic(dir + "/accuracy.md", md.str());
}

}  // namespace tailsim
