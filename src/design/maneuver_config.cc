// Reading `kind: maneuver` files (maneuver.h): the head and base through design_yaml.h, the
// maneuver section from the declared fields, and every stroke and run the maneuver will ask of the
// models checked as the experiment loader checks a trajectory and its work, at the maneuver key
// that sets it, before any work.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "design/design_yaml.h"
#include "design/maneuver.h"
#include "design/stroke_family.h"
#include "experiments/experiment_loader.h"
#include "experiments/work_estimate.h"
#include "common/units.h"
#include "common/work_limits.h"

namespace tailsim {
namespace {

using namespace design_yaml;

// Reads the declared fields from a YAML map through design_yaml::Reader (file:line:col errors).
struct YamlFieldReader {
  const Reader& r;
  const std::vector<std::pair<std::string, Val>>& m;
  void number(const settings::Field& f, double& x, const settings::Limits& l) {
    const Val* v = Reader::get(m, f.key);
    if (!v) return;
    const double y = r.number(*v);
    if (!l.ok(y)) r.fail(*v, "must " + l.text() + ", got " + fmtG(y));
    x = y;
  }
  void integer(const settings::Field& f, int& x, const settings::Limits& l) {
    if (const Val* v = Reader::get(m, f.key)) x = r.integer(*v, static_cast<int>(l.lo), static_cast<int>(l.hi));
  }
  void boolean(const settings::Field& f, bool& x) {
    if (const Val* v = Reader::get(m, f.key)) x = r.boolean(*v);
  }
};

// The case's trajectory set to t (split-cycle joints or spline joints).
void setTrajectory(ExperimentCase& c, const TailTrajectory& t) {
  c.joints.clear();
  c.splines.clear();
  for (const auto& j : t.joints) {
    if (j.isSpline()) c.splines.push_back(j.spline());
    else c.joints.push_back(j.params());
  }
}

// The first of `keys` the section sets, else the section itself: where an error points.
const Val& firstSet(const Val& section, const std::vector<std::pair<std::string, Val>>& m,
                    std::initializer_list<const char*> keys) {
  for (const char* k : keys)
    if (const Val* v = Reader::get(m, k)) return *v;
  return section;
}

// Every stroke a maneuver runs is a split-cycle trajectory the experiment loader would have to
// accept (dT and w_ss ranges, the analytic model's work per segment), and the longest MuJoCo run
// (the closed loop: max_strokes cycles) must keep the per-run work limits.
void checkStrokes(const Reader& r, const Val& mv, const std::vector<std::pair<std::string, Val>>& m,
                  const ManeuverSpec& spec) {
  const ManeuverSettings& s = spec.settings;
  for (const auto& [key, w] : {std::pair<const char*, double>{"stroke_w_ss", s.stroke_w_ss}, {"return_w_ss", s.return_w_ss}})
    if (w < limits::kMinWss || w > limits::kMaxWss)
      r.fail(firstSet(mv, m, {key}), "must lie in [" + fmtG(limits::kMinWss) + ", " + fmtG(limits::kMaxWss) +
                                         "] (as an experiment's trajectory.w_ss), got " + fmtG(w));
  const int n = spec.base.robot.numLinks();
  if (spec.min_scale_given && s.min_scale < minScaleFloor(s, n))
    r.fail(firstSet(mv, m, {"min_scale", "stroke_dT_s"}),
           "the shortest stroke (min_scale " + fmtG(s.min_scale) + " x the fast stroke's shortest joint duration) is shorter "
           "than an experiment's trajectory.dT_s may be (" + fmtG(limits::kMinDT_s) + " s): min_scale must be at least " +
               fmtG(minScaleFloor(s, n)) + " (or leave it out: derived from tolerance_deg)");
  if (s.return_dT_s < limits::kMinDT_s)
    r.fail(firstSet(mv, m, {"return_dT_s"}), "must be at least " + fmtG(limits::kMinDT_s) +
                                                 " s (as an experiment's trajectory.dT_s), got " + fmtG(s.return_dT_s));
  // The analytic segments: each stroke run alone with the rest after it (analyticCycleYaw, the plan).
  for (const double scale : {spec.min_scale_given ? s.min_scale : minScaleFloor(s, n), 1.0}) {
    const CycleStrokes cs = cycleStrokes(s, n, {scale, 1}, 0.0);
    for (int part = 0; part < 2; ++part) {
      ExperimentCase c = spec.base;
      setTrajectory(c, shiftedToZero(part == 0 ? cs.fast : cs.back));
      c.models = {"analytic"};
      c.render.enabled = false;
      c.output.duration_s = (part == 0 ? cs.fast.endTime() : s.return_dT_s) + s.rest_s;
      c.output.time_series = TimeSeriesOutput::kFull;
      if (const WorkExcess x = checkWork(c); !x.what.empty())
        r.fail(firstSet(mv, m, part == 0 ? std::initializer_list<const char*>{"stroke_dT_s", "min_scale", "rest_s"}
                                         : std::initializer_list<const char*>{"return_dT_s", "rest_s"}),
               std::string("the ") + (part == 0 ? "fast stroke" : "return") + " at scale " + fmtG(scale) +
                   " asks too much of the analytic model: " + x.what);
    }
  }
  // The fast stroke at full scale within the robot's own actuator limits, where its tail entry gives
  // them (tail base held still, as the optimiser's figures): a stroke the robot cannot make is no plan.
  // 1 % is allowed over: a stroke searched onto a limit, sampled on another 0.5 ms grid once shifted
  // to start at 0, peaks a little apart (a best.yaml at 6 N m showed 6.0009 here).
  constexpr double kAllowed = 1.01;
  const StrokeFigures f = strokeFigures(spec.base.robot.tail, shiftedToZero(cycleStrokes(s, n, {1.0, 1}, 0.0).fast));
  for (int i = 0; i < n && i < static_cast<int>(f.joints.size()); ++i) {
    const TailLink& k = spec.base.robot.tail[i];
    const JointFigures& j = f.joints[i];
    std::string over;
    if (k.torque_max_Nm > 0.0 && j.peak_torque_Nm > kAllowed * k.torque_max_Nm)
      over = "a peak torque of " + fmtG(j.peak_torque_Nm) + " N m, over its " + fmtG(k.torque_max_Nm) + " N m";
    else if (k.thetadot_max_radps > 0.0 && j.peak_speed_radps > kAllowed * k.thetadot_max_radps)
      over = "a peak speed of " + fmtG(units::degrees(j.peak_speed_radps)) + " deg/s, over its " +
             fmtG(units::degrees(k.thetadot_max_radps)) + " deg/s";
    if (!over.empty())
      r.fail(firstSet(mv, m, {"stroke_from", "stroke_dT_s", "stroke_deg"}),
             "the fast stroke needs " + over + " at joint " + std::to_string(i + 1) +
                 " (the robot file's tail entry; 1 % over is allowed): the robot cannot make it; use a slower stroke (stroke_dT_s, or a "
                 "tailsim optimize best.yaml searched within these limits)");
  }
  // The MuJoCo closed loop: at most max_strokes cycles (runManeuver's duration), one run.
  if (s.mujoco) {
    ExperimentCase c = spec.base;
    setTrajectory(c, shiftedToZero(cycleStrokes(s, n, {1.0, 1}, 0.0).fast));
    c.models = {"mujoco"};
    c.render.enabled = false;
    c.output.duration_s = s.max_strokes * (cycleDuration(s, 1.0) + 0.2) + 0.5;
    c.output.time_series = TimeSeriesOutput::kFull;
    if (const WorkExcess x = checkWork(c); !x.what.empty())
      r.fail(firstSet(mv, m, {"max_strokes", "return_dT_s", "rest_s"}),
             "the MuJoCo closed loop may run max_strokes x (cycle + 0.2 s) + 0.5 s = " + fmtG(c.output.duration_s) +
                 " s: " + x.what);
  }
}

}  // namespace

ManeuverSpec loadManeuverSpec(const std::string& path) {
  ManeuverSpec s;
  s.source_file = fs::absolute(path).lexically_normal().string();
  const Reader r(s.source_file);
  design_yaml::DesignFile file = design_yaml::openDesignFile(r, s.source_file, "maneuver", "maneuver");
  s.name = std::move(file.head.name);
  s.description = std::move(file.head.description);
  s.base_file = std::move(file.head.base_file);
  const Val& base = file.base(r);  // the base experiment's own checks below point here
  const Val& mv = file.section(r);
  std::vector<std::string> allowed = settings::declaredKeys<ManeuverSettings>();
  if (!mv.node.IsMap()) r.fail(mv, "expected a map of key: value");
  std::vector<std::pair<std::string, Val>> m;
  {
    // Reader::map takes the allowed keys as an initializer list: check them here from the declaration.
    allowed.push_back("stroke_from");  // not a declared number: a trajectory's source (below)
    for (const auto& kv : mv.node) {
      const std::string key = "maneuver." + kv.first.Scalar();
      if (!kv.first.IsScalar()) r.fail(kv.first.Mark(), "maneuver", "keys must be plain names");
      if (std::find(allowed.begin(), allowed.end(), kv.first.Scalar()) == allowed.end())
        r.fail(kv.first.Mark(), key, unknownKeyMessage(kv.first.Scalar(), allowed));
      for (const auto& e : m)
        if (e.first == kv.first.Scalar()) r.fail(kv.first.Mark(), key, "duplicate key");
      const bool empty = kv.second.IsNull() || kv.second.Mark().is_null();
      m.emplace_back(kv.first.Scalar(), Val{kv.second, key, empty ? kv.first.Mark() : kv.second.Mark()});
    }
  }
  YamlFieldReader fr{r, m};
  declareFields(fr, s.settings);
  if (s.settings.min_scale > 1.0) r.fail(*Reader::get(m, "min_scale"), "must be <= 1");
  s.min_scale_given = Reader::get(m, "min_scale") != nullptr;
  const Val* from = Reader::get(m, "stroke_from");
  if (from)
    for (const char* k : {"stroke_deg", "stroke_dT_s", "stroke_w_ss"})
      if (const Val* v = Reader::get(m, k))
        r.fail(*v, std::string("not used with stroke_from (the fast stroke is that trajectory)"));

  const Experiment e = loadExperiment(s.base_file);
  if (e.cases.size() != 1)
    r.fail(base, "the base experiment must have exactly one case (no sweeps), it has " + std::to_string(e.cases.size()));
  s.base = e.cases.front();
  design_yaml::refuseModelFileBase(r, base, s.base.robot_model.has_value(), "maneuver");
  if (s.base.kind != CaseKind::kSimulate) r.fail(base, "the base experiment must be kind: simulate");
  if (from) {
    // stroke_from: base (the base experiment's trajectory) or the path of a one-case experiment
    // file (relative to this file), e.g. a `tailsim optimize` best.yaml: its trajectory, split-cycle
    // or spline, is the fast stroke at full scale.
    const std::string v = r.text(*from);
    TailTrajectory t;
    if (v == "base") {
      t = s.base.trajectory();
    } else {
      s.stroke_file = (fs::path(s.source_file).parent_path() / v).lexically_normal().string();
      std::error_code ec;
      if (!fs::is_regular_file(s.stroke_file, ec)) r.fail(*from, "no such experiment file: " + s.stroke_file);
      const Experiment se = loadExperiment(s.stroke_file);
      if (se.cases.size() != 1 || se.cases.front().kind != CaseKind::kSimulate)
        r.fail(*from, s.stroke_file + " must be a one-case kind: simulate experiment (e.g. a tailsim optimize best.yaml)");
      t = se.cases.front().trajectory();
    }
    if (static_cast<int>(t.joints.size()) != s.base.robot.numLinks())
      r.fail(*from, "the stroke moves " + std::to_string(t.joints.size()) + " joints, the base's tail has " +
                        std::to_string(s.base.robot.numLinks()));
    s.settings.stroke_shape = shiftedToZero(t);
  }
  checkStrokes(r, mv, m, s);
  const Val& at = firstSet(mv, m, {"max_strokes"});
  s.max_strokes_at = s.source_file + ":" + std::to_string(at.mark.line + 1) + ":" + std::to_string(at.mark.column + 1) +
                     ": " + (at.key.empty() ? std::string("maneuver") : at.key);
  return s;
}


}  // namespace tailsim
