// robot: {mjcf: PATH, ...}: a robot from its MuJoCo model file (docs/experiment-format.md).
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

// robot: {mjcf: PATH, mu, stance: {keyframe, joints_deg: {NAME: deg}}, feet: [geom, ...]}: the
// model file is checked here (a regular file, within kMaxModelFileBytes; its path UTF-8 without
// control characters); loading it and standing the robot need MuJoCo and happen later, once per
// experiment (resolveRobotModels), each of its errors then named at the key recorded here.
void readRobotModel(const Reader& r, const Item& item, const std::string& source, ExperimentCase& c) {
  static const std::vector<std::string> kKeys = [] {
    std::vector<std::string> k = declaredKeys<RobotModelSpec>();
    k.insert(k.end(), {"stance", "feet"});
    return k;
  }();
  c.robot_model.emplace();
  RobotModelSpec& spec = *c.robot_model;
  auto at = [&](const std::string& key, const Item& it) { c.robot_model_at[key] = locText(r.loc(it)); };
  if (isSweepMap(item.node)) r.fail(item, "a sweep can replace a single value only, not a section or list");
  const MapView m = r.map(item, kKeys);
  const Item& file = r.need(m, "mjcf");
  const std::string rel = r.string(file);
  if (rel.empty()) r.fail(file, "needs the path of the robot's MJCF or URDF file");
  if (rel.size() > 4096) r.fail(file, "a path of more than 4096 bytes");
  if (std::any_of(rel.begin(), rel.end(), [](char ch) { return static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f; }))
    r.fail(file, "the path holds a control character (a line break, a tab, a NUL byte ...)");
  if (invalidUtf8At(rel) != std::string::npos) r.fail(file, "the path is not UTF-8");
  spec.file = resolveRelative(source, rel);
  {
    struct stat st {};
    if (::stat(spec.file.c_str(), &st) != 0)
      r.fail(file, "model file not found: " + spec.file + " (" + std::strerror(errno) + ")");
    if (!S_ISREG(st.st_mode))
      r.fail(file, spec.file + " is not a regular file (a folder, a device or a FIFO): expected an MJCF or URDF file");
    if (static_cast<unsigned long long>(st.st_size) > kMaxModelFileBytes)
      r.fail(file, spec.file + " is larger than " + std::to_string(kMaxModelFileBytes >> 20) +
                       " MiB; an MJCF or URDF file is text of at most a few MB (its meshes are files of their own)");
  }
  c.robot_file = spec.file;
  at("robot.mjcf", file);
  at("robot", item);
  if (const Item* mu = m.get("mu")) {
    spec.mu = r.nonNegative(*mu);
    at("robot.mu", *mu);
  }
  if (const Item* legs = m.get("legs")) {
    spec.legs = r.choice(*legs, {"servos", "locked"});
    at("robot.legs", *legs);
  }
  if (const Item* st = m.get("stance")) {
    at("robot.stance", *st);
    const MapView sm = r.map(*st, {"keyframe", "joints_deg"});
    if (const Item* k = sm.get("keyframe")) {
      spec.keyframe = r.string(*k);
      if (spec.keyframe.empty()) r.fail(*k, "must not be empty (absent: the model's `home` keyframe)");
    }
    if (const Item* j = sm.get("joints_deg")) {
      if (r.pick(*j) || !j->node.IsMap()) r.fail(*j, "expected a map of joint name: angle [deg]");
      for (const auto& kv : j->node) {
        if (!kv.first.IsScalar()) loader::fail(Loc{r.file(), kv.first.Mark(), j->key}, "keys must be joint names");
        const std::string name = kv.first.Scalar();
        if (name.empty()) loader::fail(Loc{r.file(), kv.first.Mark(), j->key}, "a joint name must not be empty");
        const Item v{kv.second, joinKey(j->key, name), kv.second.Mark().is_null() ? kv.first.Mark() : kv.second.Mark()};
        if (spec.joint_angles_rad.count(name)) r.fail(v, "duplicate joint");
        spec.joint_angles_rad[name] = boundedDeg(r, v, 360.0) * units::kRadPerDeg;
      }
      if (spec.joint_angles_rad.empty()) r.fail(*j, "needs at least one joint (or leave joints_deg out)");
    }
  }
  if (const Item* f = m.get("feet")) {
    at("robot.feet", *f);
    const std::vector<Item> v = r.list(*f);
    if (v.size() < 3 || v.size() > 4) r.fail(*f, "needs 3 or 4 foot geoms' names, got " + std::to_string(v.size()));
    for (const Item& x : v) {
      const std::string g = r.string(x);
      if (g.empty()) r.fail(x, "a geom name must not be empty");
      if (std::find(spec.feet.begin(), spec.feet.end(), g) != spec.feet.end()) r.fail(x, "'" + clip(g) + "' is listed twice");
      spec.feet.push_back(g);
    }
  }
}

}  // namespace loader
}  // namespace tailsim
