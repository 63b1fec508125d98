#include "design/optimize_config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>

#include "design/design_yaml.h"
#include "experiments/experiment_loader.h"
#include "experiments/work_estimate.h"
#include "common/work_limits.h"
#include "settings/optimize_section.h"
#include "settings/trajectory_section.h"
#include "common/units.h"

namespace tailsim {
namespace {

using units::kRadPerDeg;
using namespace design_yaml;

// A joint limit given in the design file: one value for every joint, or a list of one per joint
// (checked against the base's n once it is read).
struct FileLimit {
  const Val* at = nullptr;     // the key (nullptr: not given)
  std::vector<double> values;  // 1 (every joint) or n entries; theta: pairs lo, hi flattened
  bool per_joint = false;
};

// The joint limits, joint by joint: the design file's value (a scalar: every joint; a list: one per
// joint), else the robot's (each joint's own tail-entry value). A limit neither gives is refused
// with what to add (torque: `none` keeps no torque limit). When every joint ends with the same
// limits, the scalars of StrokeLimits hold them (joints empty); else StrokeLimits::joints does.
void resolveJointLimits(const Reader& r, const Val& lv, const ExperimentCase& base, const FileLimit& theta,
                        const FileLimit& speed, const FileLimit& torque, bool torque_given_as_word, StrokeLimits& L,
                        std::vector<std::string>& overrides) {
  const std::vector<TailLink>& tail = base.robot.tail;
  const std::size_t n = tail.size();
  const std::string where = base.robot_file.empty() ? std::string("the base experiment's tail")
                                                    : "the robot file " + base.robot_file + " (its tails." +
                                                          std::to_string(n) + " entry)";
  auto missing = [&](const char* key, const std::string& add, std::size_t joint) {
    r.fail(lv.mark, lv.key + "." + key,
           std::string("required key is missing: neither this file nor ") + where + " gives it for joint " +
               std::to_string(joint + 1) + ". Add " + add);
  };
  for (const FileLimit* f : {&theta, &speed, &torque})
    if (f->at && f->per_joint && f->values.size() != (f == &theta ? 2 * n : n))
      r.fail(*f->at, "a list gives one value per joint: the base's tail has " + std::to_string(n) + " joints, got " +
                         std::to_string(f == &theta ? f->values.size() / 2 : f->values.size()));
  auto fileValue = [](const FileLimit& f, std::size_t i, std::size_t stride, std::size_t k) {
    return f.values[(f.per_joint ? i * stride : 0) + k];
  };
  std::vector<JointLimits> js(n);
  // This file's value where the robot gives another: noted (a preset copied for one's own robot).
  auto overridden = [&](std::size_t joint, const std::string& what, const std::string& here, const std::string& robot) {
    if (here != robot)
      overrides.push_back("joint " + std::to_string(joint + 1) + " " + what + ": " + here + " from " + r.file() +
                          " replaces the robot file's " + robot);
  };
  const auto deg = [](double rad) { return fmtG(rad / kRadPerDeg); };
  const auto torqueText = [](double t) { return t > 0.0 ? fmtG(t) + " N m" : std::string("none"); };
  for (std::size_t i = 0; i < n; ++i) {
    JointLimits& J = js[i];
    const TailLink& k = tail[i];
    if (theta.at) {
      J.theta_min_rad = fileValue(theta, i, 2, 0);
      J.theta_max_rad = fileValue(theta, i, 2, 1);
      if (k.hasRange())
        overridden(i, "theta_deg", "[" + deg(J.theta_min_rad) + ", " + deg(J.theta_max_rad) + "] deg",
                   "[" + deg(k.theta_min_rad) + ", " + deg(k.theta_max_rad) + "] deg");
    } else {
      if (!k.hasRange())
        missing("theta_deg", "theta_min_deg and theta_max_deg to the robot's tail entry, or theta_deg: [low, high] here", i);
      J.theta_min_rad = k.theta_min_rad;
      J.theta_max_rad = k.theta_max_rad;
    }
    if (speed.at) {
      J.thetadot_max_radps = fileValue(speed, i, 1, 0);
      if (k.thetadot_max_radps > 0.0)
        overridden(i, "thetadot_max_dps", deg(J.thetadot_max_radps) + " deg/s", deg(k.thetadot_max_radps) + " deg/s");
    } else {
      if (!(k.thetadot_max_radps > 0.0))
        missing("thetadot_max_dps", "thetadot_max_dps (the actuator's peak speed) to the robot's tail entry or here", i);
      J.thetadot_max_radps = k.thetadot_max_radps;
    }
    if (torque.at || torque_given_as_word) {
      J.torque_max_Nm = torque.at ? fileValue(torque, i, 1, 0) : L.torque_max_Nm;
      if (k.torque_max_Nm > 0.0) overridden(i, "torque_max_Nm", torqueText(J.torque_max_Nm), torqueText(k.torque_max_Nm));
    } else {
      if (!(k.torque_max_Nm > 0.0))
        missing("torque_max_Nm", "torque_max_Nm (the actuator's peak torque) to the robot's tail entry or here, or "
                                 "torque_max_Nm: none here for no torque limit", i);
      J.torque_max_Nm = k.torque_max_Nm;
    }
  }
  L.joints.clear();
  if (n == 0) return;
  const JointLimits& a = js.front();
  const bool uniform = std::all_of(js.begin(), js.end(), [&](const JointLimits& b) {
    return b.theta_min_rad == a.theta_min_rad && b.theta_max_rad == a.theta_max_rad &&
           b.thetadot_max_radps == a.thetadot_max_radps && b.torque_max_Nm == a.torque_max_Nm;
  });
  L.theta_min_rad = a.theta_min_rad;
  L.theta_max_rad = a.theta_max_rad;
  L.thetadot_max_radps = a.thetadot_max_radps;
  L.torque_max_Nm = a.torque_max_Nm;
  if (!uniform) L.joints = std::move(js);
}

// The limits section as read, before the base is known.
struct LimitKeys {
  FileLimit theta, speed, torque;
  const Val* torque_key = nullptr;
  bool torque_word = false;  // torque_max_Nm: base or none
};

// Stage: optimize.objective: phi_net (the analytic model's), or {quantity: ..., model: analytic |
// perfoot | mujoco, search: analytic | perfoot (mujoco only; default perfoot), candidates: K (mujoco
// only; default 8)}.
void readObjective(const Reader& r, const Map& o, OptimizeSpec& s) {
  const Val* v = Reader::get(o, "objective");
  if (!v) return;
  const Val* q = v;
  if (v->node.IsMap()) {
    static const std::vector<std::string> kObjectiveKeys = settings::declaredKeys<OptimizeObjectiveSection>();
    const auto om = r.map(*v, kObjectiveKeys);
    q = Reader::get(om, "quantity");
    if (const Val* m = Reader::get(om, "model")) {
      const std::string mn = r.choice(*m, {"analytic", "perfoot", "mujoco"});
      s.objective_model = mn == "perfoot" ? ObjectiveModel::kPerFoot
                          : mn == "mujoco" ? ObjectiveModel::kMujoco
                                           : ObjectiveModel::kAnalytic;
    }
    s.problem.search_model =
        s.objective_model == ObjectiveModel::kAnalytic ? ObjectiveModel::kAnalytic : ObjectiveModel::kPerFoot;
    const Val* search = Reader::get(om, "search");
    const Val* cand = Reader::get(om, "candidates");
    if (s.objective_model != ObjectiveModel::kMujoco) {
      if (search) r.fail(*search, "only used with model: mujoco (the model the candidates are searched on)");
      if (cand) r.fail(*cand, "only used with model: mujoco (how many of the search's best MuJoCo re-ranks)");
    } else {
      if (search)
        s.problem.search_model =
            r.choice(*search, {"analytic", "perfoot"}) == "perfoot" ? ObjectiveModel::kPerFoot : ObjectiveModel::kAnalytic;
      s.problem.keep_candidates = cand ? r.integer(*cand, 1, kMaxMujocoCandidates) : 8;
    }
  }
  if (q) {
    const std::string ob = r.choice(*q, {"phi_net", "phi_net_per_torque", "phi_net_per_energy"});
    s.problem.objective = ob == "phi_net" ? StrokeObjective::kPhiNet
                          : ob == "phi_net_per_torque" ? StrokeObjective::kPhiNetPerTorque
                                                       : StrokeObjective::kPhiNetPerEnergy;
  }
}

// Stage: optimize.limits (its map l). The angle range, speed and torque limits: here (a value for
// every joint, or a list of one per joint), or the robot file's (each joint's tail-entry
// theta_min_deg/theta_max_deg, thetadot_max_dps, torque_max_Nm; resolved once the base is read);
// the others into sp.limits.
LimitKeys readLimits(const Reader& r, const Map& l, StrokeSpace& sp) {
  StrokeLimits& L = sp.limits;
  LimitKeys k;
  FileLimit& theta = k.theta;
  if ((theta.at = Reader::get(l, "theta_deg"))) {
    auto pair = [&](const Val& v) {
      const auto [lo, hi] = r.interval(v, -360.0, 360.0);
      if (!(hi > lo)) r.fail(v, "the range must not be empty");
      theta.values.insert(theta.values.end(), {lo * kRadPerDeg, hi * kRadPerDeg});
    };
    theta.per_joint = theta.at->node.IsSequence() && theta.at->node.size() > 0 && theta.at->node[0].IsSequence();
    if (theta.per_joint)
      for (const Val& e : r.list(*theta.at, 1, 64)) pair(e);
    else
      pair(*theta.at);
  }
  auto numbers = [&](FileLimit& f, double lo, double hi, double scale) {
    f.per_joint = f.at->node.IsSequence();
    if (f.per_joint)
      for (const Val& e : r.list(*f.at, 1, 64)) f.values.push_back(r.inRange(e, lo, hi) * scale);
    else
      f.values.push_back(r.inRange(*f.at, lo, hi) * scale);
  };
  if ((k.speed.at = Reader::get(l, "thetadot_max_dps"))) numbers(k.speed, 1.0, 36000.0, kRadPerDeg);
  k.torque_key = Reader::get(l, "torque_max_Nm");
  k.torque_word = k.torque_key && k.torque_key->node.IsScalar() &&
                  (k.torque_key->node.Scalar() == "base" || k.torque_key->node.Scalar() == "none");
  if (k.torque_key && !k.torque_word) {
    k.torque.at = k.torque_key;
    k.torque.per_joint = k.torque_key->node.IsSequence();
    for (const Val& e : k.torque.per_joint ? r.list(*k.torque_key, 1, 64) : std::vector<Val>{*k.torque_key}) {
      const double v = r.number(e);
      if (!(v > 0.0)) r.fail(e, "must be > 0, base (the base stroke's peak) or none (no torque limit), got " + fmtG(v));
      k.torque.values.push_back(v);
    }
  }
  if (k.torque_word) L.torque_max_Nm = 0.0;  // none; base: set below from the base stroke
  if (const Val* e = Reader::get(l, "end")) {
    L.end = r.choice(*e, {"rest", "start"}) == "start" ? StrokeEnd::kAtStart : StrokeEnd::kAtRest;
    if (L.end == StrokeEnd::kAtStart && sp.family == StrokeFamily::kSplitCycle)
      r.fail(*e, "a split-cycle stroke moves by dtheta and cannot end where it started: use family: spline");
  }
  if (const Val* d = Reader::get(l, "dT_s")) {
    const auto [a, b] = r.interval(*d, 0.01, 10.0);
    L.dT_min_s = a;
    L.dT_max_s = b;
  }
  if (const Val* w = Reader::get(l, "w_ss")) {
    if (sp.family != StrokeFamily::kSplitCycle) r.fail(*w, "only used with family: split_cycle");
    const auto [a, b] = r.interval(*w, 0.01, 0.99);
    L.w_ss_min = a;
    L.w_ss_max = b;
  }
  if (const Val* t = Reader::get(l, "start_delay_s")) L.t0_max_s = r.inRange(*t, 0.0, 10.0);
  if (const Val* v = Reader::get(l, "over_torque")) sp.slow_down_over_torque = r.choice(*v, {"penalize", "slow_down"}) == "slow_down";
  return k;
}

// Stage: the optimizer's settings (algorithm to max_runs) into os; returns the directions_kept key.
const Val* readOptimizer(const Reader& r, const Map& o, const StrokeSpace& sp, OptimizerSettings& os) {
  if (const Val* v = Reader::get(o, "algorithm")) os.algorithm = r.choice(*v, {"cmaes", "de"});
  if (const Val* v = Reader::get(o, "islands")) os.islands = r.integer(*v, 1, kMaxIslands);
  if (const Val* v = Reader::get(o, "population")) os.population = r.integer(*v, 5, kMaxPopulation);
  if (const Val* v = Reader::get(o, "generations")) os.generations = r.integer(*v, 1, kMaxGenerations);
  if (const Val* v = Reader::get(o, "restarts")) os.restarts = r.integer(*v, 1, kMaxRestarts);
  if (const Val* v = Reader::get(o, "restart_growth")) {
    os.restart_growth = r.integer(*v, 1, 4);
    double last = os.population;  // the last restart's population must stay within the limit
    for (int i = 1; i < os.restarts; ++i) last *= os.restart_growth;
    if (last > kMaxPopulation)
      r.fail(*v, "gives the last restart a population of " + fmtG(last) + ", over " + std::to_string(kMaxPopulation) +
                     " (population x restart_growth^(restarts - 1))");
  }
  if (const Val* v = Reader::get(o, "refine_generations")) os.refine_generations = r.integer(*v, 0, kMaxGenerations);
  if (const Val* v = Reader::get(o, "directions")) {
    os.enumerate_directions = r.choice(*v, {"free", "enumerate"}) == "enumerate";
    if (os.enumerate_directions && sp.family != StrokeFamily::kSplitCycle)
      r.fail(*v, "enumerate needs family: split_cycle (the spline family has no single stroke direction per joint)");
  }
  if (const Val* v = Reader::get(o, "local_restarts")) os.local_restarts = r.integer(*v, 0, kMaxLocalRestarts);
  if (const Val* v = Reader::get(o, "local_step")) {
    os.local_step = r.inRange(*v, 0.0, 1.0);
    if (!(os.local_step > 0.0)) r.fail(*v, "must be > 0 (a share of the unit box), got " + fmtG(os.local_step));
  }
  const Val* kept = Reader::get(o, "directions_kept");
  if (kept) {
    os.directions_kept = r.integer(*kept, 0, 1 << kMaxKeptDirectionsLog2);
    if (!os.enumerate_directions) r.fail(*kept, "only used with directions: enumerate");
  }
  if (const Val* v = Reader::get(o, "polish")) os.polish = r.choice(*v, {"cobyla", "bobyqa", "none"});
  if (const Val* v = Reader::get(o, "polish_evaluations")) os.polish_evaluations = r.integer(*v, 0, kMaxPolishEvaluations);
  if (const Val* v = Reader::get(o, "restart_polish_evaluations"))
    os.restart_polish_evaluations = r.integer(*v, 0, kMaxPolishEvaluations);
  if (const Val* v = Reader::get(o, "max_runs")) {
    os.max_runs = r.integer(*v, 0, static_cast<int>(limits::kMaxOptimizeRuns));
    const long least = 2 + static_cast<long>(os.islands) * os.population + (os.polish != "none" ? os.polish_evaluations : 0);
    if (os.max_runs > 0 && os.max_runs < least)
      r.fail(*v, "must be 0 (no cap) or at least " + std::to_string(least) +
                     " (the start, one population of every island and the polish's polish_evaluations), got " +
                     std::to_string(os.max_runs));
  }
  return kept;
}

// Stage: seeds, pareto_points, min_turn_deg and mujoco_check.
void readRunSettings(const Reader& r, const Map& o, OptimizeSpec& s) {
  if (const Val* v = Reader::get(o, "seeds")) {
    s.seeds.clear();
    for (const Val& e : r.list(*v, 1, kMaxSeeds)) {
      const int x = r.integer(e, 0, 1000000000);
      if (std::find(s.seeds.begin(), s.seeds.end(), static_cast<std::uint64_t>(x)) != s.seeds.end())
        r.fail(e, "duplicate seed " + std::to_string(x));
      s.seeds.push_back(static_cast<std::uint64_t>(x));
    }
  }
  if (const Val* v = Reader::get(o, "pareto_points")) {
    s.pareto_points = r.integer(*v, 0, kMaxParetoPoints);
    if (s.pareto_points == 1) r.fail(*v, "a front needs 0 (none) or at least 2 points");
  }
  if (const Val* v = Reader::get(o, "min_turn_deg")) s.min_turn_deg = r.inRange(*v, 0.0, 90.0);
  if (const Val* v = Reader::get(o, "mujoco_check")) {
    s.mujoco_check = r.boolean(*v);
    if (!s.mujoco_check && s.objective_model == ObjectiveModel::kMujoco)
      r.fail(*v, "objective model: mujoco runs MuJoCo on the candidates: leave mujoco_check true");
  }
}

// Stage: the base experiment, through the loader (its errors name the base file): one split-cycle
// simulate case, whose tail gives the search's n.
void readBase(const Reader& r, const Val& base, OptimizeSpec& s) {
  const Experiment e = loadExperiment(s.base_file);
  if (e.cases.size() != 1)
    r.fail(base, "the base experiment must have exactly one case (no sweeps), it has " + std::to_string(e.cases.size()));
  s.base = e.cases.front();
  design_yaml::refuseModelFileBase(r, base, s.base.robot_model.has_value(), "optimize");
  if (s.base.kind != CaseKind::kSimulate) r.fail(base, "the base experiment must be kind: simulate");
  if (!s.base.splines.empty())
    r.fail(base, "the base experiment's trajectory is the search's start and must be split-cycle (not family: spline)");
  s.problem.space.n_links = s.base.robot.numLinks();
}

// Stage: the search's size within the work limits: the kept and enumerated direction patterns for
// the base's n, the analytic runs and their solver steps.
void checkSearchSize(const Reader& r, const Map& o, const Val& opt, const Val* kept, const OptimizeSpec& s) {
  const OptimizerSettings& os = s.optimizer;
  const int n = s.problem.space.n_links;
  if (kept && n <= kMaxKeptDirectionsLog2 && os.directions_kept > (1 << n))
    r.fail(*kept, "keeps " + std::to_string(os.directions_kept) + " patterns, but an n = " + std::to_string(n) +
                      " tail has only " + std::to_string(1 << n));
  if (os.enumerate_directions && n > limits::kMaxEnumeratedLinks)
    r.fail(*Reader::get(o, "directions"),
           "enumerate would search 2^" + std::to_string(n) + " = " + fmtG(std::ldexp(1.0, n)) +
               " joint-direction patterns for the base's n = " + std::to_string(n) + " tail, more than 2^" +
               std::to_string(limits::kMaxEnumeratedLinks) + " = " +
               std::to_string(1 << limits::kMaxEnumeratedLinks) + " (n <= " +
               std::to_string(limits::kMaxEnumeratedLinks) + "): use directions: free");
  if (const double runs = optimizeRunEstimate(s); !(runs <= limits::kMaxOptimizeRuns))
    r.fail(opt, "the search would run the analytic model about " + fmtG(runs) +
                    " times (seeds + pareto_points) x (islands x population x (generations + 1 + refine_generations) "
                    "per restart + local restarts + polish_evaluations)" +
                    (os.enumerate_directions ? " x 2^n patterns" : "") + ", more than the limit " +
                    fmtG(limits::kMaxOptimizeRuns) +
                    " (docs/design-a-tail-stroke.md \"Limits\"): lower generations, population, islands, restarts or seeds");
  // A run's cost is the base's: its analytic steps (a fixed or bounded step may make a run seconds long).
  if (const double runs = optimizeRunEstimate(s), per_run = std::max(1.0, estimateWork(s.base).solverSteps());
      !(runs * per_run <= limits::kMaxOptimizeSteps))
    r.fail(opt, "the search would take about " + fmtG(runs * per_run) + " analytic solver steps (about " + fmtG(runs) +
                    " runs x at least " + fmtG(per_run) +
                    " steps a run, as the base experiment's stroke and analytic settings take), more than the limit " +
                    fmtG(limits::kMaxOptimizeSteps) +
                    " (docs/design-a-tail-stroke.md \"Limits\"): lower generations, population, islands, restarts or "
                    "seeds, or give the base a coarser analytic step (analytic.fixed_dt_s, analytic.max_step_s)");
}

// Stage: limits that leave no stroke to search are refused here, not after a whole search that could
// only report "limits VIOLATED": a 1 deg split-cycle stroke of every joint over the longest duration
// must keep them.
void requireSearchableLimits(const Reader& r, const Val& lv, const OptimizeSpec& s) {
  const StrokeLimits& L = s.problem.space.limits;
  const double amp = 1.0 * kRadPerDeg;
  TailTrajectory probe;
  double narrowest = 1e300;
  for (int i = 0; i < s.problem.space.n_links; ++i) {
    const JointLimits J = L.joint(static_cast<std::size_t>(i));
    SplitCycleParams p;
    p.theta0_rad = std::max(J.theta_min_rad, std::min(0.0, J.theta_max_rad - amp));
    p.dtheta_rad = amp;
    p.dT_s = L.dT_max_s;
    p.w_ss = std::max(L.w_ss_min, std::min(0.5, L.w_ss_max));
    probe.joints.emplace_back(p);
    narrowest = std::min(narrowest, J.theta_max_rad - J.theta_min_rad);
  }
  StrokeLimits at_rest = L;  // a stroke that must end where it started is a spline's: not this probe
  at_rest.end = StrokeEnd::kAtRest;
  const StrokeFigures f = strokeFigures(s.base.robot.tail, probe);
  if (!(narrowest < amp || limitViolation(f, at_rest) > 0.0)) return;
  std::string which;  // the joints whose limits the probe breaks; the first is described
  std::size_t first = f.joints.size();
  for (std::size_t i = 0; i < f.joints.size(); ++i) {
    StrokeLimits one = at_rest;
    StrokeFigures fi;
    fi.joints = {f.joints[i]};
    one.joints = {L.joint(i)};
    if (L.joint(i).theta_max_rad - L.joint(i).theta_min_rad < amp || limitViolation(fi, one) > 0.0) {
      which += (which.empty() ? "" : ", ") + std::to_string(i + 1);
      first = std::min(first, i);
    }
  }
  if (which.empty()) which = "1";
  if (first == f.joints.size()) first = 0;
  const JointLimits J = L.joint(first);
  const JointFigures& g = f.joints.at(first);
  r.fail(lv, "no stroke keeps these limits: 1 deg of every joint over the longest duration (dT_s " +
                 fmtG(L.dT_max_s) + " s) breaks them at joint " + which +
                 ": it needs a range of 1 deg (have " + fmtG((J.theta_max_rad - J.theta_min_rad) / kRadPerDeg) +
                 "), peaks at " + fmtG(g.peak_speed_radps / kRadPerDeg) + " deg/s (limit " +
                 fmtG(J.thetadot_max_radps / kRadPerDeg) + ") and " + fmtG(g.peak_torque_Nm) + " N m (limit " +
                 (J.torque_max_Nm > 0 ? fmtG(J.torque_max_Nm) : std::string("none")) + "): widen them");
}
}  // namespace

bool isOptimizeFile(const std::string& path) {
  try {
    const YAML::Node doc = loadBoundedYaml(fs::absolute(path).lexically_normal().string());
    return doc.IsMap() && doc["kind"] && doc["kind"].IsScalar() && doc["kind"].Scalar() == "optimize";
  } catch (const std::exception&) {
    return false;
  }
}

double optimizeRunEstimate(const OptimizeSpec& s) {
  const OptimizerSettings& o = s.optimizer;
  auto restartRuns = [&](int r) {
    const double pop = o.population * std::pow(static_cast<double>(o.restart_growth), r);
    return o.islands * pop * (o.generations + 1.0 + o.refine_generations);
  };
  double later = 0;  // the restarts after the first, the local restarts and the polish
  const double restart_polish = o.polish != "none" ? o.restart_polish_evaluations : 0.0;
  for (int r = 1; r < o.restarts; ++r) later += restartRuns(r) + restart_polish;
  later += o.local_restarts * static_cast<double>(o.islands) * o.population * (o.generations + 1.0);
  if (o.polish != "none") later += o.polish_evaluations;
  const double first = 2.0 + restartRuns(0) + restart_polish;  // the start (base stroke and its box point) and restart 0
  double per_search = first + later;
  if (o.enumerate_directions) {
    const double patterns = std::ldexp(1.0, std::min(s.problem.space.n_links, 1000));
    const double kept = o.directions_kept > 0 ? std::min<double>(o.directions_kept, patterns) : patterns;
    per_search = patterns * first + kept * later;
    if (o.max_runs > 0) per_search = std::min(per_search, static_cast<double>(o.max_runs));
  } else if (o.max_runs > 0) {
    per_search = std::min(per_search, static_cast<double>(o.max_runs));
  }
  return per_search * static_cast<double>(s.seeds.size() + static_cast<std::size_t>(s.pareto_points));
}

// The stages in order: the file's head, family and knots, objective, limits, optimizer and run
// settings, the base experiment, the search's size, the joint limits resolved on the base, the probe.
OptimizeSpec loadOptimizeSpec(const std::string& path) {
  OptimizeSpec s;
  s.source_file = fs::absolute(path).lexically_normal().string();
  const Reader r(s.source_file);
  design_yaml::DesignFile file = design_yaml::openDesignFile(r, s.source_file, "optimize", "optimize",
                                                                      kMaxNameChars - (sizeof kBestNameSuffix - 1));
  s.name = std::move(file.head.name);
  s.description = std::move(file.head.description);
  s.base_file = std::move(file.head.base_file);
  const Val& base = file.base(r);  // the base experiment's own checks below point here
  const Val& opt = file.section(r);
  // The allowed keys (and their order in "allowed here") from the declaration (settings/optimize_section.h).
  static const std::vector<std::string> kOptimizeKeys = settings::declaredKeys<OptimizeSection>();
  static const std::vector<std::string> kLimitsKeys = settings::declaredKeys<OptimizeLimitsSection>();
  const auto o = r.map(opt, kOptimizeKeys);
  StrokeSpace& sp = s.problem.space;
  sp.family = r.choice(design_yaml::need(r, o, opt, "family"), {"split_cycle", "spline"}) == "spline"
                  ? StrokeFamily::kSpline
                  : StrokeFamily::kSplitCycle;
  if (const Val* k = Reader::get(o, "knots")) {
    if (sp.family != StrokeFamily::kSpline) r.fail(*k, "only used with family: spline");
    sp.knots = r.integer(*k, 0, kMaxKnots);
  }
  readObjective(r, o, s);
  const Val& lv = design_yaml::need(r, o, opt, "limits");
  const auto l = r.map(lv, kLimitsKeys);
  const LimitKeys lk = readLimits(r, l, sp);
  const Val* kept = readOptimizer(r, o, sp, s.optimizer);
  readRunSettings(r, o, s);
  readBase(r, base, s);
  checkSearchSize(r, o, opt, kept, s);
  StrokeLimits& L = sp.limits;
  if (lk.torque_word && lk.torque_key->node.Scalar() == "base") {  // the base stroke's own peak joint torque
    L.torque_max_Nm = strokeFigures(s.base.robot.tail, s.base.trajectory()).peak_torque_Nm;
    if (!(L.torque_max_Nm > 0.0)) r.fail(*lk.torque_key, "base: the base stroke has no joint torque to keep");
  }
  resolveJointLimits(r, lv, s.base, lk.theta, lk.speed, lk.torque, lk.torque_word, L, s.limit_overrides);
  requireSearchableLimits(r, lv, s);
  sp.tail = s.base.robot.tail;
  s.problem.base = s.base;
  return s;
}

}  // namespace tailsim
