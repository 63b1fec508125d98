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
#include "experiments/work_estimate.h"
#include "results/work_limits.h"

namespace tailsim {
namespace {

using namespace design_yaml;

// The keys a struct declares (settings/fields.h).
struct KeyList {
  std::vector<std::string> keys;
  template <class... T>
  void number(const settings::Field& f, T&&...) { keys.push_back(f.key); }
  template <class... T>
  void integer(const settings::Field& f, T&&...) { keys.push_back(f.key); }
  template <class... T>
  void boolean(const settings::Field& f, T&&...) { keys.push_back(f.key); }
};

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
  if (s.min_scale * s.stroke_dT_s < limits::kMinDT_s)
    r.fail(firstSet(mv, m, {"min_scale", "stroke_dT_s"}),
           "the shortest stroke (min_scale x stroke_dT_s = " + fmtG(s.min_scale) + " x " + fmtG(s.stroke_dT_s) + " = " +
               fmtG(s.min_scale * s.stroke_dT_s) + " s) is shorter than an experiment's trajectory.dT_s may be (" +
               fmtG(limits::kMinDT_s) + " s): raise min_scale or stroke_dT_s");
  if (s.return_dT_s < limits::kMinDT_s)
    r.fail(firstSet(mv, m, {"return_dT_s"}), "must be at least " + fmtG(limits::kMinDT_s) +
                                                 " s (as an experiment's trajectory.dT_s), got " + fmtG(s.return_dT_s));
  const int n = spec.base.robot.numLinks();
  auto atZero = [](const TailTrajectory& t) {
    std::vector<SplitCycleParams> joints;
    for (const auto& j : t.joints) {
      SplitCycleParams p = j.params();
      p.t0_s = 0.0;
      joints.push_back(p);
    }
    return joints;
  };
  // The analytic segments: each stroke run alone with the rest after it (analyticCycleYaw, the plan).
  for (const double scale : {s.min_scale, 1.0}) {
    const CycleStrokes cs = cycleStrokes(s, n, {scale, 1}, 0.0);
    for (int part = 0; part < 2; ++part) {
      ExperimentCase c = spec.base;
      c.splines.clear();
      c.joints = atZero(part == 0 ? cs.fast : cs.back);
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
  // The MuJoCo closed loop: at most max_strokes cycles (runManeuver's duration), one run.
  if (s.mujoco) {
    ExperimentCase c = spec.base;
    c.splines.clear();
    c.joints = atZero(cycleStrokes(s, n, {1.0, 1}, 0.0).fast);
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
  KeyList kl;
  declareFields(kl, static_cast<const ManeuverSettings&>(s.settings));
  if (!mv.node.IsMap()) r.fail(mv, "expected a map of key: value");
  std::vector<std::pair<std::string, Val>> m;
  {
    // Reader::map takes the allowed keys as an initializer list: check them here from the declaration.
    for (const auto& kv : mv.node) {
      const std::string key = "maneuver." + kv.first.Scalar();
      if (!kv.first.IsScalar()) r.fail(kv.first.Mark(), "maneuver", "keys must be plain names");
      if (std::find(kl.keys.begin(), kl.keys.end(), kv.first.Scalar()) == kl.keys.end())
        r.fail(kv.first.Mark(), key, unknownKeyMessage(kv.first.Scalar(), kl.keys));
      for (const auto& e : m)
        if (e.first == kv.first.Scalar()) r.fail(kv.first.Mark(), key, "duplicate key");
      const bool empty = kv.second.IsNull() || kv.second.Mark().is_null();
      m.emplace_back(kv.first.Scalar(), Val{kv.second, key, empty ? kv.first.Mark() : kv.second.Mark()});
    }
  }
  YamlFieldReader fr{r, m};
  declareFields(fr, s.settings);
  if (s.settings.min_scale > 1.0) r.fail(*Reader::get(m, "min_scale"), "must be <= 1");

  const Experiment e = loadExperiment(s.base_file);
  if (e.cases.size() != 1)
    r.fail(base, "the base experiment must have exactly one case (no sweeps), it has " + std::to_string(e.cases.size()));
  s.base = e.cases.front();
  if (s.base.kind != CaseKind::kSimulate) r.fail(base, "the base experiment must be kind: simulate");
  checkStrokes(r, mv, m, s);
  return s;
}


}  // namespace tailsim
