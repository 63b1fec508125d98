#include "experiments/settings_schema.h"

#include "controllers/heading_controller.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <type_traits>

#include "experiments/experiment_config.h"
#include "experiments/experiment_loader.h"
#include "experiments/model_registry.h"
#include "common/work_limits.h"
#include "common/number_text.h"
#include "settings/optimize_section.h"
#include "settings/trajectory_section.h"

namespace tailsim {
namespace {

using json = nlohmann::json;

json sweepRef() { return {{"$ref", "#/$defs/sweep"}}; }
// A value, or a sweep replacing it.
json orSweep(json value) { return {{"anyOf", json::array({std::move(value), sweepRef()})}}; }

void limitsInto(json& s, const settings::Limits& l) {
  if (l.hasLo()) s[l.lo_open ? "exclusiveMinimum" : "minimum"] = l.lo;
  if (l.hasHi()) s[l.hi_open ? "exclusiveMaximum" : "maximum"] = l.hi;
}

// A number for all joints, or one per joint.
json perJointSchema(json value, const std::string& doc) {
  json one = orSweep(value);
  return {{"description", doc},
          {"anyOf", json::array({value, sweepRef(), {{"type", "array"}, {"minItems", 1}, {"items", one}}})}};
}

// One declared struct -> schema properties and Markdown rows.
struct Describer {
  json props = json::object();
  std::string rows;
  bool sweeps = true;  // false: a design file's section (no sweeps)
  void add(const settings::Field& f, json value, const std::string& allowed, const std::string& dflt) {
    json p = sweeps ? orSweep(std::move(value)) : std::move(value);
    p["description"] = f.doc;
    props[f.key] = std::move(p);
    std::string doc = f.doc;
    for (char& ch : doc)
      if (ch == '|') ch = '/';
    rows += "| `" + std::string(f.key) + "` | " + allowed + " | " + (dflt.empty() ? std::string("(none)") : dflt) + " | " + doc + " |\n";
  }
  void number(const settings::Field& f, double x, const settings::Limits& l) {
    json v = {{"type", "number"}};
    limitsInto(v, l);
    const std::string t = l.text();
    add(f, v, t.empty() ? "number" : "number, " + t.substr(t.find(' ') + 1), defaultText(x));
  }
  // A number for every joint, or a list of one per joint.
  void perJoint(const settings::Field& f, double x, const settings::Limits& l) {
    json v = {{"type", "number"}};
    limitsInto(v, l);
    const std::string t = l.text();
    add(f, v, t.empty() ? "number or one per joint" : "number or one per joint, " + t.substr(t.find(' ') + 1),
        defaultText(x));
    props[f.key] = perJointSchema(v, f.doc);
  }
  // A list of 2..max knots within l, or a list of one such list per joint.
  void knotLists(const settings::Field& f, const settings::Limits& l, int max) {
    json knot = {{"type", "number"}};
    limitsInto(knot, l);
    const json knots = {{"type", "array"}, {"minItems", 2}, {"maxItems", max}, {"items", orSweep(knot)}};
    const std::string t = l.text();
    add(f, knots, "2.." + std::to_string(max) + " numbers, each " + t.substr(t.find(' ') + 1) + "; or one such list per joint",
        "");
    props[f.key] = {{"description", f.doc},
                    {"anyOf", json::array({knots, {{"type", "array"}, {"minItems", 1}, {"items", knots}}})}};
  }
  static std::string defaultText(double x) { return std::isnan(x) ? "" : formatG(x); }
  void integer(const settings::Field& f, int x, const settings::Limits& l, const settings::IntSet& only = {}) {
    json v = {{"type", "integer"}};
    limitsInto(v, l);
    std::string allowed = "integer";
    if (!l.text(true).empty()) allowed += ", " + l.text(true).substr(l.text(true).find(' ') + 1);
    if (!only.one_of.empty()) {
      v["enum"] = only.one_of;
      allowed = "one of";
      for (int k : only.one_of) allowed += " " + std::to_string(k);
    }
    if (only.except != 0) {
      v = {{"allOf", json::array({v, {{"not", {{"const", only.except}}}}})}};
      allowed += ", not " + std::to_string(only.except);
    }
    if (only.multiple_of != 1) {
      v["multipleOf"] = only.multiple_of;
      allowed += only.multiple_of == 2 ? ", even" : ", multiple of " + std::to_string(only.multiple_of);
    }
    add(f, v, allowed, std::to_string(x));
  }
  void boolean(const settings::Field& f, bool x) { add(f, {{"type", "boolean"}}, "true, false", x ? "true" : "false"); }
  template <class E>
  void choice(const settings::Field& f, E x, const settings::EnumNames<E>& names) {
    std::string allowed;
    for (const auto& n : names) allowed += (allowed.empty() ? "`" : " \\| `") + std::string(n.name) + "`";
    add(f, {{"type", "string"}, {"enum", settings::namesOf(names)}}, allowed,
        "`" + std::string(settings::nameOf(names, x)) + "`");
  }
  void text(const settings::Field& f, const std::string& x, const settings::TextRule& rule) {
    json v = {{"type", "string"}};
    std::string allowed = "string";
    if (rule.non_empty) {
      v["minLength"] = 1;
      allowed = "non-empty string";
    }
    if (!rule.one_of.empty()) {
      v["enum"] = rule.one_of;
      allowed = rule.one_of.size() == 1 ? "`" + rule.one_of.front() + "`"
                                        : "`" + rule.one_of.front() + "` .. `" + rule.one_of.back() + "`";
    }
    add(f, v, allowed, x.empty() ? std::string() : "`" + x + "`");
  }
  template <std::size_t N>
  void numbers(const settings::Field& f, const std::array<double, N>& x) {
    json item = orSweep({{"type", "number"}});
    json v = {{"type", "array"}, {"items", item}, {"minItems", N}, {"maxItems", N}};
    std::string d = "[";
    for (std::size_t i = 0; i < N; ++i) d += (i ? ", " : "") + formatG(x[i]);
    // An array cannot be swept as a whole; its elements can.
    json p = v;
    p["description"] = f.doc;
    props[f.key] = p;
    rows += "| `" + std::string(f.key) + "` | " + std::to_string(N) + " numbers | " + d + "] | " + f.doc + " |\n";
  }
  template <class T>
  void internal(const settings::Field&, const T&) {}

  // The design sections' kinds (settings/optimize_section.h): no sweeps.
  static json intervalSchema(const settings::Limits& l) {
    json item = {{"type", "number"}};
    limitsInto(item, l);
    return {{"type", "array"}, {"minItems", 2}, {"maxItems", 2}, {"items", item}};
  }
  static std::string limitsWords(const settings::Limits& l, bool integer = false) {
    const std::string t = l.text(integer);
    return t.substr(t.find(' ') + 1);
  }
  void plainRow(const settings::Field& f, json value, const std::string& allowed, const std::string& dflt) {
    value["description"] = f.doc;
    props[f.key] = std::move(value);
    rows += "| `" + std::string(f.key) + "` | " + allowed + " | " + (dflt.empty() ? std::string("(none)") : dflt) + " | " +
            f.doc + " |\n";
  }
  void interval(const settings::Field& f, const std::array<double, 2>& x, const settings::Limits& l) {
    plainRow(f, intervalSchema(l), "[low, high], each " + limitsWords(l),
             "[" + formatG(x[0]) + ", " + formatG(x[1]) + "]");
  }
  void jointLimit(const settings::Field& f, const settings::Limits& l, bool range, const settings::TextRule& words) {
    json one = {{"type", "number"}};
    limitsInto(one, l);
    if (range) one = intervalSchema(l);
    json any = json::array({one, {{"type", "array"}, {"minItems", 1}, {"items", one}}});
    std::string allowed = (range ? "[low, high], each " : "number, ") + limitsWords(l) + "; or one per joint";
    if (!words.one_of.empty()) {
      any = json::array({{{"anyOf", any}}, {{"enum", words.one_of}}});
      for (const std::string& w : words.one_of) allowed += "; or `" + w + "`";
    }
    plainRow(f, {{"anyOf", any}}, allowed, "");
  }
  void integerList(const settings::Field& f, const settings::Limits& l, int max) {
    json item = {{"type", "integer"}};
    limitsInto(item, l);
    plainRow(f, {{"type", "array"}, {"minItems", 1}, {"maxItems", max}, {"uniqueItems", true}, {"items", item}},
             "1.." + std::to_string(max) + " distinct integers, each " + limitsWords(l, true), "");
  }
  template <class S>
  void section(const settings::Field& f, const S& sub) {
    Describer d;
    d.sweeps = false;
    declareFields(d, sub);
    plainRow(f, {{"type", "object"}, {"additionalProperties", false}, {"properties", d.props}}, "map", "");
  }
  template <class S>
  void nameOrSection(const settings::Field& f, const std::string& x, const settings::TextRule& names, const S& sub) {
    Describer d;
    d.sweeps = false;
    declareFields(d, sub);
    const json name = {{"type", "string"}, {"enum", names.one_of}};
    const json map = {{"type", "object"}, {"additionalProperties", false}, {"properties", d.props}};
    plainRow(f, {{"anyOf", json::array({name, map})}}, "`" + names.one_of.front() + "` .. `" + names.one_of.back() + "`, or map",
             "`" + x + "`");
  }
};

template <class S>
Describer describe(const S& s = S{}, bool sweeps = true) {
  Describer d;
  d.sweeps = sweeps;
  declareFields(d, s);
  return d;
}

json section(const json& props, const std::vector<std::string>& required = {}) {
  json s = {{"type", "object"}, {"additionalProperties", false}, {"properties", props}};
  if (!required.empty()) s["required"] = required;
  return s;
}
template <class S>
std::vector<std::string> allKeys() {
  std::vector<std::string> v;
  const Describer d = describe<S>();  // named: a range-for over describe<S>().props.items() would
                                      // iterate a destroyed temporary (ASan: stack-use-after-scope)
  for (const auto& [k, _] : d.props.items()) v.push_back(k);
  return v;
}

json defs() {
  json d;
  d["sweep"] = {{"type", "object"},
                {"description", "{sweep: [v1, v2, ...]} or {range: [start, stop, step]} (docs/experiment-format.md)"},
                {"minProperties", 1},
                {"maxProperties", 1},
                {"additionalProperties", false},
                {"properties",
                 {{"sweep", {{"type", "array"}, {"minItems", 1}, {"items", {{"type", {"number", "string", "boolean"}}}}}},
                  {"range", {{"type", "array"}, {"minItems", 3}, {"maxItems", 3}, {"items", {{"type", "number"}}}}}}}};
  return d;
}

// A number for all joints, or one per joint.
// The quadruped section: the explicit numbers or the size form (QuadrupedBox), one map of both
// forms' keys (the loader refuses a mix).
json quadrupedProps() {
  json p = describe<QuadrupedParams>().props;
  const json box = describe<QuadrupedBox>().props;  // named: not a range-for over a temporary's items()
  for (const auto& [k, v] : box.items())
    if (!p.contains(k)) p[k] = v;
  return p;
}


// Declared properties without their sweep alternative (files that hold no sweeps).
json plain(json props) {
  for (auto& [k, p] : props.items())
    if (p.contains("anyOf")) {
      json v = p["anyOf"][0];
      v["description"] = p["description"];
      p = v;
    }
  return props;
}

// An experiment's name: one safe path component (experimentNameProblem).
json nameSchema() {
  return {{"type", "string"}, {"minLength", 1}, {"maxLength", 100}, {"pattern", "^[^/\\\\-][^/\\\\]*$"}};
}

// A design file (`tailsim optimize`, `tailsim maneuver`): name, description, kind, the base
// experiment file and the section named like the kind. No sweeps.
json designFile(const std::string& kind, json section_schema) {
  return section({{"name", nameSchema()},
                  {"description", {{"type", "string"}}},
                  {"kind", {{"const", kind}}},
                  {"base", {{"type", "string"}, {"minLength", 1}, {"description", "the one-case experiment file the design starts from, relative to this file"}}},
                  {kind, std::move(section_schema)}},
                 {"name", "kind", "base", kind});
}

// The optimize section (settings/optimize_section.h; docs/design-a-tail-stroke.md).
json optimizeSection() { return section(describe<OptimizeSection>(OptimizeSection{}, false).props, {"family", "limits"}); }

// The maneuver section: its declared settings and stroke_from (a trajectory's source, not a number).
json maneuverSection() {
  json props = plain(describe<ManeuverSettings>().props);
  props["stroke_from"] = {{"type", "string"},
                          {"minLength", 1},
                          {"description", "the fast stroke: base, or a one-case experiment or an optimize best.yaml"}};
  return section(props);
}

}  // namespace

json experimentSchema() {
  const json num = {{"type", "number"}};
  json link = section(describe<TailLink>().props, {"mass_kg", "izz_kgm2", "length_m"});
  // The trajectory section: the split-cycle keys and the spline's (settings/trajectory_section.h).
  json traj_props = describe<SplitCycleSection>().props;
  const json spline_props = describe<SplineSection>().props;  // named: not a range-for over a temporary
  for (const auto& [k, v] : spline_props.items())
    if (!traj_props.contains(k)) traj_props[k] = v;
  json traj = section(traj_props);
  json pose = section({{"theta_deg", perJointSchema(num, "joint angles [deg]")},
                       {"thetadot_radps", perJointSchema(num, "joint speeds [rad/s]")},
                       {"thetaddot_radps2", perJointSchema(num, "joint accelerations [rad/s^2]")}});
  json tail = {{"type", "object"},
               {"additionalProperties", false},
               {"properties",
                {{"links", orSweep({{"type", "integer"}, {"minimum", 1}, {"maximum", 6}})},
                 {"custom", {{"type", "array"}, {"minItems", 1}, {"items", link}}},
                 {"mount", section(describe<TailMount>().props)}}},
               {"minProperties", 1},
               {"maxProperties", 2}};
  // robot: a robot file (or built-in name), or a robot from its MuJoCo model file.
  json modelRobot = section(describe<RobotModelSpec>().props, {"mjcf"});
  modelRobot["properties"]["stance"] = section(
      {{"keyframe", describe<RobotStanceKeys>().props["keyframe"]},
       {"joints_deg",
        {{"type", "object"},
         {"description", "joint name: angle [deg], over the keyframe (or the reference pose qpos0)"},
         {"additionalProperties", orSweep({{"type", "number"}, {"minimum", -360}, {"maximum", 360}})}}}});
  modelRobot["properties"]["feet"] = {{"type", "array"},
                                      {"minItems", 4},
                                      {"maxItems", 4},
                                      {"uniqueItems", true},
                                      {"description", "the 4 foot geoms (absent: those touching the floor after standing)"},
                                      {"items", orSweep({{"type", "string"}, {"minLength", 1}})}};
  json exp = section(
      {{"name", nameSchema()},
       {"description", {{"type", "string"}}},
       {"robot", {{"anyOf", json::array({{{"type", "string"}, {"minLength", 1}}, sweepRef(), modelRobot})}}},
       {"kind", orSweep({{"type", "string"}, {"enum", settings::namesOf(kindNames())}})},
       {"tail", tail},
       {"quadruped", section(quadrupedProps())},
       {"friction", section(describe<FrictionParams>().props)},
       {"gravity_mps2", orSweep({{"type", "number"}, {"minimum", 0}})},
       {"trajectory", traj},
       {"pose", pose},
       {"models", {{"type", "array"}, {"minItems", 1}, {"uniqueItems", true},
                   {"items", orSweep({{"type", "string"}, {"enum", modelNames()}})}}},
       },
      {"name", "robot"});
  // The settings sections (experiment_config.h forEachSection); `render:` may also be empty (null).
  const ExperimentCase defaults;
  forEachSection(defaults, [&](const SectionInfo& s, const auto& v) {
    using T = std::decay_t<decltype(v)>;
    json sec = section(describe<T>().props);
    if constexpr (std::is_same_v<T, RenderSettings>) sec = {{"anyOf", json::array({{{"type", "null"}}, sec})}};
    exp["properties"][s.key] = sec;
  });
  json suite = section({{"experiments", {{"type", "array"}, {"minItems", 1}, {"items", {{"type", "string"}}}}},
                        {"description", {{"type", "string"}}}},
                       {"experiments"});
  json s = {{"$schema", "https://json-schema.org/draft/2020-12/schema"},
            {"title", "tailsim experiment, suite, optimize or maneuver file (docs/experiment-format.md, "
                      "docs/design-a-tail-stroke.md)"},
            {"$defs", defs()},
            {"oneOf", json::array({exp, suite, designFile("optimize", optimizeSection()),
                                   designFile("maneuver", maneuverSection())})}};
  return s;
}

json robotSchema() {
  // Robot files hold no sweeps: the plain declared types.
  json props = plain(describe<TailLink>().props);
  for (const char* k : {"torque_max_Nm", "thetadot_max_dps", "theta_min_deg", "theta_max_deg"})  // or one per joint
    if (props.contains(k))
      props[k] = json{{"anyOf", json::array({props[k], {{"type", "array"}, {"minItems", 1}, {"items", props[k]}}})}};
  json link = section(props, {"mass_kg", "izz_kgm2", "length_m"});
  json tails = {{"type", "object"}, {"additionalProperties", false}, {"minProperties", 1}, {"properties", json::object()}};
  for (int n = 1; n <= 6; ++n) tails["properties"][std::to_string(n)] = link;
  return {{"$schema", "https://json-schema.org/draft/2020-12/schema"},
          {"title", "tailsim robot file (docs/experiment-format.md \"Robot file\")"},
          {"type", "object"},
          {"additionalProperties", false},
          {"required", {"quadruped", "friction", "gravity_mps2", "tails"}},
          {"properties",
           {{"quadruped", [&] {
              // Every explicit key but com_height_m (optional), or mass_kg and size_m.
              json q = section(plain(quadrupedProps()));
              std::vector<std::string> k = allKeys<QuadrupedParams>();
              k.erase(std::remove(k.begin(), k.end(), "com_height_m"), k.end());
              q["oneOf"] = json::array({{{"required", k}}, {{"required", {"mass_kg", "size_m"}}}});
              return q;
            }()},
            {"friction", section(plain(describe<FrictionParams>().props), {"mu_s", "mu_d"})},
            {"gravity_mps2", {{"type", "number"}, {"minimum", 0}}},
            {"tails", tails}}}};
}

std::string settingsMarkdown() {
  std::ostringstream o;
  const char* head = "| key | value | default | meaning |\n|---|---|---|---|\n";
  auto table = [&](const char* title, const char* note, const std::string& rows) {
    o << "### " << title << "\n\n" << note << "\n\n" << head << rows << "\n";
  };
  table("quadruped", "Overrides of the robot file's values (defaults: `robot: paper`, Table 1).",
        describe<QuadrupedParams>().rows);
  table("quadruped by its size", "Instead of the explicit numbers above (robot file or experiment): a uniform box "
                                 "on four feet; `mass_kg` and `size_m` required. The explicit keys are then derived "
                                 "(docs/experiment-format.md \"A robot given by its size\").",
        describe<QuadrupedBox>().rows);
  table("friction", "Overrides of the robot file's values (defaults: `robot: paper`, Table 1). A robot file "
                    "needs `mu_s` and `mu_d`; the thresholds only with `effects.friction: continuous` "
                    "(`v_s_mps`, `v_d_mps` only when translation is simulated too).",
        describe<FrictionParams>().rows);
  table("tail links", "Each entry of `tail: {custom: [...]}` and of a robot file's `tails.n`; `mass_kg`, "
                      "`izz_kgm2`, `length_m` required.",
        describe<TailLink>().rows);
  table("robot from its model file", "`robot: {mjcf: PATH, ...}` instead of a robot file: the robot's MJCF or URDF, "
                                     "stood in its stance and measured; `quadruped`, `friction` and `gravity_mps2` "
                                     "are then derived, not keys ([your-robot.md](your-robot.md) \"Experiments\").",
        describe<RobotModelSpec>().rows +
            "| `stance` | map | `keyframe` `home` | `{keyframe: NAME, joints_deg: {JOINT: deg}}`: the pose the legs are "
            "held in; no `home` keyframe and none given: an error |\n" +
            [] {
              std::string k = describe<RobotStanceKeys>().rows;
              return k.replace(k.find("| `keyframe`"), 12, "| `stance.keyframe`");
            }() +
            "| `stance.joints_deg` | map of joint name: number, [-360, 360] | (none) | stance: joint angles over the keyframe "
            "(or qpos0) [deg] |\n"
            "| `feet` | 4 geom names | (touching the floor) | the foot geoms; the planar models need 4 |\n");
  table("tail.mount", "A robot from its model file only: where the tail is attached. `tail: {links: n}` is then n "
                      "links sharing 10 % of the robot's mass and one body length (l_F).",
        describe<TailMount>().rows);
  const ExperimentCase defaults;
  forEachSection(defaults, [&](const SectionInfo& s, const auto& v) {
    table(s.key, s.note, describe<std::decay_t<decltype(v)>>().rows);
  });
  table("maneuver", "The `maneuver:` section of a `kind: maneuver` file (`tailsim maneuver`, "
                    "[design-a-tail-stroke.md](design-a-tail-stroke.md) \"Maneuvers\"), not of `tailsim run` experiments.",
        describe<ManeuverSettings>().rows);
  table("optimize", "The `optimize:` section of a `kind: optimize` file (`tailsim optimize`, "
                    "[design-a-tail-stroke.md](design-a-tail-stroke.md)); `family` and `limits` required. The reader "
                    "also refuses keys that do not fit together (`knots` without `family: spline`, `directions_kept` "
                    "without `directions: enumerate`, a last restart's population over the limit, ...).",
        describe<OptimizeSection>(OptimizeSection{}, false).rows);
  table("optimize.limits", "A joint limit not given here is the robot file's tail entry's (`theta_min_deg`, "
                           "`theta_max_deg`, `thetadot_max_dps`, `torque_max_Nm`).",
        describe<OptimizeLimitsSection>(OptimizeLimitsSection{}, false).rows);
  table("optimize.objective", "The map form of `objective:`; `search` and `candidates` with `model: mujoco` only.",
        describe<OptimizeObjectiveSection>(OptimizeObjectiveSection{}, false).rows);
  table("trajectory (split-cycle, Eqs. 20-23)",
        "The default family. Each per-joint key is a number (the same for every joint) or a list with one value per "
        "joint (exactly n values). Give `dtheta_deg` and one of `dT_s`, `peak_speed_dps`; or `rule: eq25` with "
        "`thetadot_max_dps` or `thetadot_max_radps` (below).",
        describe<SplitCycleSection>().rows);
  table("trajectory (spline, `family: spline`)",
        "Per joint a clamped cubic spline through equally spaced knots (below); `knots_deg` and `dT_s` required.",
        describe<SplineSection>().rows);
  std::string s = o.str();
  while (s.size() >= 2 && s[s.size() - 1] == '\n' && s[s.size() - 2] == '\n') s.pop_back();
  return s;
}

}  // namespace tailsim
