#include "design/optimize_experiment.h"
#include "common/stop_signals.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "models/analytic/analytic_simulation.h"
#include "models/perfoot/per_foot_model.h"
#include "experiments/experiment_loader.h"
#include "experiments/folder_inputs.h"
#include "models/mujoco/mujoco_simulation.h"
#include "plotting/gnuplot.h"
#include "common/atomic_file.h"
#include "results/csv.h"
#include "common/units.h"

namespace tailsim {
namespace {

namespace fs = std::filesystem;
using units::kDegPerRad;

std::string g17(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

// Full-resolution re-run on the base's output grid.
OutputSettings fullOutput(const ExperimentCase& c, const TailTrajectory& t) {
  OutputSettings o = c.output;
  o.duration_s = 0.0;  // tail end + settle
  (void)t;
  return o;
}

TimeSeries trajectorySeries(const std::vector<TailLink>& links, const TailTrajectory& traj, double dt, double t_end) {
  TimeSeries ts;
  const int n = static_cast<int>(traj.joints.size());
  ts.addColumn("t_s");
  for (const char* q : {"theta", "thetadot", "thetaddot", "tau"})
    for (int i = 1; i <= n; ++i)
      ts.addColumn(std::string(q) + std::to_string(i) +
                   (std::string(q) == "theta" ? "_deg" : std::string(q) == "thetadot" ? "_dps" : std::string(q) == "tau" ? "_Nm" : "_dps2"));
  std::vector<JointState> js;
  for (long k = 0; k * dt <= t_end + 1e-12; ++k) {
    const double t = k * dt;
    traj.evaluate(t, js);
    const std::vector<double> tau = jointTorques(links, js);
    std::vector<double> row{t};
    for (const auto& j : js) row.push_back(j.theta * kDegPerRad);
    for (const auto& j : js) row.push_back(j.theta_dot * kDegPerRad);
    for (const auto& j : js) row.push_back(j.theta_ddot * kDegPerRad);
    for (double x : tau) row.push_back(x);
    ts.appendRow(row);
  }
  return ts;
}

}  // namespace

LimitCheck checkLimitsOnSeries(const std::vector<TailLink>& links, const TimeSeries& ts, const StrokeLimits& L) {
  LimitCheck c;
  const int n = static_cast<int>(links.size());
  const double d2r = units::kRadPerDeg;
  StrokeFigures& f = c.figures;
  f.theta_min_rad = std::numeric_limits<double>::infinity();
  f.theta_max_rad = -f.theta_min_rad;
  std::vector<JointState> js(static_cast<std::size_t>(n));
  const std::vector<double>& t = ts.values("t_s");
  double prev_p = 0;
  for (std::size_t r = 0; r < ts.numRows(); ++r) {
    for (int i = 0; i < n; ++i) {
      const std::string k = std::to_string(i + 1);
      js[i] = {ts.at(r, ts.column("theta" + k + "_deg")) * d2r, ts.at(r, ts.column("thetadot" + k + "_dps")) * d2r,
               ts.at(r, ts.column("thetaddot" + k + "_dps2")) * d2r};
    }
    const std::vector<double> tau = jointTorques(links, js);
    f.addSample(js, tau);
    double p = 0;
    for (int i = 0; i < n; ++i) p += std::abs(tau[i] * js[i].theta_dot);
    if (r > 0) f.energy_J += 0.5 * (p + prev_p) * (t[r] - t[r - 1]);
    prev_p = p;
    if (r + 1 == ts.numRows() && r > 0)
      for (int i = 0; i < n; ++i)
        f.end_offset_rad = std::max(f.end_offset_rad, std::abs(js[i].theta - ts.at(0, ts.column("theta" + std::to_string(i + 1) + "_deg")) * d2r));
  }
  auto over = exceedsLimit;  // the optimiser's rule (limitViolation)
  for (std::size_t i = 0; i < f.joints.size(); ++i) {
    const JointLimits J = L.joint(i);
    const JointFigures& g = f.joints[i];
    const std::string who = "joint " + std::to_string(i + 1) + " ";
    if (over(g.theta_max_rad, J.theta_max_rad) || over(J.theta_min_rad, g.theta_min_rad))
      c.violations.push_back(who + "angle " + std::to_string(g.theta_min_rad * kDegPerRad) + ".." +
                             std::to_string(g.theta_max_rad * kDegPerRad) + " deg outside its range " +
                             std::to_string(J.theta_min_rad * kDegPerRad) + ".." + std::to_string(J.theta_max_rad * kDegPerRad));
    if (over(g.peak_speed_radps, J.thetadot_max_radps))
      c.violations.push_back(who + "peak speed " + std::to_string(g.peak_speed_radps * kDegPerRad) + " deg/s over its limit " +
                             std::to_string(J.thetadot_max_radps * kDegPerRad));
    if (J.torque_max_Nm > 0 && over(g.peak_torque_Nm, J.torque_max_Nm))
      c.violations.push_back(who + "peak torque " + std::to_string(g.peak_torque_Nm) + " N m over its limit " +
                             std::to_string(J.torque_max_Nm));
  }
  if (L.end == StrokeEnd::kAtStart && f.end_offset_rad > 1e-6)
    c.violations.push_back("the tail ends " + std::to_string(f.end_offset_rad * kDegPerRad) + " deg from its start");
  c.ok = c.violations.empty();
  return c;
}

std::string bestExperimentYaml(const OptimizeSpec& spec, const TailTrajectory& traj) {
  YAML::Node doc = YAML::LoadFile(spec.base_file);
  doc["name"] = spec.name + kBestNameSuffix;
  doc["description"] = "Best stroke of " + spec.name + " (tailsim optimize, " + std::string(familyName(spec.problem.space.family)) + ")";
  doc["robot"] = "robot.yaml";  // the copy beside it in the folder (designFolderInputs)
  YAML::Node t(YAML::NodeType::Map);
  auto flowList = [] {
    YAML::Node l(YAML::NodeType::Sequence);
    l.SetStyle(YAML::EmitterStyle::Flow);
    return l;
  };
  if (spec.problem.space.family == StrokeFamily::kSpline) {
    // trajectory: {family: spline, knots_deg: [[...] per joint], dT_s: [...], t0_s: [...]}
    t["family"] = "spline";
    YAML::Node knots(YAML::NodeType::Sequence);
    YAML::Node dT = flowList(), t0 = flowList();
    for (const auto& j : traj.joints) {
      YAML::Node k = flowList();
      for (double v : j.spline().knots_rad) k.push_back(YAML::Load(g17(v * kDegPerRad)));
      knots.push_back(k);
      dT.push_back(YAML::Load(g17(j.spline().dT_s)));
      t0.push_back(YAML::Load(g17(j.spline().t0_s)));
    }
    t["knots_deg"] = knots;
    t["dT_s"] = dT;
    t["t0_s"] = t0;
  } else {
    const char* keys[] = {"theta0_deg", "dtheta_deg", "dT_s", "w_ss", "t0_s"};
    for (const char* k : keys) {
      YAML::Node l = flowList();
      for (const auto& j : traj.joints) {
        const SplitCycleParams& p = j.params();
        const std::string key = k;
        const double v = key == "theta0_deg" ? p.theta0_rad * kDegPerRad
                         : key == "dtheta_deg" ? p.dtheta_rad * kDegPerRad
                         : key == "dT_s" ? p.dT_s : key == "w_ss" ? p.w_ss : p.t0_s;
        l.push_back(YAML::Load(g17(v)));
      }
      t[k] = l;
    }
  }
  doc["trajectory"] = t;
  // The re-runs simulate to the tail's end + settle (fullOutput); so does the file.
  const YAML::Node& base = doc;  // const: looking up a key must not add it
  if (base["output"] && base["output"].IsMap() && base["output"]["duration_s"]) doc["output"]["duration_s"] = 0;
  YAML::Node models(YAML::NodeType::Sequence);
  models.SetStyle(YAML::EmitterStyle::Flow);
  models.push_back("analytic");
  models.push_back("perfoot");
  models.push_back("mujoco");
  doc["models"] = models;
  YAML::Emitter e;
  e << doc;
  return "# Written by tailsim optimize (" + spec.name + "); its robot is the folder's copy, robot.yaml\n" +
         std::string(e.c_str()) + "\n";
}

std::map<std::string, std::string> designFolderInputs(const std::string& design_file, const std::string& design_copy,
                                                      const std::string& base_file, const std::string& stroke_file) {
  std::map<std::string, std::string> in = folderInputs(loadExperiment(base_file));  // experiment.yaml, robot.yaml
  std::map<std::string, std::string> out;
  out["base.yaml"] = in.at("experiment.yaml");
  out["robot.yaml"] = in.at("robot.yaml");
  std::ifstream f(design_file, std::ios::binary);
  if (!f) throw std::runtime_error("cannot read " + design_file);
  std::ostringstream text;
  text << f.rdbuf();
  std::string design = withValueAt(design_file, text.str(), {"base"}, "base.yaml");
  if (!stroke_file.empty()) {
    std::map<std::string, std::string> st = folderInputs(loadExperiment(stroke_file));
    out["stroke.yaml"] = withValueAt(stroke_file, st.at("experiment.yaml"), {"robot"}, "stroke_robot.yaml");
    out["stroke_robot.yaml"] = st.at("robot.yaml");
    design = withValueAt(design_file, design, {"maneuver", "stroke_from"}, "stroke.yaml");
  }
  out[design_copy] = design;
  return out;
}

namespace {

std::string fmt4(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.4g", v);
  return std::string(b);
}

// The limits as the infeasible message names them: one torque and speed, or each joint's.
std::string limitsText(const StrokeLimits& L) {
  std::string limits;
  if (L.joints.empty())
    limits = "torque " + (L.torque_max_Nm > 0 ? fmt4(L.torque_max_Nm) + " N m" : std::string("unlimited")) + ", speed " +
             fmt4(L.thetadot_max_radps * kDegPerRad) + " deg/s";
  else
    for (std::size_t i = 0; i < L.joints.size(); ++i)
      limits += (i ? "; joint " : "joint ") + std::to_string(i + 1) + ": torque " +
                (L.joints[i].torque_max_Nm > 0 ? fmt4(L.joints[i].torque_max_Nm) + " N m" : std::string("unlimited")) +
                ", speed " + fmt4(L.joints[i].thetadot_max_radps * kDegPerRad) + " deg/s";
  return limits;
}

// The infeasible message's first sentence: the limits, the turn asked and found, the binding
// joint (B: its limits) and the stiction reach.
std::string infeasibleHead(const Infeasibility& r, const JointLimits& B, const StrokeLimits& L,
                           const StrokeEvaluation& best, double min_turn_rad) {
  const std::string binding =
      r.binding_joint < 0 ? std::string()
                          : "; the binding joint is joint " + std::to_string(r.binding_joint + 1) + " (" +
                                fmt4(r.binding_torque_Nm) + " N m" +
                                (B.torque_max_Nm > 0 ? " of its " + fmt4(B.torque_max_Nm) + " N m" : std::string()) + ")";
  return "no stroke within the limits (" + limitsText(L) + ") turns the body by min_turn_deg " +
         fmt4(min_turn_rad * kDegPerRad) + " or more: the best found turns it " + fmt4(best.phi_net_rad * kDegPerRad) +
         " deg" + binding +
         (r.reach.applies ? "; its yaw moment on the held body peaks at " + fmt4(100.0 * r.reach.ratio) +
                                " % of the static friction limit (" + fmt4(r.reach.peak_moment_Nm) +
                                " N m of max(mu_s, mu_d) m g L_F = " + fmt4(r.reach.limit_Nm) + " N m)"
                          : std::string());
}

// The problem without torque and speed limits.
StrokeProblem unlimitedProblem(const StrokeProblem& p) {
  StrokeProblem unlimited = p;
  unlimited.space.limits.torque_max_Nm = 0.0;
  unlimited.space.limits.thetadot_max_radps = std::numeric_limits<double>::infinity();
  for (JointLimits& j : unlimited.space.limits.joints) {
    j.torque_max_Nm = 0.0;
    j.thetadot_max_radps = std::numeric_limits<double>::infinity();
  }
  return unlimited;
}

// The least speed-up k (to 1e-6 of k) at which the same stroke shape, run k times faster, turns
// the body by min_turn_rad, bracketed from the stiction reach's estimate; none if not even 30
// times faster does.
std::optional<double> neededSpeedUp(const StrokeProblem& unlimited, const TailTrajectory& traj, const StictionReach& reach,
                     double min_turn_rad) {
  auto turns = [&](double k) {
    const StrokeEvaluation e = evaluateStroke(unlimited, timeScaled(traj, k));
    return e.ok && std::abs(e.phi_net_rad) >= min_turn_rad;
  };
  double lo = 1.0, hi = reach.applies && reach.ratio > 0.0 && reach.ratio < 1.0 ? std::sqrt(1.0 / reach.ratio) : 1.2;
  while (!turns(hi) && hi < 30.0) {
    lo = hi;
    hi *= 1.25;
  }
  if (!turns(hi)) return std::nullopt;
  for (int it = 0; it < 40 && hi - lo > 1e-6 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (turns(mid) ? hi : lo) = mid;
  }
  return hi;
}

// The needed figures at speed-up k: exactly k^2 and k times the stroke's (the check's are sampled
// every 0.5 ms, coarse for a stroke this fast), in all and per joint.
void neededFigures(const StrokeEvaluation& best, double k, Infeasibility& r) {
  r.torque_needed_Nm = r.peak_torque_Nm * k * k;
  r.speed_needed_dps = r.peak_speed_dps * k;
  for (const JointFigures& g : best.figures.joints) {
    r.torque_needed_per_joint_Nm.push_back(g.peak_torque_Nm * k * k);
    r.speed_needed_per_joint_dps.push_back(g.peak_speed_radps * kDegPerRad * k);
  }
}

}  // namespace

// Stages: the binding joint, the message's head, the least speed-up that turns the body (the loads
// are inertial: the same shape run k times faster needs joint torques x k^2, speeds x k), a check
// run at it, and the figures needed.
Infeasibility analyseInfeasible(const StrokeProblem& p, const StrokeEvaluation& best, const TailTrajectory& traj,
                                double min_turn_rad) {
  Infeasibility r;
  if (!best.ok || !(std::abs(best.phi_net_rad) < min_turn_rad)) return r;
  r.infeasible = true;
  r.reach = stictionReach(p.base, traj);
  r.peak_torque_Nm = best.figures.peak_torque_Nm;
  r.peak_speed_dps = best.figures.peak_speed_radps * kDegPerRad;
  const StrokeLimits& L = p.space.limits;
  // The joint that binds: the one whose torque uses the largest share of its limit.
  r.binding_joint = mostLoadedJoint(best.figures, L);
  const JointLimits B = L.joint(static_cast<std::size_t>(std::max(0, r.binding_joint)));
  if (r.binding_joint >= 0) {
    r.binding_torque_Nm = best.figures.joints[static_cast<std::size_t>(r.binding_joint)].peak_torque_Nm;
    r.binding_limit_Nm = B.torque_max_Nm;
  }
  const std::string head = infeasibleHead(r, B, L, best, min_turn_rad);
  const StrokeProblem unlimited = unlimitedProblem(p);
  const std::optional<double> speed_up = neededSpeedUp(unlimited, traj, r.reach, min_turn_rad);
  if (!speed_up) {
    r.torque_needed_Nm = r.speed_needed_dps = std::numeric_limits<double>::infinity();
    r.message = head + "; even 30 times faster the same stroke shape does not: widen the angle range or change the robot";
    return r;
  }
  const double k = *speed_up;
  const StrokeEvaluation c = evaluateStroke(unlimited, timeScaled(traj, k));
  r.check_ok = c.ok;
  r.check_torque_Nm = c.figures.peak_torque_Nm;
  r.check_speed_dps = c.figures.peak_speed_radps * kDegPerRad;
  r.check_phi_net_deg = c.phi_net_rad * kDegPerRad;
  neededFigures(best, k, r);
  std::string per_joint;
  if (!L.joints.empty())
    for (std::size_t i = 0; i < r.torque_needed_per_joint_Nm.size(); ++i)
      per_joint += (i ? ", joint " : "; per joint: joint ") + std::to_string(i + 1) + " " +
                   fmt4(r.torque_needed_per_joint_Nm[i]) + " N m, " + fmt4(r.speed_needed_per_joint_dps[i]) + " deg/s";
  // The limits the needed figures pass, joint by joint (a speed-up may pass the speed limit and
  // not the torque limit): those are the ones to raise.
  std::string passed;
  for (std::size_t i = 0; i < r.torque_needed_per_joint_Nm.size(); ++i) {
    const JointLimits J = L.joint(i);
    const std::string joint = "joint " + std::to_string(i + 1) + "'s ";
    if (J.torque_max_Nm > 0 && exceedsLimit(r.torque_needed_per_joint_Nm[i], J.torque_max_Nm))
      passed += (passed.empty() ? "" : ", ") + joint + "torque (" + fmt4(J.torque_max_Nm) + " N m)";
    if (exceedsLimit(r.speed_needed_per_joint_dps[i], J.thetadot_max_radps * kDegPerRad))
      passed += (passed.empty() ? "" : ", ") + joint + "speed (" + fmt4(J.thetadot_max_radps * kDegPerRad) + " deg/s)";
  }
  r.message = head + ". The same stroke shape, run " + fmt4(k) + " times faster, turns it " + fmt4(r.check_phi_net_deg) +
              " deg (" + objectiveModelName(p.search_model) + " model) at a peak joint torque of " + fmt4(r.torque_needed_Nm) +
              " N m and a peak joint speed of " + fmt4(r.speed_needed_dps) + " deg/s (now " + fmt4(r.peak_torque_Nm) +
              " N m, " + fmt4(r.peak_speed_dps) + " deg/s" + per_joint + "): raise the limits to at least these" +
              (passed.empty() ? std::string() : " (it passes " + passed + ")") + ", or change the robot";
  return r;
}

namespace {

// Progress of the seed searches on stderr: on a terminal one line redrawn with \r (every 0.5 s), in a
// log a plain line every 5 s, as `tailsim run` does; a line per finished seed either way.
class SeedProgress {
 public:
  SeedProgress(const OptimizeSpec& spec, std::chrono::steady_clock::time_point t0)
      : spec_(spec), t0_(t0), tty_(::isatty(STDERR_FILENO) == 1),
        period_(tty_ ? std::chrono::milliseconds(500) : std::chrono::milliseconds(5000)),
        runs_estimate_(optimizeRunEstimate(spec) /
                       static_cast<double>(spec.seeds.size() + static_cast<std::size_t>(spec.pareto_points)) *
                       static_cast<double>(spec.seeds.size())),
        unit_(objectiveUnit(spec.problem.objective)),
        last_print_(std::chrono::steady_clock::now() - period_) {}  // the first line at once

  // The running line during seed i's search; runs_before counts the earlier seeds' runs.
  void during(std::size_t i, long runs_before, const SearchProgress& p) {
    const auto now = std::chrono::steady_clock::now();
    if (now - last_print_ < period_) return;
    last_print_ = now;
    const bool better = p.best_objective > best_obj_;
    const double obj = better ? p.best_objective : best_obj_, phi = better ? p.best_phi_net_rad : best_phi_;
    const double el = std::chrono::duration<double>(now - t0_).count();
    std::fprintf(stderr, "%s[optimize %s] seed %llu (%zu/%zu), %s: %ld runs (about %.3g in all), best so far %s %+.6g %s "
                 "(phi_net %+.4f deg), %.1f s elapsed%s",
                 tty_ ? "\r" : "", spec_.name.c_str(), static_cast<unsigned long long>(spec_.seeds[i]), i + 1, spec_.seeds.size(),
                 p.stage, runs_before + p.evaluations, runs_estimate_, objectiveName(spec_.problem.objective),
                 signedObjectiveDeg(obj, phi), unit_, phi * kDegPerRad, el, tty_ ? "   " : "\n");
    line_open_ = tty_;
    std::fflush(stderr);
  }

  // Keeps the best over the finished seeds; prints the seed's line when `print`.
  void finished(std::uint64_t seed, const OptimizeResult& r, bool print) {
    if (r.best.objective > best_obj_) {
      best_obj_ = r.best.objective;
      best_phi_ = r.best.phi_net_rad;
    }
    if (!print) return;
    if (line_open_) std::fprintf(stderr, "\n");
    line_open_ = false;
    std::fprintf(stderr, "seed %llu: %s %+.6g %s (phi_net %+.4f deg), peak torque %.4g N m, %ld runs, %.2f s\n",
                 static_cast<unsigned long long>(seed), objectiveName(spec_.problem.objective),
                 signedObjectiveDeg(r.best.objective, r.best.phi_net_rad), unit_, r.best.phi_net_rad * kDegPerRad,
                 r.best.figures.peak_torque_Nm, r.evaluations, r.wall_s);
  }

 private:
  const OptimizeSpec& spec_;
  std::chrono::steady_clock::time_point t0_;
  bool tty_;
  std::chrono::milliseconds period_;
  double runs_estimate_;
  const char* unit_;
  double best_obj_ = 0.0, best_phi_ = 0.0;  // over the finished seeds
  bool line_open_ = false;
  std::chrono::steady_clock::time_point last_print_;
};

// Stage 1: one search per seed, into rep.per_seed and rep.evaluations.
void searchSeeds(const OptimizeSpec& spec, bool progress, std::chrono::steady_clock::time_point t0,
                 const std::function<int()>& stopped, OptimizeReport& rep) {
  SeedProgress line(spec, t0);
  for (std::size_t i = 0; i < spec.seeds.size(); ++i) {
    if (stopped && (rep.stop_signal = stopped()) != 0) return;
    OptimizerSettings os = spec.optimizer;
    os.seed = spec.seeds[i];
    ProgressFn show;
    if (progress) show = [&line, &rep, i](const SearchProgress& p) { line.during(i, rep.evaluations, p); };
    rep.per_seed.push_back(optimizeStroke(spec.problem, os, show));
    const OptimizeResult& r = rep.per_seed.back();
    rep.evaluations += r.evaluations;
    line.finished(spec.seeds[i], r, progress);
  }
}

// Stage 2: the best seed (rep.best_seed_index) and the seeds' spread; returns the best seed's result.
OptimizeResult pickBestSeed(OptimizeReport& rep) {
  double lo = 1e300, hi = -1e300;
  for (std::size_t i = 0; i < rep.per_seed.size(); ++i) {
    const double v = rep.per_seed[i].best.objective;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    if (rep.per_seed[i].best.betterThan(rep.per_seed[rep.best_seed_index].best)) rep.best_seed_index = i;
  }
  rep.spread = hi > 0 ? (hi - lo) / hi : 0.0;
  return rep.per_seed[rep.best_seed_index];
}

// The search's best distinct candidates over every seed, best first, at most keep_candidates.
std::vector<Candidate> distinctCandidates(const OptimizeReport& rep, const OptimizeResult& best, int keep_candidates) {
  std::vector<Candidate> cands;
  for (const OptimizeResult& r : rep.per_seed) cands.insert(cands.end(), r.candidates.begin(), r.candidates.end());
  std::stable_sort(cands.begin(), cands.end(),
                   [](const Candidate& a, const Candidate& b) { return a.eval.objective > b.eval.objective; });
  std::vector<Candidate> distinct;
  for (Candidate& c : cands) {
    bool same = false;
    for (const Candidate& d : distinct) same = same || std::abs(d.eval.objective - c.eval.objective) <= 1e-6 * d.eval.objective;
    if (!same && distinct.size() < static_cast<std::size_t>(keep_candidates)) distinct.push_back(std::move(c));
  }
  if (distinct.empty()) distinct.push_back({best.trajectory, best.best});
  return distinct;
}

// Stage 3 (objective model mujoco): MuJoCo re-ranks the search's best distinct candidates; the one
// whose MuJoCo objective is largest replaces `best`.
void rerankWithMujoco(const OptimizeSpec& spec, bool progress, OptimizeResult& best, OptimizeReport& rep) {
  const StrokeProblem& prob = spec.problem;
  const std::vector<Candidate> distinct = distinctCandidates(rep, best, prob.keep_candidates);
  for (std::size_t k = 0; k < distinct.size(); ++k) {
    const Candidate& c = distinct[k];
    RerankRow row;
    row.search_phi_net_deg = c.eval.phi_net_rad * kDegPerRad;
    const RunResult rm = simulateMujoco(spec.base.robot, c.trajectory, spec.base.mujoco, spec.base.effects,
                                        fullOutput(spec.base, c.trajectory));
    row.ok = rm.summary.ok && std::isfinite(rm.summary.phi_net_deg);
    row.error = rm.summary.error;
    if (row.ok) {
      row.mujoco_phi_net_deg = rm.summary.phi_net_deg;
      row.mujoco_objective = objectiveValue(prob.objective, rm.summary.phi_net_deg / kDegPerRad, c.eval.figures);
    }
    if (row.mujoco_objective > (rep.rerank.empty() ? -1.0 : rep.rerank[rep.rerank_chosen].mujoco_objective))
      rep.rerank_chosen = k;
    rep.rerank.push_back(row);
    if (progress)
      std::fprintf(stderr, "MuJoCo re-rank %zu/%zu: %s phi_net %+.4f deg, MuJoCo %s\n", k + 1, distinct.size(),
                   objectiveModelName(prob.search_model), row.search_phi_net_deg,
                   row.ok ? (std::to_string(row.mujoco_phi_net_deg) + " deg").c_str() : ("failed: " + row.error).c_str());
  }
  const Candidate& chosen = distinct[rep.rerank_chosen];
  if (rep.rerank_chosen != 0 || chosen.eval.objective != best.best.objective) {
    best.trajectory = chosen.trajectory;
    best.best = chosen.eval;
    best.x.clear();
    best.directions.clear();  // the candidates' direction patterns are not kept
  }
}

// Stage 4: the stroke the re-simulations run, as best.yaml writes it, read back by the experiment
// loader: its angles are decimal degrees there, which need not convert back to the search's radians
// to the last bit, and `tailsim run best.yaml` must give what summary.json reports. It cannot fail
// the search's work: if the loader refuses the file, the search's trajectory is returned and
// rep.best_yaml_error says why (best.yaml is still written).
TailTrajectory readBackBest(const std::string& best_yaml, const TailTrajectory& searched, const std::string& out_dir,
                            OptimizeReport& rep) {
  TailTrajectory traj = searched;
  try {
    traj = loadExperimentText(best_yaml, (fs::path(out_dir) / "best.yaml").string()).cases.at(0).trajectory();
  } catch (const std::exception& e) {
    rep.best_yaml_error = e.what();
  }
  return traj;
}

// Stage 5: verification: re-simulate, check the limits on what the model ran, run the per-foot model
// and (mujoco_check) MuJoCo; writes the series, the trajectory and best.yaml.
void resimulateBest(const OptimizeSpec& spec, const TailTrajectory& traj, const std::string& best_yaml,
                    const std::string& out_dir, OptimizeReport& rep) {
  const OutputSettings out = fullOutput(spec.base, traj);
  const RunResult ra = simulateAnalytic(spec.base.robot, traj, spec.base.analytic, spec.base.effects, out);
  rep.analytic = ra.summary;
  rep.limits_analytic = checkLimitsOnSeries(spec.base.robot.tail, ra.series, spec.problem.space.limits);
  writeOwnedFile(out_dir, "best_analytic.csv", toCsv(ra.series));
  rep.files.push_back("best_analytic.csv");
  // The per-foot friction model: milliseconds, always run; a failure (e.g. the robot
  // tips) is reported, not thrown.
  // A write error (a full disk) is not the model's: it ends the command.
  std::optional<RunResult> rp;
  try {
    rp = simulatePerFoot(spec.base.robot, traj, spec.base.perfoot, spec.base.effects, out);
  } catch (const std::exception& e) {
    rep.perfoot.model = "perfoot";
    rep.perfoot.ok = false;
    rep.perfoot.error = e.what();
    rep.perfoot.phi_net_deg = std::numeric_limits<double>::quiet_NaN();
  }
  if (rp) {
    rep.perfoot = rp->summary;
    writeOwnedFile(out_dir, "best_perfoot.csv", toCsv(rp->series));
    rep.files.push_back("best_perfoot.csv");
  }
  if (spec.mujoco_check) {
    const RunResult rm = simulateMujoco(spec.base.robot, traj, spec.base.mujoco, spec.base.effects, out);
    rep.mujoco = rm.summary;
    writeOwnedFile(out_dir, "best_mujoco.csv", toCsv(rm.series));
    rep.files.push_back("best_mujoco.csv");
  }
  writeOwnedFile(out_dir, "best_trajectory.csv", toCsv(trajectorySeries(spec.base.robot.tail, traj, 1e-3, traj.endTime())));
  rep.files.push_back("best_trajectory.csv");
  writeOwnedFile(out_dir, "best.yaml", best_yaml);
  rep.files.push_back("best.yaml");
}

// Stage 6: the convergence history, in signed degrees (the objective's sign is phi_net's): history.csv
// and plots/history.png.
void writeHistory(const OptimizeSpec& spec, const std::string& out_dir, OptimizeReport& rep) {
  const StrokeProblem& prob = spec.problem;
  const std::string col = std::string("best_") + objectiveName(prob.objective) + "_" + objectiveUnitSuffix(prob.objective);
  std::ostringstream csv;
  csv << "seed,stage,generation,evaluations,wall_s," << col
      << (prob.objective == StrokeObjective::kPhiNet ? "" : ",best_phi_net_deg") << "\n";
  for (std::size_t i = 0; i < rep.per_seed.size(); ++i)
    for (const HistoryRow& h : rep.per_seed[i].history) {
      csv << spec.seeds[i] << "," << h.stage << "," << h.generation << "," << h.evaluations << "," << g17(h.wall_s) << ","
          << g17(signedObjectiveDeg(h.best_objective, h.best_phi_net_rad));
      if (prob.objective != StrokeObjective::kPhiNet) csv << "," << g17(h.best_phi_net_rad * kDegPerRad);
      csv << "\n";
    }
  writeOwnedFile(out_dir, "history.csv", csv.str());
  rep.files.push_back("history.csv");
  GnuplotFigure fig;
  fig.stem = "history";
  std::ostringstream b;
  b << "set datafile separator ','\nset key outside right\nset grid\n"
    << "set title " << gpQuote("Convergence of " + spec.name + " (" + familyName(prob.space.family) + ")")
    << " noenhanced\nset xlabel " << gpQuote(std::string(objectiveModelName(prob.search_model)) + " model runs")
    << "\nset ylabel "
    // Signed: the best stroke so far (ranked by |objective|) may turn the body the other way.
    << gpQuote(std::string(objectiveName(prob.objective)) + " of the best stroke so far, signed [" + objectiveUnit(prob.objective) + "]")
    << " noenhanced\nplot ";
  const std::string data = gpFileName("../history.csv");
  for (std::size_t i = 0; i < spec.seeds.size(); ++i)
    b << (i ? ", " : "") << data << " every ::1 using ($1==" << spec.seeds[i]
      << " ? $4 : 1/0):6 with steps lw 2 title " << gpQuote("seed " + std::to_string(spec.seeds[i]));
  // The stages: a mark at every generation of each (all seeds), so the plot shows where the
  // global search, the refine, the local restarts and the polish ran.
  const char* stages[][2] = {{"global", "6"}, {"refine", "8"}, {"local", "4"}, {"polish", "7"}};
  for (const auto& st : stages)
    b << ", " << data << " every ::1 using (strcol(2) eq '" << st[0] << "' ? $4 : 1/0):6 with points pt " << st[1]
      << " ps 0.6 lc rgb 'gray40' title '" << st[0] << "'";
  b << "\n";
  fig.body = b.str();
  renderFigure((fs::path(out_dir) / "plots").string(), fig);
  rep.files.push_back("plots/history.png");
}

// Stage 7 (pareto_points >= 2): the Pareto front, phi_net vs peak joint torque, by re-optimising under
// torque limits: pareto.csv and plots/pareto.png; returns summary.json's "pareto" rows.
nlohmann::json paretoFront(const OptimizeSpec& spec, const OptimizeResult& best, bool progress, const std::string& out_dir,
                           OptimizeReport& rep) {
  const StrokeProblem& prob = spec.problem;
  nlohmann::json pareto = nlohmann::json::array();
  const double tau_top = best.best.figures.peak_torque_Nm;
  std::ostringstream csv;
  csv << "torque_limit_Nm,peak_torque_Nm,phi_net_deg,evaluations\n";
  for (int k = 0; k < spec.pareto_points; ++k) {
    StrokeProblem p = prob;
    p.objective = StrokeObjective::kPhiNet;
    const double lim = tau_top * (0.2 + 0.8 * k / (spec.pareto_points - 1));
    p.space.limits.torque_max_Nm = prob.space.limits.torque_max_Nm > 0 ? std::min(lim, prob.space.limits.torque_max_Nm) : lim;
    for (JointLimits& jl : p.space.limits.joints) jl.torque_max_Nm = jl.torque_max_Nm > 0 ? std::min(lim, jl.torque_max_Nm) : lim;
    OptimizerSettings os = spec.optimizer;
    os.seed = spec.seeds.front();
    const OptimizeResult r = optimizeStroke(p, os);
    rep.evaluations += r.evaluations;
    csv << g17(p.space.limits.torque_max_Nm) << "," << g17(r.best.figures.peak_torque_Nm) << ","
        << g17(r.best.phi_net_rad * kDegPerRad) << "," << r.evaluations << "\n";
    pareto.push_back({{"torque_limit_Nm", p.space.limits.torque_max_Nm}, {"peak_torque_Nm", r.best.figures.peak_torque_Nm},
                      {"phi_net_deg", r.best.phi_net_rad * kDegPerRad}, {"feasible", r.best.feasible()}});
    if (progress)
      std::fprintf(stderr, "pareto %d/%d: torque <= %.4g N m: phi_net %+.4f deg\n", k + 1, spec.pareto_points,
                   p.space.limits.torque_max_Nm, r.best.phi_net_rad * kDegPerRad);
  }
  writeOwnedFile(out_dir, "pareto.csv", csv.str());
  rep.files.push_back("pareto.csv");
  GnuplotFigure fig;
  fig.stem = "pareto";
  fig.body = "set datafile separator ','\nset grid\nset key off\nset title " +
             gpQuote("Net yaw vs peak joint torque (" + spec.name + ")") + " noenhanced\nset xlabel 'peak joint torque [N m]'\nset ylabel '|{/Symbol f}_{net}| [deg]'\n"
             "plot " + gpFileName("../pareto.csv") + " every ::1 using 2:(abs($3)) with linespoints lw 2 pt 7\n";
  renderFigure((fs::path(out_dir) / "plots").string(), fig);
  rep.files.push_back("plots/pareto.png");
  return pareto;
}

// summary.json's description of the search: the spec's names and optimizer settings.
void summarizeSettings(const OptimizeSpec& spec, nlohmann::json& j) {
  const StrokeProblem& prob = spec.problem;
  j["experiment"] = spec.name;
  j["source"] = spec.source_file;
  j["base"] = spec.base_file;
  j["limit_overrides"] = spec.limit_overrides;
  j["family"] = familyName(prob.space.family);
  j["objective"] = objectiveName(prob.objective);
  j["objective_model"] = objectiveModelName(spec.objective_model);
  j["search_model"] = objectiveModelName(prob.search_model);
  j["objective_unit"] = objectiveUnit(prob.objective);  // of every "objective_signed" (signed like phi_net); "objective": |.| in radians
  j["n_links"] = prob.space.n_links;
  j["dimensions"] = prob.space.dim();
  j["algorithm"] = spec.optimizer.algorithm;
  j["islands"] = spec.optimizer.islands;
  j["restarts"] = spec.optimizer.restarts;
  j["restart_growth"] = spec.optimizer.restart_growth;
  j["refine_generations"] = spec.optimizer.refine_generations;
  j["restart_polish_evaluations"] = spec.optimizer.restart_polish_evaluations;
  j["local_restarts"] = spec.optimizer.local_restarts;
  j["local_step"] = spec.optimizer.local_step;
  j["directions"] = spec.optimizer.enumerate_directions ? "enumerate" : "free";
  j["directions_kept"] = spec.optimizer.directions_kept;
  j["polish"] = spec.optimizer.polish;
  j["over_torque"] = prob.space.slow_down_over_torque ? "slow_down" : "penalize";
}

// summary.json's search results: start, seeds, directions, the best stroke and its joints.
void summarizeSearch(const OptimizeSpec& spec, const OptimizeReport& rep, const OptimizeResult& best,
                     const TailTrajectory& traj, nlohmann::json& j) {
  j["start"] = {{"phi_net_deg", best.start.phi_net_rad * kDegPerRad}, {"objective", best.start.objective},
                {"objective_signed", signedObjectiveDeg(best.start.objective, best.start.phi_net_rad)},
                {"peak_torque_Nm", best.start.figures.peak_torque_Nm}, {"feasible", best.start.feasible()}};
  nlohmann::json seeds = nlohmann::json::array();
  for (std::size_t i = 0; i < rep.per_seed.size(); ++i) {
    const OptimizeResult& r = rep.per_seed[i];
    seeds.push_back({{"seed", spec.seeds[i]}, {"objective", r.best.objective},
                     {"objective_signed", signedObjectiveDeg(r.best.objective, r.best.phi_net_rad)},
                     {"phi_net_deg", r.best.phi_net_rad * kDegPerRad},
                     {"evaluations", r.evaluations}, {"wall_s", r.wall_s}});
  }
  j["seeds"] = seeds;
  j["seed_spread"] = rep.spread;
  if (!best.by_direction.empty()) {  // the best seed's search per joint-direction pattern
    nlohmann::json dirs = nlohmann::json::array();
    for (const DirectionResult& d : best.by_direction)
      dirs.push_back({{"directions", d.directions}, {"objective", d.best.objective},
                      {"phi_net_deg", d.best.phi_net_rad * kDegPerRad}, {"feasible", d.best.feasible()},
                      {"evaluations", d.evaluations}});
    j["by_direction"] = dirs;
  }
  if (!best.directions.empty()) j["best_directions"] = best.directions;
  const StrokeEvaluation& b = best.best;
  nlohmann::json joints = nlohmann::json::array();
  for (const auto& jp : traj.joints) {
    if (jp.isSpline()) {
      nlohmann::json k = nlohmann::json::array();
      for (double v : jp.spline().knots_rad) k.push_back(v * kDegPerRad);
      joints.push_back({{"knots_deg", k}, {"dT_s", jp.spline().dT_s}, {"t0_s", jp.spline().t0_s}});
    } else {
      const SplitCycleParams& p = jp.params();
      joints.push_back({{"theta0_deg", p.theta0_rad * kDegPerRad}, {"dtheta_deg", p.dtheta_rad * kDegPerRad},
                        {"dT_s", p.dT_s}, {"w_ss", p.w_ss}, {"t0_s", p.t0_s}});
    }
  }
  j["best"] = {{"objective", b.objective}, {"objective_signed", signedObjectiveDeg(b.objective, b.phi_net_rad)},
               {"phi_net_deg", b.phi_net_rad * kDegPerRad},
               {"peak_speed_dps", b.figures.peak_speed_radps * kDegPerRad}, {"peak_torque_Nm", b.figures.peak_torque_Nm},
               {"energy_J", b.figures.energy_J}, {"joints", joints}};
  // The best's objective over the start's, less 1; null when the start scores nothing (a start that
  // does not turn the body: any turn is an unbounded improvement, not 0).
  j["improvement_over_start"] =
      best.start.objective > 0 ? nlohmann::json(b.objective / best.start.objective - 1.0) : nlohmann::json(nullptr);
}

// summary.json's re-runs: the analytic re-run and its limits per joint, MuJoCo, the per-foot model.
void summarizeResimulation(const OptimizeSpec& spec, const OptimizeReport& rep, nlohmann::json& j) {
  const StrokeProblem& prob = spec.problem;
  const LimitCheck& lc = rep.limits_analytic;
  j["resimulated"]["analytic"] = {{"ok", rep.analytic.ok}, {"phi_net_deg", rep.analytic.phi_net_deg},
                                  {"limits_kept", lc.ok}, {"violations", lc.violations},
                                  {"theta_min_deg", lc.figures.theta_min_rad * kDegPerRad},
                                  {"theta_max_deg", lc.figures.theta_max_rad * kDegPerRad},
                                  {"peak_speed_dps", lc.figures.peak_speed_radps * kDegPerRad},
                                  {"peak_torque_Nm", lc.figures.peak_torque_Nm},
                                  {"binding", bindingLimits(lc.figures, prob.space.limits)}};
  nlohmann::json per = nlohmann::json::array();
  for (std::size_t i = 0; i < static_cast<std::size_t>(prob.space.n_links); ++i) {
    const JointLimits J = prob.space.limits.joint(i);
    nlohmann::json row = {{"joint", i + 1},
                          {"theta_min_deg", J.theta_min_rad * kDegPerRad},
                          {"theta_max_deg", J.theta_max_rad * kDegPerRad},
                          {"thetadot_max_dps", J.thetadot_max_radps * kDegPerRad},
                          {"torque_max_Nm", J.torque_max_Nm > 0 ? nlohmann::json(J.torque_max_Nm) : nlohmann::json()}};
    if (i < lc.figures.joints.size()) {
      const JointFigures& g = lc.figures.joints[i];
      row["peak_torque_Nm"] = g.peak_torque_Nm;
      row["peak_speed_dps"] = g.peak_speed_radps * kDegPerRad;
      row["theta_range_deg"] = {g.theta_min_rad * kDegPerRad, g.theta_max_rad * kDegPerRad};
    }
    per.push_back(row);
  }
  j["limits"] = per;  // per joint: the limits and the re-run's figures
  if (spec.mujoco_check)
    j["resimulated"]["mujoco"] = {{"ok", rep.mujoco.ok}, {"phi_net_deg", rep.mujoco.phi_net_deg}, {"error", rep.mujoco.error},
                                  {"difference_deg", rep.mujoco.phi_net_deg - rep.analytic.phi_net_deg},
                                  {"relative_difference", rep.analytic.phi_net_deg != 0
                                                              ? (rep.mujoco.phi_net_deg - rep.analytic.phi_net_deg) / std::abs(rep.analytic.phi_net_deg)
                                                              : 0.0}};
  const double d = rep.perfoot.phi_net_deg - rep.analytic.phi_net_deg;
  j["resimulated"]["perfoot"] = {{"ok", rep.perfoot.ok}, {"error", rep.perfoot.error},
                                 {"phi_net_deg", rep.perfoot.ok ? nlohmann::json(rep.perfoot.phi_net_deg) : nlohmann::json()},
                                 {"difference_deg", rep.perfoot.ok ? nlohmann::json(d) : nlohmann::json()},
                                 {"relative_difference", rep.perfoot.ok && rep.analytic.phi_net_deg != 0
                                                             ? nlohmann::json(d / std::abs(rep.analytic.phi_net_deg))
                                                             : nlohmann::json()}};
}

// summary.json's MuJoCo re-rank rows and the infeasibility diagnosis, when there are.
void summarizeRerankAndInfeasible(const OptimizeSpec& spec, const OptimizeReport& rep, nlohmann::json& j) {
  if (!rep.rerank.empty()) {
    nlohmann::json rr = nlohmann::json::array();
    for (std::size_t k = 0; k < rep.rerank.size(); ++k) {
      const RerankRow& row = rep.rerank[k];
      rr.push_back({{"search_phi_net_deg", row.search_phi_net_deg},
                    {"mujoco_phi_net_deg", row.ok ? nlohmann::json(row.mujoco_phi_net_deg) : nlohmann::json()},
                    {"ok", row.ok}, {"error", row.error}, {"chosen", k == rep.rerank_chosen}});
    }
    j["mujoco_rerank"] = rr;
  }
  if (const Infeasibility& inf = rep.infeasible; inf.infeasible) {
    auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
    j["infeasible"] = {{"message", inf.message},
                       {"min_turn_deg", spec.min_turn_deg},
                       {"stiction_ratio", inf.reach.ratio},
                       {"tail_moment_Nm", inf.reach.peak_moment_Nm},
                       {"friction_limit_Nm", inf.reach.limit_Nm},
                       {"peak_torque_Nm", inf.peak_torque_Nm},
                       {"peak_speed_dps", inf.peak_speed_dps},
                       {"torque_needed_Nm", num(inf.torque_needed_Nm)},
                       {"binding_joint", inf.binding_joint + 1},
                       {"torque_needed_per_joint_Nm", inf.torque_needed_per_joint_Nm},
                       {"speed_needed_per_joint_dps", inf.speed_needed_per_joint_dps},
                       {"speed_needed_dps", num(inf.speed_needed_dps)},
                       {"check", {{"ok", inf.check_ok}, {"peak_torque_Nm", inf.check_torque_Nm},
                                  {"peak_speed_dps", inf.check_speed_dps}, {"phi_net_deg", inf.check_phi_net_deg}}}};
  }
}

// Stage 8: summary.json, the keys in the order readers have always seen them.
void writeSummary(const OptimizeSpec& spec, const OptimizeReport& rep, const OptimizeResult& best, const TailTrajectory& traj,
                  const nlohmann::json& pareto, const std::string& out_dir) {
  nlohmann::json j;
  summarizeSettings(spec, j);
  summarizeSearch(spec, rep, best, traj, j);
  summarizeResimulation(spec, rep, j);
  if (!pareto.empty()) j["pareto"] = pareto;
  summarizeRerankAndInfeasible(spec, rep, j);
  if (rep.stop_signal) {
    j["stopped_by"] = StopSignals::name(rep.stop_signal);
    j["seeds_finished"] = rep.per_seed.size();
  }
  j["evaluations"] = rep.evaluations;
  j["wall_s"] = rep.wall_s;
  j["files"] = rep.files;
  if (!rep.best_yaml_error.empty()) j["best_yaml_error"] = rep.best_yaml_error;
  writeOwnedFile(out_dir, "summary.json", j.dump(2) + "\n");
}

}  // namespace

// The stages in order: the folder's inputs, the seeds' searches, the best seed, the MuJoCo re-rank,
// the infeasibility diagnosis, the read-back and re-simulation, the history, the Pareto front, the summary.
OptimizeReport runOptimize(const OptimizeSpec& spec, const std::string& out_dir, bool progress,
                           const std::function<int()>& stopped) {
  const auto t0 = std::chrono::steady_clock::now();
  OptimizeReport rep;
  fs::create_directories(fs::path(out_dir) / "plots");
  // The folder's own inputs first: best.yaml names the robot copy, and is read back below.
  for (const auto& [name, text] : designFolderInputs(spec.source_file, "optimize.yaml", spec.base_file)) {
    writeOwnedFile(out_dir, name, text);
    rep.files.push_back(name);
  }
  for (const std::string& o : spec.limit_overrides) std::fprintf(stderr, "note: %s\n", o.c_str());
  searchSeeds(spec, progress, t0, stopped, rep);
  if (rep.per_seed.empty()) return rep;  // stopped before a seed finished: the inputs only
  OptimizeResult best = pickBestSeed(rep);
  if (spec.objective_model == ObjectiveModel::kMujoco) rerankWithMujoco(spec, progress, best, rep);
  rep.infeasible = analyseInfeasible(spec.problem, best.best, best.trajectory, units::radians(spec.min_turn_deg));
  const std::string best_yaml = bestExperimentYaml(spec, best.trajectory);
  const TailTrajectory traj = readBackBest(best_yaml, best.trajectory, out_dir, rep);
  resimulateBest(spec, traj, best_yaml, out_dir, rep);
  writeHistory(spec, out_dir, rep);
  nlohmann::json pareto = nlohmann::json::array();
  if (spec.pareto_points >= 2) pareto = paretoFront(spec, best, progress, out_dir, rep);
  rep.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  writeSummary(spec, rep, best, traj, pareto, out_dir);
  rep.files.push_back("summary.json");
  return rep;
}

}  // namespace tailsim
