// Pass 2 of an experiment file: one ExperimentCase at one point of the sweep grid.
#include "experiments/loader_parts.h"

#include <dlfcn.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include "experiments/model_registry.h"
#include "experiments/work_estimate.h"
#include "common/work_limits.h"
#include "common/number_text.h"
#include "common/units.h"
#include "settings/trajectory_section.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <type_traits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <utility>

namespace tailsim {
namespace loader {

namespace {

// The robot a case starts from, with where each value was set: a robot file (rf, its origins), or
// a robot from its model file (model_robot; rf then has no values).
struct CaseRobot {
  const RobotFile* rf = nullptr;
  bool model_robot = false;
  Origins origin;
};

// Stage 1: the top-level map, the name and description.
MapView readHeader(const Reader& r, const Item& root, const std::string& source, ExperimentCase& c) {
  static const std::vector<std::string> kTopKeys = [] {
    std::vector<std::string> k = {"name",         "description", "robot", "kind",  "tail",  "quadruped",
                                  "friction",     "gravity_mps2", "trajectory", "pose", "models"};
    for (const std::string& s : sectionKeys()) k.push_back(s);  // experiment_config.h forEachSection
    return k;
  }();
  const MapView top = r.map(root, kTopKeys);
  c.source_file = source;
  const Item& name = r.need(top, "name");
  c.experiment = r.string(name);
  // The name becomes a folder (a suite's OUT/<name>/, render's OUT/<name>/): one safe path component.
  if (const std::string why = experimentNameProblem(c.experiment); !why.empty()) r.fail(name, why);
  if (const Item* d = top.get("description")) r.string(*d);
  return top;
}

// Stage 2: the robot file (its base values and origins), or a robot from its MuJoCo model file.
CaseRobot readRobotSource(Loader& L, const Reader& r, const MapView& top, const std::string& source, ExperimentCase& c) {
  const Item& robotItem = r.need(top, "robot");
  const bool modelRobot = !r.pick(robotItem) && robotItem.node.IsMap();
  static const RobotFile kNoRobotFile{};
  const RobotFile* rfp = &kNoRobotFile;
  if (modelRobot) {
    readRobotModel(r, robotItem, source, c);
    for (const char* k : {"quadruped", "friction", "gravity_mps2"})
      if (const Item* x = top.get(k))
        r.fail(*x, std::string("not used with robot: {mjcf: ...}: derived from the model file") +
                       (std::string(k) == "friction" ? " (robot.mu sets the friction)"
                        : std::string(k) == "gravity_mps2" ? " (the model's <option gravity>)" : ""));
  } else {
    const std::string robotRel = r.string(robotItem);
    if (robotRel.empty()) r.fail(robotItem, "needs a built-in robot name (paper) or the path of a robot file");
    c.robot_file = isBuiltinRobotName(robotRel) ? builtinRobotFile(robotRel, r.loc(robotItem))
                                                : resolveRelative(source, robotRel);
    rfp = &L.robot(c.robot_file, r.loc(robotItem));
  }
  const RobotFile& rf = *rfp;
  c.robot = rf.base;
  return CaseRobot{rfp, modelRobot, rf.origin};
}

// Stage 3a: tail.mount, the tail's place on a robot from its model file.
void readTailMount(const Reader& r, const Item& mount, bool modelRobot, ExperimentCase& c) {
  if (!modelRobot) r.fail(mount, "only used with a robot from its model file (robot: {mjcf: PATH})");
  static const std::vector<std::string> kMountKeys = declaredKeys<TailMount>();
  const MapView mm = readDeclared(r, mount, c.robot_model->mount);
  for (const std::string& k : kMountKeys)
    if (const Item* x = mm.get(k)) c.robot_model_at["tail.mount." + k] = locText(r.loc(*x));
  if (const Item* b = mm.get("body"))
    if (c.robot_model->mount.body.empty()) r.fail(*b, "must not be empty (absent: the root body)");
}

// Stage 3: the tail: links: n of the robot file (or derived with a model robot), or custom links.
void readTail(const Reader& r, const MapView& top, const Item& root, CaseRobot& robot, ExperimentCase& c) {
  const bool modelRobot = robot.model_robot;
  const RobotFile& rf = *robot.rf;
  Origins& origin = robot.origin;
  if (const Item* t = top.get("tail")) {
    const MapView tm = r.map(*t, {"links", "custom", "mount"});
    const Item* links = tm.get("links");
    const Item* custom = tm.get("custom");
    if (const Item* mount = tm.get("mount")) readTailMount(r, *mount, modelRobot, c);
    if (!links && !custom) r.fail(*t, "give links: n (1..6) or custom: [{mass_kg, izz_kgm2, length_m}, ...]");
    if (links && custom) r.fail(*custom, "give links: n or custom: [...], not both");
    if (links && modelRobot) {
      // n links sharing 10 % of the robot's mass and one body length, derived with the robot.
      const int n = r.integer(*links, 1, 6);
      c.robot_model_links = n;
      c.robot.tail.assign(static_cast<std::size_t>(n), TailLink{});
      c.robot_model_at["tail.links"] = locText(r.loc(*links));
    } else if (links) {
      const int n = r.integer(*links, 1, 6);
      const auto f = rf.tails.find(n);
      if (f == rf.tails.end()) r.fail(*links, "robot file " + rf.file + " has no tails." + std::to_string(n));
      c.robot.tail = f->second;  // n identical links (Table 2), but for per-joint actuator keys
      for (int i = 1; i <= n; ++i)
        for (const auto& [k, loc] : rf.tail_origin.at(n))  // keys "tail link 1 <field>"
          origin["tail link " + std::to_string(i) + k.substr(std::string("tail link 1").size())] = loc;
    } else {
      const std::vector<Item> v = r.list(*custom);
      if (v.empty()) r.fail(*custom, "needs at least one link (n >= 1)");
      for (std::size_t i = 0; i < v.size(); ++i) c.robot.tail.push_back(readLink(r, v[i], static_cast<int>(i + 1), origin));
    }
  } else if (modelRobot) {  // default: tail: {links: 1}, derived with the robot
    c.robot_model_links = 1;
    c.robot.tail.assign(1, TailLink{});
    c.robot_model_at["tail.links"] = locText(r.locAt(root, "tail"));
  } else {  // default: tail: {links: 1}
    const auto f = rf.tails.find(1);
    if (f == rf.tails.end()) loader::fail(r.locAt(root, "tail"), "missing, and robot file " + rf.file + " has no tails.1");
    c.robot.tail = f->second;
    origin.insert(rf.tail_origin.at(1).begin(), rf.tail_origin.at(1).end());
  }
}

// Stage 4: the experiment's quadruped, friction and gravity over the robot file's; the robot validated.
void readRobotOverrides(const Reader& r, const MapView& top, const Item& root, CaseRobot& robot, ExperimentCase& c) {
  Origins& origin = robot.origin;
  if (const Item* q = top.get("quadruped")) readQuadruped(r, *q, false, c.robot.quadruped, origin);
  if (const Item* f = top.get("friction")) readFriction(r, *f, false, c.robot.friction, origin);
  if (const Item* g = top.get("gravity_mps2")) {
    c.robot.gravity_mps2 = r.number(*g);
    origin["gravity_mps2"] = r.loc(*g);
  }
  if (robot.model_robot) {
    // The robot's own values come with its derivation (resolveRobotModels); a custom tail is checked now.
    if (c.robot_model_links == 0) {
      RobotParams check;
      check.tail = c.robot.tail;
      validateRobot(check, origin, r.loc(root));
      checkMasses(check, origin, r.loc(root));
    }
  } else {
    validateRobot(c.robot, origin, r.loc(root));
    checkMasses(c.robot, origin, r.loc(root));
  }
}

// Stage 5: the trajectory (kind: simulate: split-cycle or spline) or the pose (kind: pose) of n joints.
void readMotion(const Reader& r, const MapView& top, const Item& root, int n, ExperimentCase& c) {
  const Item* traj = top.get("trajectory");
  const Item* pose = top.get("pose");
  if (c.kind == CaseKind::kSimulate) {
    if (pose) r.fail(*pose, "only used with kind: pose");
    if (!traj) loader::fail(r.locAt(root, "trajectory"), "required for kind: simulate");
    // family: split_cycle (default: Eqs. 20-23) or spline (a clamped cubic spline per joint).
    const MapView tm = r.map(*traj, [] {
      std::vector<std::string> k = kSplitCycleKeys;  // ... family, then the spline's own keys
      for (const std::string& key : kSplineKeys)
        if (std::find(k.begin(), k.end(), key) == k.end()) k.push_back(key);
      return k;
    }());
    const Item* fam = tm.get("family");
    if (fam && r.choice(*fam, {"split_cycle", "spline"}) == "spline") {
      c.splines = readSplineTrajectory(r, *traj, tm, n);
    } else {
      if (const Item* k = tm.get("knots_deg")) r.fail(*k, "only used with family: spline");
      c.joints = readTrajectory(r, *traj, n);
    }
  } else {
    if (traj) r.fail(*traj, "only used with kind: simulate");
    c.pose = pose ? readPose(r, *pose, n) : readPose(r, Item{YAML::Node(YAML::NodeType::Map), "pose", root.mark}, n);
  }
}

// Stage 6: models: the models each case runs (default: the registry's first).
void readModels(const Reader& r, const MapView& top, ExperimentCase& c) {
  if (const Item* m = top.get("models")) {
    const std::vector<Item> v = r.list(*m);
    const std::vector<std::string> names = modelNames();
    if (v.empty()) {
      std::string list;
      for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
      r.fail(*m, "needs at least one model (" + list + ")");
    }
    for (const Item& x : v) {
      const std::string s = r.choice(x, names);
      if (std::find(c.models.begin(), c.models.end(), s) != c.models.end()) r.fail(x, "'" + s + "' is listed twice");
      c.models.push_back(s);
    }
  } else {
    c.models = {modelRegistry().front().name};
  }
}

// Stage 7: the settings sections (experiment_config.h forEachSection): declared fields, read by
// readDeclared; the few with checks across keys or defaults from elsewhere have their own reader.
void readSettingsSections(const Reader& r, const MapView& top, ExperimentCase& c) {
  forEachSection(c, [&](const SectionInfo& sec, auto& v) {
    using T = std::decay_t<decltype(v)>;
    const Item* x = top.get(sec.key);
    if constexpr (std::is_same_v<T, MujocoSettings>) {
      if (x) v = readMujoco(r, *x);
      // The MuJoCo body stands at the robot's COM height (one key: quadruped.com_height_m).
      v.body_height_m = c.robot.quadruped.com_height_m;
    } else if constexpr (std::is_same_v<T, OutputSettings>) {
      if (x) v = readOutput(r, *x, c.kind == CaseKind::kSimulate ? c.trajectory().endTime() : -1.0);
    } else if constexpr (std::is_same_v<T, RenderSettings>) {
      const double run_end = c.kind != CaseKind::kSimulate ? -1.0 : c.simDuration();
      if (x) v = readRender(r, *x, run_end);
    } else if (x) {
      readDeclared(r, *x, v);
    }
  });
}

// Stage 8: the rules across the whole case: a model robot's limits, the continuous law's
// thresholds, the work limits.
void checkCase(const Reader& r, const MapView& top, const Origins& origin, const ExperimentCase& c) {
  if (c.robot_model) {
    if (const Item* x = top.get("render"))
      r.fail(*x, "videos of a robot from its model file are not drawn yet: leave render: out");
    if (c.kind != CaseKind::kSimulate) r.fail(*top.get("kind"), "a robot from its model file runs kind: simulate only");
  }
  requireContinuousThresholds(r, top, c, origin);
  checkCaseWork(r, top, c);
}

}  // namespace

// Pass 2: one case, with the sweeps resolved by `r`, read in the stages above (each error at its
// key, in the order the stages run).
ExperimentCase readCase(Loader& L, const Reader& r, const YAML::Node& doc, const std::string& source) {
  const Item root = r.root(doc);
  ExperimentCase c;
  const MapView top = readHeader(r, root, source, c);
  CaseRobot robot = readRobotSource(L, r, top, source, c);
  if (const Item* k = top.get("kind")) c.kind = r.choice(*k, kindNames());
  readTail(r, top, root, robot, c);
  readRobotOverrides(r, top, root, robot, c);
  readMotion(r, top, root, c.robot.numLinks(), c);
  readModels(r, top, c);
  readSettingsSections(r, top, c);
  checkCase(r, top, robot.origin, c);
  return c;
}

}  // namespace loader
}  // namespace tailsim
