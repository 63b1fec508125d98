#include "experiments/settings_json.h"

#include <algorithm>
#include <type_traits>
#include <stdexcept>

#include "models/mujoco/robot_import.h"
#include "common/sha256.h"
#include "tailsim_version.h"

namespace tailsim {
namespace {

using json = nlohmann::json;

// Writes the declared fields of a struct into a JSON object (SI values; enums by name).
struct JsonWriter {
  json& j;
  void number(const settings::Field& f, double x, const settings::Limits&) { j[f.si_key ? f.si_key : f.key] = x; }
  void integer(const settings::Field& f, int x, const settings::Limits&, const settings::IntSet& = {}) { j[f.key] = x; }
  void boolean(const settings::Field& f, bool x) { j[f.key] = x; }
  template <class E>
  void choice(const settings::Field& f, E x, const settings::EnumNames<E>& names) {
    j[f.key] = settings::nameOf(names, x);
  }
  void text(const settings::Field& f, const std::string& x, const settings::TextRule&) { j[f.key] = x; }
  template <std::size_t N>
  void numbers(const settings::Field& f, const std::array<double, N>& x) {
    j[f.key] = json::array();
    for (double v : x) j[f.key].push_back(v);
  }
  template <class T>
  void internal(const settings::Field& f, const T& x) {
    j[f.key] = x;
  }
};

// Reads them back; every declared key must be there with the right type.
struct JsonReader {
  const json& j;
  std::string where;
  const json& at(const settings::Field& f) const {
    const char* k = f.si_key ? f.si_key : f.key;
    if (!j.is_object() || !j.contains(k)) throw std::runtime_error("resolved case: " + where + "." + k + " is missing");
    return j.at(k);
  }
  template <class T>
  T get(const settings::Field& f) const {
    try {
      return at(f).get<T>();
    } catch (const json::exception& e) {
      throw std::runtime_error("resolved case: " + where + "." + f.key + ": " + e.what());
    }
  }
  void number(const settings::Field& f, double& x, const settings::Limits&) { x = get<double>(f); }
  void integer(const settings::Field& f, int& x, const settings::Limits&, const settings::IntSet& = {}) { x = get<int>(f); }
  void boolean(const settings::Field& f, bool& x) { x = get<bool>(f); }
  template <class E>
  void choice(const settings::Field& f, E& x, const settings::EnumNames<E>& names) {
    const std::string s = get<std::string>(f);
    if (!settings::valueOf(names, s, x))
      throw std::runtime_error("resolved case: " + where + "." + f.key + ": unknown value '" + s + "'");
  }
  void text(const settings::Field& f, std::string& x, const settings::TextRule&) { x = get<std::string>(f); }
  template <std::size_t N>
  void numbers(const settings::Field& f, std::array<double, N>& x) {
    const auto v = get<std::vector<double>>(f);
    if (v.size() != N) throw std::runtime_error("resolved case: " + where + "." + f.key + ": wrong length");
    for (std::size_t i = 0; i < N; ++i) x[i] = v[i];
  }
  template <class T>
  void internal(const settings::Field& f, T& x) {
    x = get<T>(f);
  }
};

template <class S>
json toJson(const S& s) {
  json j = json::object();
  JsonWriter w{j};
  declareFields(w, s);
  return j;
}
template <class S>
S fromJson(const json& j, const std::string& where) {
  S s{};
  JsonReader r{j, where};
  declareFields(r, s);
  return s;
}
const json& need(const json& j, const char* k) {
  if (!j.is_object() || !j.contains(k)) throw std::runtime_error(std::string("resolved case: ") + k + " is missing");
  return j.at(k);
}

// A robot from its model file: the model (by the SHA-256 of the text tailsim compiles, so a folder's
// copy gives the same key), what the user said, and every derived value with where it came from.
json robotModelJson(const ExperimentCase& c) {
  const RobotModelSpec& s = *c.robot_model;
  json j;
  json given = toJson(s);
  given.erase("mjcf");  // the path: robot_file
  given["keyframe"] = s.keyframe;
  given["joints_rad"] = s.joint_angles_rad;
  given["feet"] = s.feet;
  given["mount"] = toJson(s.mount);
  given["tail_links"] = c.robot_model_links;
  j["given"] = given;
  if (const DerivedRobot* d = c.robot_derived.get()) {
    j["model_sha256"] = sha256Hex(d->model.xml);
    j["stance"] = d->stance;
    j["feet"] = d->feet;
    j["root_body"] = d->root_body;
    j["mount_body"] = d->mount_body;
    j["standing_tilt_deg"] = d->tilt_deg;
    j["derived"] = json::array();
    for (const DerivedValue& v : d->values)
      j["derived"].push_back({{"key", v.key}, {"value", v.value}, {"unit", v.unit}, {"source", v.source}});
  }
  return j;
}

}  // namespace

json resolvedJson(const ExperimentCase& c) {
  json j;
  j["experiment"] = c.experiment;
  j["case"] = c.name;
  j["sweep"] = json::object();
  for (const auto& [k, v] : c.sweep_values) j["sweep"][k] = v;
  j["source_file"] = c.source_file;
  j["robot_file"] = c.robot_file;
  j["kind"] = name(c.kind);
  j["models"] = c.models;
  j["quadruped"] = toJson(c.robot.quadruped);
  j["friction"] = toJson(c.robot.friction);
  j["gravity_mps2"] = c.robot.gravity_mps2;
  j["tail"] = json::array();
  for (const TailLink& l : c.robot.tail) j["tail"].push_back(toJson(l));
  j["joints"] = json::array();
  for (const SplitCycleParams& p : c.joints) j["joints"].push_back(toJson(p));
  if (!c.splines.empty()) {  // only then: split-cycle cases keep their resume keys
    j["splines"] = json::array();
    for (const SplineParams& p : c.splines) j["splines"].push_back(toJson(p));
  }
  if (c.robot_model) j["robot_model"] = robotModelJson(c);
  j["pose"] = {{"theta_rad", c.pose.theta_rad},
               {"thetadot_radps", c.pose.thetadot_radps},
               {"thetaddot_radps2", c.pose.thetaddot_radps2}};
  // The settings sections (experiment_config.h); a model's own section only where that model runs.
  forEachSection(c, [&](const SectionInfo& s, const auto& v) {
    if (!s.model || std::find(c.models.begin(), c.models.end(), s.model) != c.models.end()) j[s.key] = toJson(v);
  });
  return j;
}

ExperimentCase caseFromResolved(const json& j) {
  ExperimentCase c;
  try {
    c.experiment = need(j, "experiment").get<std::string>();
    c.name = need(j, "case").get<std::string>();
    for (const auto& [k, v] : need(j, "sweep").items()) c.sweep_values[k] = v.get<std::string>();
    c.source_file = j.value("source_file", std::string());  // absent in result.json (see the runner)
    c.robot_file = j.value("robot_file", std::string());
    const std::string kind = need(j, "kind").get<std::string>();
    if (!settings::valueOf(kindNames(), kind, c.kind)) throw std::runtime_error("resolved case: unknown kind '" + kind + "'");
    c.models = need(j, "models").get<std::vector<std::string>>();
    c.robot.quadruped = fromJson<QuadrupedParams>(need(j, "quadruped"), "quadruped");
    c.robot.friction = fromJson<FrictionParams>(need(j, "friction"), "friction");
    c.robot.gravity_mps2 = need(j, "gravity_mps2").get<double>();
    for (const json& l : need(j, "tail")) c.robot.tail.push_back(fromJson<TailLink>(l, "tail[]"));
    for (const json& p : need(j, "joints")) c.joints.push_back(fromJson<SplitCycleParams>(p, "joints[]"));
    if (j.contains("splines"))
      for (const json& p : j.at("splines")) c.splines.push_back(fromJson<SplineParams>(p, "splines[]"));
    const json& pose = need(j, "pose");
    c.pose.theta_rad = need(pose, "theta_rad").get<std::vector<double>>();
    c.pose.thetadot_radps = need(pose, "thetadot_radps").get<std::vector<double>>();
    c.pose.thetaddot_radps2 = need(pose, "thetaddot_radps2").get<std::vector<double>>();
    forEachSection(c, [&](const SectionInfo& s, auto& v) {
      using T = std::decay_t<decltype(v)>;
      if (!s.model) v = fromJson<T>(need(j, s.key), s.key);
      else if (j.contains(s.key)) v = fromJson<T>(j.at(s.key), s.key);
    });
  } catch (const json::exception& e) {
    throw std::runtime_error(std::string("resolved case: ") + e.what());
  }
  return c;
}

BuildId thisBuild() { return {kVersion, kGitCommit}; }

std::string caseKeyText(const ExperimentCase& c, bool render) { return caseKeyText(c, render, thisBuild()); }

std::string caseKeyText(const ExperimentCase& c, bool render, const BuildId& b) {
  json k = resolvedJson(c);
  k.erase("source_file");  // where the values came from does not change the results
  k.erase("robot_file");
  if (!render) k.erase("render");  // --no-render: a later run with rendering renders the case
  k["rendered"] = render;
  k["tailsim_version"] = b.version;
  k["tailsim_git_commit"] = b.git_commit;
  return k.dump();  // keys sorted (std::map), numbers in shortest round-trip form
}

}  // namespace tailsim
