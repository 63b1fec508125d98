// Robot files (docs/experiment-format.md "Robot file"), built-in robots, and the robot parts an
// experiment overrides: quadruped, friction, tail links, with validate()'s messages at their keys.
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

// Robot parts: ranges are checked by validate() (robot_params.cc, the same declarations), with
// each message at the value that set it (origin).
//
// quadruped: the explicit numbers (QuadrupedParams; a robot file gives every key but com_height_m,
// default 0.15 m), or the size form {mass_kg, size_m, foot_inset_m} (QuadrupedBox), which sets every
// value but the mass from the box (quadrupedFromBox). An experiment's size_m without mass_kg keeps the
// robot file's mass.
void readQuadruped(const Reader& r, const Item& item, bool all, QuadrupedParams& q, Origins& origin) {
  static const std::vector<std::string> kExplicit = declaredKeys<QuadrupedParams>();
  static const std::vector<std::string> kAllowed = [] {
    std::vector<std::string> k = kExplicit;
    for (const std::string& b : declaredKeys<QuadrupedBox>())
      if (std::find(k.begin(), k.end(), b) == k.end()) k.push_back(b);
    return k;
  }();
  const MapView m = r.map(item, kAllowed);
  if (const Item* size = m.get("size_m")) {
    for (const std::string& k : kExplicit)
      if (const Item* x = m.get(k); x && k != "mass_kg")
        r.fail(*x, "give the size (mass_kg, size_m, foot_inset_m) or the explicit numbers, not both: size_m sets " + k);
    if (all) r.need(m, "mass_kg");
    QuadrupedBox box;
    box.mass_kg = q.mass_kg;
    YamlFields v(r, m, false, true, &origin, "quadruped.");
    declareFields(v, box);
    try {
      q = quadrupedFromBox(box);
    } catch (const std::invalid_argument& e) {
      rethrowAt(e.what(), origin, r.loc(*size));
    }
    for (const std::string& k : kExplicit)
      if (k != "mass_kg") origin["quadruped." + k] = r.loc(*size);
    return;
  }
  if (const Item* x = m.get("foot_inset_m")) r.fail(*x, "only used with size_m (a robot given by its size)");
  YamlFields v(r, m, false, false, &origin, "quadruped.");
  declareFields(v, q);
  if (all)
    for (const std::string& k : kExplicit)
      if (k != "com_height_m" && !m.get(k))
        loader::fail(r.locAt(m.self, k), "required key is missing (or give the size: {mass_kg, size_m: [l, w, h]})");
}

// friction: mu_s and mu_d always; the continuous law's thresholds are checked where that law is
// chosen (requireContinuousThresholds).
const char* const kContinuousKeys[4] = {"phidot_s_radps", "phidot_d_radps", "v_s_mps", "v_d_mps"};
void readFriction(const Reader& r, const Item& item, bool all, FrictionParams& fp, Origins& origin) {
  const MapView m = readDeclared(r, item, fp, false, &origin, "friction.", false);
  if (all)
    for (const char* k : {"mu_s", "mu_d"}) r.need(m, k);
}

// One tail link {mass_kg, izz_kgm2, length_m, com_offset_m?}; origins under "tail link <i> ".
TailLink readLink(const Reader& r, const Item& item, int index, Origins& origin) {
  TailLink l;
  l.com_offset_m = -1.0;  // absent: 0.5 length_m (Table 2: COM at mid-length)
  const std::string pre = "tail link " + std::to_string(index) + " ";
  const MapView m = readDeclared(r, item, l, false, &origin, pre, false);
  for (const char* k : {"mass_kg", "izz_kgm2", "length_m"}) r.need(m, k);
  if (!m.get("com_offset_m")) {
    l.com_offset_m = 0.5 * l.length_m;
    origin[pre + "com_offset_m"] = r.loc(r.need(m, "length_m"));
  }
  return l;
}

void validateRobot(const RobotParams& p, const Origins& origin, const Loc& fallback) {
  try {
    validate(p);
  } catch (const std::invalid_argument& e) {
    rethrowAt(e.what(), origin, fallback);
  }
}

// Masses within [kMinMassKg, kMaxMassKg] (docs/experiment-format.md "Limits"), at the value that set them.
void checkMasses(const RobotParams& p, const Origins& origin, const Loc& fallback) {
  auto check = [&](double m, const std::string& key) {
    if (m >= limits::kMinMassKg && m <= limits::kMaxMassKg) return;
    const auto it = origin.find(key);
    fail(it == origin.end() ? fallback : it->second,
         "must lie in [" + formatG(limits::kMinMassKg) + ", " + formatG(limits::kMaxMassKg) + "] kg, got " + formatG(m) +
             " (docs/experiment-format.md \"Limits\")");
  };
  check(p.quadruped.mass_kg, "quadruped.mass_kg");
  for (std::size_t i = 0; i < p.tail.size(); ++i) check(p.tail[i].mass_kg, "tail link " + std::to_string(i + 1) + " mass_kg");
}

std::unique_ptr<RobotFile> readRobotFile(const std::string& abs) {
  auto rf = std::make_unique<RobotFile>();
  rf->file = abs;
  const YAML::Node doc = parseYaml(&rf->file);
  const Reader r(&rf->file, nullptr);
  const Item root = r.root(doc);
  const MapView top = r.map(root, {"quadruped", "friction", "gravity_mps2", "tails"});
  readQuadruped(r, r.need(top, "quadruped"), true, rf->base.quadruped, rf->origin);
  readFriction(r, r.need(top, "friction"), true, rf->base.friction, rf->origin);
  const Item& g = r.need(top, "gravity_mps2");
  rf->base.gravity_mps2 = r.number(g);
  rf->origin["gravity_mps2"] = r.loc(g);
  const Item& tailsItem = r.need(top, "tails");
  const MapView tails = r.map(tailsItem, {"1", "2", "3", "4", "5", "6"});
  if (tails.fields.empty()) r.fail(tailsItem, "needs at least one tail (keys 1..6)");
  for (const auto& [k, item] : tails.fields) {
    const int n = std::stoi(k);
    Origins o;
    // The actuator keys may give one value per joint (a list of n); the link itself is one for all.
    // A list stands in the node as its first value while the link is read, then sets each joint's.
    constexpr std::pair<const char*, double> kPerJoint[] = {
        {"torque_max_Nm", 1.0}, {"thetadot_max_dps", M_PI / 180.0}, {"theta_min_deg", M_PI / 180.0}, {"theta_max_deg", M_PI / 180.0}};
    std::vector<std::pair<int, std::vector<Item>>> lists;  // (index in kPerJoint, the n values)
    if (item.node.IsMap())
      for (int q = 0; q < 4; ++q)
        if (const YAML::Node v = item.node[kPerJoint[q].first]; v && v.IsSequence()) {
          const Item list{v, joinKey(item.key, kPerJoint[q].first), v.Mark()};
          lists.emplace_back(q, r.perJoint(list, n));
          YAML::Node target = item.node;
          target[kPerJoint[q].first] = v[0];
        }
    const TailLink link = readLink(r, item, 1, o);
    std::vector<TailLink> links(static_cast<std::size_t>(n), link);
    for (const auto& [q, values] : lists)
      for (int i = 0; i < n; ++i) {
        const double x = r.number(values[static_cast<std::size_t>(i)]) * kPerJoint[q].second;
        TailLink& l = links[static_cast<std::size_t>(i)];
        (q == 0 ? l.torque_max_Nm : q == 1 ? l.thetadot_max_radps : q == 2 ? l.theta_min_rad : l.theta_max_rad) = x;
        if (q < 2 && x < 0.0) r.fail(values[static_cast<std::size_t>(i)], "must be >= 0, got " + formatG(x / kPerJoint[q].second));
      }
    RobotParams check = rf->base;
    check.tail = links;
    Origins all = rf->origin;
    all.insert(o.begin(), o.end());
    validateRobot(check, all, r.loc(item));
    rf->tails[n] = std::move(links);
    rf->tail_origin[n] = std::move(o);
  }
  return rf;
}

std::string absolutePath(const std::string& p) { return fs::absolute(fs::path(p)).lexically_normal().string(); }
std::string resolveRelative(const std::string& base_file, const std::string& p) {
  const fs::path q(p);
  // A relative base (the label of an experiment given as text) means the working directory.
  return fs::absolute(q.is_absolute() ? q : fs::path(base_file).parent_path() / q).lexically_normal().string();
}

// Built-in robots: `robot: paper` names the robot file packaged with tailsim, so an experiment
// runs from wherever it is saved. A value without '/' and '.' is such a name; anything else is a
// path, relative to the experiment file.
bool isBuiltinRobotName(const std::string& v) { return v.find_first_of("/.") == std::string::npos; }

// The packaged robots folder, looked for from the file holding this code (the program, or the
// Python module tailsim links into): configs/robots next to its build folder (build/tailsim ->
// configs/robots, so a moved checkout still works); an installed copy, <a>/share/tailsim/robots for
// the nearest of its ancestors a (<prefix>/bin/tailsim, <prefix>/lib/python3/dist-packages/tailsim.so
// -> <prefix>/share/tailsim/robots); then the source tree tailsim was built from.
std::vector<fs::path> builtinRobotDirs() {
  std::vector<fs::path> dirs;
  std::error_code ec;
  fs::path self;
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&builtinRobotDirs), &info) && info.dli_fname && *info.dli_fname)
    self = fs::canonical(info.dli_fname, ec);
  if (self.empty() || ec) self = fs::read_symlink("/proc/self/exe", ec);
  if (!self.empty()) {
    const fs::path here = self.parent_path();
    dirs.push_back((here.parent_path() / "configs" / "robots").lexically_normal());
    int up = 0;
    for (fs::path a = here; up < 4; a = a.parent_path(), ++up) {
      dirs.push_back((a / "share" / "tailsim" / "robots").lexically_normal());
      if (a == a.parent_path()) break;
    }
  }
#ifdef TAILSIM_ROBOTS_DIR
  dirs.push_back(fs::path(TAILSIM_ROBOTS_DIR).lexically_normal());
#endif
  return dirs;
}

std::string builtinRobotFile(const std::string& name, const Loc& at) {
  static const std::map<std::string, std::string> kBuiltin = {{"paper", "paper_quadruped.yaml"}};
  const auto it = kBuiltin.find(name);
  if (it == kBuiltin.end())
    fail(at, "unknown built-in robot " + quote(name) +
                 " (built-in: paper); a robot file is given by its path, e.g. my_robot.yaml");
  std::string looked;
  for (const fs::path& d : builtinRobotDirs()) {
    const fs::path f = d / it->second;
    std::error_code ec;
    if (fs::is_regular_file(f, ec)) return f.string();
    looked += (looked.empty() ? "" : ", ") + f.string();
  }
  fail(at, "built-in robot '" + name + "' not found (looked for " + looked + ")");
}

}  // namespace loader
}  // namespace tailsim
