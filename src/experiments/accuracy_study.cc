#include "experiments/accuracy_study.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>

#include "models/analytic/analytic_simulation.h"
#include "results/columns.h"
#include "models/mujoco/mujoco_simulation.h"
#include "common/atomic_file.h"
#include "common/number_text.h"

namespace tailsim {
namespace {

double rmsDiff(const TimeSeries& a, const TimeSeries& b) {
  if (!a.has(col::kPhi) || !b.has(col::kPhi)) return NAN;
  const auto& x = a.values(col::kPhi);
  const auto& y = b.values(col::kPhi);
  const size_t n = std::min(x.size(), y.size());
  if (n == 0) return NAN;
  double s = 0;
  for (size_t i = 0; i < n; ++i) s += (x[i] - y[i]) * (x[i] - y[i]);
  return std::sqrt(s / n);
}

// Runs `run(k)`, k = 0..repeats-1 (once if it is slow), median wall time. `mean_phi` averages
// phi_net over the runs that succeeded; the result of run(0) is returned (or the first failure).
RunResult timed(const std::function<RunResult(int)>& run, int repeats, double& wall, double& mean_phi, int& runs) {
  std::vector<double> walls;
  RunResult first = run(0);
  walls.push_back(first.summary.wall_time_s);
  double sum = first.summary.phi_net_deg;
  runs = 1;
  for (int k = 1; k < repeats && first.summary.ok && first.summary.wall_time_s < 0.5; ++k) {
    const RunResult r = run(k);
    walls.push_back(r.summary.wall_time_s);
    if (!r.summary.ok) return r;
    sum += r.summary.phi_net_deg;
    ++runs;
  }
  std::sort(walls.begin(), walls.end());
  wall = walls[walls.size() / 2];
  mean_phi = sum / runs;
  return first;
}

AccuracyRow makeRow(const std::string& model, const std::string& family, const std::string& setting, double value,
                    bool is_default, const RunResult& r, double wall, double mean_phi, int runs, const RunResult& ref) {
  AccuracyRow row;
  row.model = model;
  row.family = family;
  row.setting = setting;
  row.value = value;
  row.is_default = is_default;
  row.ok = r.summary.ok && std::isfinite(r.summary.phi_net_deg);
  row.failure = r.summary.ok ? (row.ok ? "" : "non-finite phi_net") : r.summary.error;
  row.phi_net_deg = mean_phi;
  row.runs = runs;
  row.err_phi_net_deg = std::abs(mean_phi - ref.summary.phi_net_deg);
  row.rms_err_phi_deg = rmsDiff(r.series, ref.series);
  row.wall_s = wall;
  row.steps = r.summary.solver_steps;
  return row;
}

// The analytic model's study: adaptive tolerances and fixed RK4 steps against rel_tol = 1e-12.
void studyAnalytic(const ExperimentCase& c, const TailTrajectory& traj, const AccuracyOptions& opt, AccuracyStudy& st) {
  const AnalyticSettings defaults_a;
  char b[512];
  auto analytic = [&](const AnalyticSettings& s) { return simulateAnalytic(c.robot, traj, s, c.effects, c.output); };
  auto adaptive = [&](double tol) {
    AnalyticSettings s = c.analytic;
    s.solver = AnalyticSolver::kAdaptive;
    s.rel_tol = tol;
    s.abs_tol = tol * 1e-2;
    return s;
  };
  const RunResult ref_a = analytic(adaptive(1e-12));
  st.analytic.present = true;
  st.analytic.setting = "adaptive rel_tol=1e-12 abs_tol=1e-14";
  st.analytic.phi_net_deg = ref_a.summary.phi_net_deg;
  {
    // Successive refinements 1e-9 .. 1e-12: their differences shrink towards the reference.
    std::string line = "analytic adaptive, phi_net at rel_tol 1e-9, 1e-10, 1e-11, 1e-12:";
    std::vector<double> seq;
    for (double tol : {1e-9, 1e-10, 1e-11}) seq.push_back(analytic(adaptive(tol)).summary.phi_net_deg);
    seq.push_back(ref_a.summary.phi_net_deg);
    for (double v : seq) {
      std::snprintf(b, sizeof b, " %.10f", v);
      line += b;
    }
    line += " deg; successive differences";
    for (size_t i = 1; i < seq.size(); ++i) {
      std::snprintf(b, sizeof b, " %.1e", std::abs(seq[i] - seq[i - 1]));
      line += b;
    }
    st.analytic.uncertainty_deg = std::abs(seq[3] - seq[2]);
    std::snprintf(b, sizeof b, " deg. Reference error estimate: %.0e deg (|1e-12 - 1e-11|).", st.analytic.uncertainty_deg);
    st.analytic.evidence.push_back(line + b);
  }
  {
    AnalyticSettings ex = adaptive(1e-12);
    ex.coupling = Coupling::kExact;
    st.analytic_exact_deg = analytic(ex).summary.phi_net_deg;
  }
  const std::vector<double> tols = opt.quick ? std::vector<double>{1e-4, 1e-8}
                                             : std::vector<double>{1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11};
  for (double tol : tols) {
    const AnalyticSettings s = adaptive(tol);
    double wall = 0, mean = 0;
    int runs = 0;
    const RunResult r = timed([&](int) { return analytic(s); }, opt.repeats, wall, mean, runs);
    const bool dflt = tol == defaults_a.rel_tol && s.abs_tol == defaults_a.abs_tol;
    st.rows.push_back(makeRow("analytic", "adaptive", "rel_tol=" + formatG(tol), tol, dflt, r, wall, mean, 1, ref_a));
  }
  const std::vector<double> hs = opt.quick ? std::vector<double>{1e-3}
                                           : std::vector<double>{1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6};
  for (double h : hs) {
    AnalyticSettings s = c.analytic;
    s.solver = AnalyticSolver::kFixed;
    s.fixed_dt_s = h;
    double wall = 0, mean = 0;
    int runs = 0;
    const RunResult r = timed([&](int) { return analytic(s); }, opt.repeats, wall, mean, runs);
    st.rows.push_back(makeRow("analytic", "fixed RK4", "fixed_dt_s=" + formatG(h), h, false, r, wall, mean, 1, ref_a));
  }
}

// phi_net over an ensemble of MuJoCo runs: mean, sample standard deviation, the runs that
// succeeded, the first failure.
struct Ensemble {
  double mean = NAN, sd = NAN;
  int ok = 0;
  std::string error;
};

// MuJoCo runs of one case: a failure to build or run is a failed RunResult. Contact chatter makes
// MuJoCo's phi_net sensitive to microscopic changes (docs/mujoco-model.md): an ensemble over
// dT_s + k us, k = 0..K-1, measures that sensitivity and averages it out.
struct MujocoRuns {
  const ExperimentCase& c;
  const TailTrajectory& traj;
  int K;      // ensemble size
  double wn;  // the case's servo w_n = servo_wn_dt / timestep_s  [rad/s]

  RunResult run(const MujocoSettings& s, const TailTrajectory& tr) const {
    try {
      return simulateMujoco(c.robot, tr, s, c.effects, c.output);
    } catch (const std::exception& ex) {
      RunResult r;
      r.summary.ok = false;
      r.summary.error = ex.what();
      return r;
    }
  }
  // The servo gains follow w_n = servo_wn_dt / timestep_s; changing the step alone would change
  // the model (stiffer servos at smaller steps). Every timestep variant keeps the case's w_n.
  MujocoSettings withStep(MujocoSettings s, double h) const {
    s.timestep_s = h;
    if (s.kp == 0.0) s.servo_wn_dt = wn * h;
    return s;
  }
  // The trajectory with every joint's dT_s + k us.
  TailTrajectory perturbed(int k) const {
    TailTrajectory t;
    for (const SplitCycleProfile& j : traj.joints) {
      if (j.isSpline()) {
        SplineParams p = j.spline();
        p.dT_s += 1e-6 * k;
        t.joints.emplace_back(p);
      } else {
        SplitCycleParams p = j.params();
        p.dT_s += 1e-6 * k;
        t.joints.emplace_back(p);
      }
    }
    return t;
  }
  Ensemble ensemble(const MujocoSettings& s) const {
    Ensemble en;
    std::vector<double> v;
    for (int k = 0; k < K; ++k) {
      const RunResult r = run(s, perturbed(k));
      if (r.summary.ok && std::isfinite(r.summary.phi_net_deg)) v.push_back(r.summary.phi_net_deg);
      else if (en.error.empty()) en.error = r.summary.error;
    }
    en.ok = static_cast<int>(v.size());
    if (v.empty()) return en;
    double sum = 0, sq = 0;
    for (double x : v) sum += x;
    en.mean = sum / v.size();
    for (double x : v) sq += (x - en.mean) * (x - en.mean);
    en.sd = v.size() > 1 ? std::sqrt(sq / (v.size() - 1)) : 0.0;
    return en;
  }
};

// MuJoCo's reference: the implicit integrator with a tight solver at a small step (w_n kept), an
// ensemble there and at twice the step, and the evidence lines; returns the reference settings.
MujocoSettings mujocoReference(const MujocoRuns& mj, const AccuracyOptions& opt, AccuracyStudy& st) {
  const int K = mj.K;
  char b[512];
  const double h_ref = opt.quick ? 1e-4 : 2.5e-5;
  MujocoSettings ref_m = mj.withStep(mj.c.mujoco, h_ref);
  ref_m.integrator = MujocoIntegrator::kImplicit;
  ref_m.iterations = std::max(ref_m.iterations, 100);
  ref_m.tolerance = std::min(ref_m.tolerance, 1e-10);
  const Ensemble e_ref = mj.ensemble(ref_m);
  const Ensemble e_2h = mj.ensemble(mj.withStep(ref_m, 2 * h_ref));
  const Ensemble e_def = mj.ensemble(mj.c.mujoco);
  st.mujoco.present = e_ref.ok > 0;
  st.mujoco.setting = "implicit timestep_s=" + formatG(h_ref) + " (w_n kept), mean of " + std::to_string(K) +
                      " runs with dT_s + 0.." + std::to_string(K - 1) + " us";
  st.mujoco.phi_net_deg = e_ref.mean;
  st.mujoco.noise_deg = e_ref.sd;
  st.mujoco.noise_default_deg = e_def.sd;
  const double se = std::sqrt((e_ref.sd * e_ref.sd + e_2h.sd * e_2h.sd) / K);
  st.mujoco.uncertainty_deg = std::max(std::abs(e_ref.mean - e_2h.mean), se);
  std::snprintf(b, sizeof b,
                "MuJoCo ensemble means (implicit, tight solver, servo w_n = %.0f rad/s kept): timestep %g s: %.4f "
                "+- %.4f deg; %g s: %.4f +- %.4f deg (+- = standard error); difference %.4f deg against a combined "
                "standard error of %.4f deg. Reference error estimate: %.3f deg.",
                mj.wn, 2 * h_ref, e_2h.mean, e_2h.sd / std::sqrt(K), h_ref, e_ref.mean, e_ref.sd / std::sqrt(K),
                std::abs(e_ref.mean - e_2h.mean), se, st.mujoco.uncertainty_deg);
  st.mujoco.evidence.push_back(b);
  std::snprintf(b, sizeof b,
                "MuJoCo sensitivity: dT_s changed by 1..%d us (a relative %.0e) moves phi_net with a standard "
                "deviation of %.4f deg at the reference step and %.4f deg (%.2f %%) at tailsim's defaults (mean "
                "%.4f deg). Single-run errors below this are contact-chatter noise, not step error.",
                K - 1, 1e-6 * (K - 1) / mj.traj.joints.front().params().dT_s, e_ref.sd, e_def.sd,
                100 * e_def.sd / std::abs(e_def.mean), e_def.mean);
  st.mujoco.evidence.push_back(b);
  if (!e_ref.error.empty()) st.mujoco.evidence.push_back("Reference run failures: " + e_ref.error);
  return ref_m;
}

// MuJoCo's rows: timestep x integrator, then one family at a time around the defaults, each
// against the reference ensemble's mean.
void studyMujoco(const ExperimentCase& c, const TailTrajectory& traj, const AccuracyOptions& opt, AccuracyStudy& st) {
  const MujocoSettings defaults_m;
  const MujocoRuns mj{c, traj, opt.quick ? 3 : 6, c.mujoco.servo_wn_dt / c.mujoco.timestep_s};
  const MujocoSettings ref_m = mujocoReference(mj, opt, st);
  RunResult ref_mj;  // makeRow compares against the ensemble mean
  ref_mj.summary.phi_net_deg = st.mujoco.phi_net_deg;
  ref_mj.series = mj.run(ref_m, traj).series;
  auto add = [&](const std::string& family, const std::string& setting, double value, const MujocoSettings& s) {
    // The repeats double as a small ensemble (dT_s + k us): phi_net is their mean.
    double wall = 0, mean = 0;
    int runs = 0;
    const RunResult r = timed([&](int k) { return mj.run(s, mj.perturbed(k)); }, opt.repeats, wall, mean, runs);
    const bool dflt = s.timestep_s == defaults_m.timestep_s && s.integrator == defaults_m.integrator &&
                      s.solver == defaults_m.solver && s.iterations == defaults_m.iterations &&
                      s.tolerance == defaults_m.tolerance && s.cone == defaults_m.cone &&
                      s.noslip_iterations == defaults_m.noslip_iterations && s.servo_wn_dt == defaults_m.servo_wn_dt;
    st.rows.push_back(makeRow("mujoco", family, setting, value, dflt, r, wall, mean, runs, ref_mj));
  };
  const std::vector<double> steps = opt.quick ? std::vector<double>{5e-4, 2e-4}
                                              : std::vector<double>{1e-3, 5e-4, 2e-4, 1e-4, 5e-5};
  for (const MujocoIntegrator in : {MujocoIntegrator::kImplicit, MujocoIntegrator::kEuler, MujocoIntegrator::kRK4})
    for (double h : steps) {
      const std::string integ = name(in);
      MujocoSettings s = mj.withStep(c.mujoco, h);
      s.integrator = in;
      add(std::string("timestep/") + integ, std::string("integrator=") + integ + " timestep_s=" + formatG(h), h, s);
    }
  if (opt.quick) return;
  for (const MujocoSolver so : {MujocoSolver::kNewton, MujocoSolver::kCG, MujocoSolver::kPGS}) {
    MujocoSettings s = c.mujoco;
    s.solver = so;
    add("solver", std::string("solver=") + name(so), 0, s);
  }
  for (auto [it, tol] : {std::pair<int, double>{100, 1e-10}, {20, 1e-6}, {5, 1e-3}}) {
    MujocoSettings s = c.mujoco;
    s.iterations = it;
    s.tolerance = tol;
    add("iterations", "iterations=" + std::to_string(it) + " tolerance=" + formatG(tol), tol, s);
  }
  for (const MujocoCone co : {MujocoCone::kElliptic, MujocoCone::kPyramidal}) {
    MujocoSettings s = c.mujoco;
    s.cone = co;
    add("cone", std::string("cone=") + name(co), 0, s);
  }
  for (int ns : {0, 10}) {
    MujocoSettings s = c.mujoco;
    s.noslip_iterations = ns;
    add("noslip", "noslip_iterations=" + std::to_string(ns), ns, s);
  }
}

}  // namespace

std::vector<AccuracyStudy> runAccuracyStudy(const Experiment& e, const AccuracyOptions& opt) {
  std::vector<AccuracyStudy> out;
  for (const ExperimentCase& c : e.cases) {
    if (c.kind != CaseKind::kSimulate) continue;
    AccuracyStudy st;
    st.case_name = e.name + (c.name == "base" ? "" : ":" + c.name);
    const TailTrajectory traj = c.trajectory();
    studyAnalytic(c, traj, opt, st);
    if (opt.mujoco) studyMujoco(c, traj, opt, st);
    out.push_back(std::move(st));
  }
  return out;
}

namespace {
// A table an earlier tailsim wrote before folders had a manifest: recognised by its first line.
EarlierOwnFile earlierAccuracyTable(const std::string& name) {
  const std::string head = name == "accuracy.csv" ? "case,model,family,setting,value,is_default," : "# Work-precision study\n";
  return [head](const std::string& text) { return text.compare(0, head.size(), head) == 0; };
}
}  // namespace

void writeAccuracyTables(const std::vector<AccuracyStudy>& studies, const std::string& dir) {
  std::ostringstream csv, md;
  csv << "case,model,family,setting,value,is_default,ok,phi_net_deg,err_phi_net_deg,rms_err_phi_deg,wall_s,steps,"
         "runs,failure\n";
  md << "# Work-precision study\n\nError of phi_net and RMS error of phi(t) on the output grid against a converged "
        "reference of the same model; wall time is the median of repeated runs (model time only). "
        "**Bold** rows are tailsim's defaults.\n";
  char b[512];
  for (const AccuracyStudy& st : studies) {
    md << "\n## " << st.case_name << "\n\n";
    std::snprintf(b, sizeof b, "- Analytic reference: %s: phi_net = %.9f deg.\n", st.analytic.setting.c_str(),
                  st.analytic.phi_net_deg);
    md << b;
    for (const std::string& line : st.analytic.evidence) md << "- " << line << "\n";
    if (st.mujoco.present) {
      std::snprintf(b, sizeof b, "- MuJoCo reference: %s: phi_net = %.4f deg.\n", st.mujoco.setting.c_str(),
                    st.mujoco.phi_net_deg);
      md << b;
      for (const std::string& line : st.mujoco.evidence) md << "- " << line << "\n";
      const double gap = st.mujoco.phi_net_deg - st.analytic.phi_net_deg;
      std::snprintf(b, sizeof b,
                    "- Modelling gap for perspective: MuJoCo - analytic = %+.3f deg (%+.1f %% of the analytic %.3f deg); "
                    "with the exact coupling the analytic model gives %.3f deg (MuJoCo %+.1f %% from it). Numerical "
                    "errors at the defaults should be far below this.\n",
                    gap, 100 * gap / st.analytic.phi_net_deg, st.analytic.phi_net_deg, st.analytic_exact_deg,
                    100 * (st.mujoco.phi_net_deg - st.analytic_exact_deg) / st.analytic_exact_deg);
      md << b;
    }
    md << "\n";
    md << "| model | family | setting | phi_net [deg] | phi_net error [deg] | RMS phi error [deg] | wall [ms] | steps | "
          "runs | status |\n|---|---|---|---|---|---|---|---|---|---|\n";
    for (const AccuracyRow& r : st.rows) {
      std::string failure = r.failure;
      std::replace(failure.begin(), failure.end(), ',', ';');
      std::replace(failure.begin(), failure.end(), '\n', ' ');
      std::snprintf(b, sizeof b, "%s,%s,%s,%s,%g,%d,%d,%.12g,%.6g,%.6g,%.6g,%ld,%d,%s\n", st.case_name.c_str(),
                    r.model.c_str(), r.family.c_str(), r.setting.c_str(), r.value, r.is_default, r.ok, r.phi_net_deg,
                    r.err_phi_net_deg, r.rms_err_phi_deg, r.wall_s, r.steps, r.runs, failure.c_str());
      csv << b;
      const char* bo = r.is_default ? "**" : "";
      if (r.ok)
        std::snprintf(b, sizeof b, "| %s%s%s | %s | %s%s%s | %.6f | %.2e | %.2e | %.3f | %ld | %d | ok |\n", bo,
                      r.model.c_str(), bo, r.family.c_str(), bo, r.setting.c_str(), bo, r.phi_net_deg,
                      r.err_phi_net_deg, r.rms_err_phi_deg, 1e3 * r.wall_s, r.steps, r.runs);
      else
        std::snprintf(b, sizeof b, "| %s | %s | %s | - | - | - | %.3f | %ld | %d | FAILED: %.160s |\n", r.model.c_str(),
                      r.family.c_str(), r.setting.c_str(), 1e3 * r.wall_s, r.steps, r.runs, failure.c_str());
      md << b;
    }
  }
  writeOwnedFile(dir, "accuracy.csv", csv.str(), earlierAccuracyTable("accuracy.csv"));
  writeOwnedFile(dir, "accuracy.md", md.str(), earlierAccuracyTable("accuracy.md"));
}

void checkAccuracyTables(const std::string& dir) {
  for (const char* name : {"accuracy.csv", "accuracy.md"}) checkOwnedFile(dir, name, std::nullopt, earlierAccuracyTable(name));
}

}  // namespace tailsim
