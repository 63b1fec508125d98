// The trajectory section (settings/trajectory_section.h: split_cycle and spline families) and
// the pose of kind: pose.
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

struct JointLocs {
  Loc dT, w_ss;
};

// The trajectory section's keys (settings/trajectory_section.h): split-cycle (the default family)
// and spline (family: spline), each ending with family.
const std::vector<std::string> kSplitCycleKeys = settings::declaredKeys<SplitCycleSection>();
const std::vector<std::string> kSplineKeys = settings::declaredKeys<SplineSection>();

// The keys of a list but `family`, comma-separated.
std::string keysButFamily(const std::vector<std::string>& keys) {
  std::string s;
  for (const std::string& k : keys)
    if (k != "family") s += (s.empty() ? "" : ", ") + k;
  return s;
}

// family: spline -- per joint a clamped cubic spline through equally spaced knots (JointProfile).
std::vector<SplineParams> readSplineTrajectory(const Reader& r, const Item& item, const MapView& t, int n) {
  for (const auto& [k, it] : t.fields)
    if (std::find(kSplineKeys.begin(), kSplineKeys.end(), k) == kSplineKeys.end())
      r.fail(it, "not used with family: spline (spline keys: " + keysButFamily(kSplineKeys) + ")");
  std::vector<SplineParams> joints(static_cast<std::size_t>(n));
  // knots_deg: one list of knots for every joint, or a list of n lists (one per joint).
  const Item& kn = r.need(t, "knots_deg");
  const std::vector<Item> outer = r.list(kn);
  const bool per_joint = !outer.empty() && outer.front().node.IsSequence();
  std::vector<Item> lists;
  if (per_joint) {
    if (static_cast<int>(outer.size()) != n)
      r.fail(kn, "has " + std::to_string(outer.size()) + " knot lists but the tail has " + std::to_string(n) +
                     " joints: give one list of knots for all joints or one list per joint");
    lists = outer;
  } else {
    lists.assign(static_cast<std::size_t>(n), kn);
  }
  for (int i = 0; i < n; ++i) {
    const std::vector<Item> v = r.list(lists[i]);
    if (v.size() < 2 || v.size() > static_cast<std::size_t>(limits::kMaxSplineKnots))
      r.fail(lists[i], "needs 2.." + std::to_string(limits::kMaxSplineKnots) + " knots (start, interior knots, end), got " +
                           std::to_string(v.size()));
    for (const Item& x : v) joints[i].knots_rad.push_back(boundedDeg(r, x, limits::kMaxAbsTheta0Deg) * units::kRadPerDeg);
  }
  const std::vector<Item> dT = r.perJoint(r.need(t, "dT_s"), n);
  for (int i = 0; i < n; ++i) {
    joints[i].dT_s = r.positive(dT[i]);
    if (joints[i].dT_s < limits::kMinDT_s)
      r.fail(dT[i], "must be >= " + formatG(limits::kMinDT_s) + " s, got " + formatG(joints[i].dT_s) +
                        " (docs/experiment-format.md \"Limits\")");
  }
  if (const Item* t0 = t.get("t0_s")) {
    const std::vector<Item> v = r.perJoint(*t0, n);
    for (int i = 0; i < n; ++i) joints[i].t0_s = r.nonNegative(v[i]);
  }
  for (int i = 0; i < n; ++i) {  // JointProfile's own checks
    try {
      JointProfile check(joints[i]);
    } catch (const std::invalid_argument& e) {
      r.fail(per_joint ? lists[i] : kn, e.what());
    }
  }
  (void)item;
  return joints;
}

namespace {

// Stage 1: w_ss and t0_s, one value or one per joint. Defaults 0.25 and 0.
void readTiming(const Reader& r, const MapView& t, int n, std::vector<SplitCycleParams>& joints, std::vector<JointLocs>& locs) {
  if (const Item* w = t.get("w_ss")) {
    const std::vector<Item> v = r.perJoint(*w, n);
    for (int i = 0; i < n; ++i) {
      const double x = r.number(v[i]);
      if (!(x > 0.0 && x < 1.0)) r.fail(v[i], "must lie in (0, 1), got " + formatG(x));
      if (!(x >= limits::kMinWss && x <= limits::kMaxWss))
        r.fail(v[i], "must lie in [" + formatG(limits::kMinWss) + ", " + formatG(limits::kMaxWss) + "], got " + formatG(x) +
                         " (docs/experiment-format.md \"Limits\")");
      joints[i].w_ss = x;
      locs[i].w_ss = r.loc(v[i]);
    }
  } else {
    for (auto& j : joints) j.w_ss = 0.25;
  }
  if (const Item* t0 = t.get("t0_s")) {
    const std::vector<Item> v = r.perJoint(*t0, n);
    for (int i = 0; i < n; ++i) joints[i].t0_s = r.nonNegative(v[i]);
  }
}

// Stage 2 (rule: eq25): every joint's stroke from the peak speed thetadot_max (Eq. 25).
void readEqualPeakSpeed(const Reader& r, const MapView& t, const Item& rule, int n, std::vector<SplitCycleParams>& joints,
                        std::vector<JointLocs>& locs) {
  r.choice(rule, {"eq25"});
  for (const char* k : {"theta0_deg", "dtheta_deg", "dT_s", "peak_speed_dps"})
    if (const Item* x = t.get(k)) r.fail(*x, "not allowed with rule: eq25 (Eq. 25 sets it)");
  const Item* dps = t.get("thetadot_max_dps");
  const Item* radps = t.get("thetadot_max_radps");
  if (!dps && !radps) loader::fail(r.locAt(t.self, "thetadot_max_dps"), "rule: eq25 needs thetadot_max_dps or thetadot_max_radps");
  if (dps && radps) r.fail(*radps, "give thetadot_max_dps or thetadot_max_radps, not both");
  const Item& w = dps ? *dps : *radps;
  const double wmax = r.positive(w) * (dps ? units::kRadPerDeg : 1.0);
  for (int i = 0; i < n; ++i) {
    try {
      joints[i] = equalPeakSpeedParams(n, wmax, joints[i].w_ss, joints[i].t0_s);  // Eq. (25)
    } catch (const std::invalid_argument& e) {
      r.fail(w, e.what());
    }
    locs[i].dT = r.loc(w);
    if (!(joints[i].dT_s >= limits::kMinDT_s))
      r.fail(w, "gives dT_s = " + formatG(joints[i].dT_s) + " s (Eq. 25), shorter than " + formatG(limits::kMinDT_s) +
                    " s (docs/experiment-format.md \"Limits\")");
  }
}

// Stage 2 (no rule): theta0_deg, dtheta_deg, and dT_s or peak_speed_dps, per joint.
void readStroke(const Reader& r, const MapView& t, int n, std::vector<SplitCycleParams>& joints, std::vector<JointLocs>& locs) {
  for (const char* k : {"thetadot_max_dps", "thetadot_max_radps"})
    if (const Item* x = t.get(k)) r.fail(*x, "only used with rule: eq25");
  if (const Item* th0 = t.get("theta0_deg")) {
    const std::vector<Item> v = r.perJoint(*th0, n);
    for (int i = 0; i < n; ++i) joints[i].theta0_rad = boundedDeg(r, v[i], limits::kMaxAbsTheta0Deg) * units::kRadPerDeg;
  }
  const std::vector<Item> dth = r.perJoint(r.need(t, "dtheta_deg"), n);
  for (int i = 0; i < n; ++i) joints[i].dtheta_rad = boundedDeg(r, dth[i], limits::kMaxAbsDthetaDeg) * units::kRadPerDeg;
  const Item* dT = t.get("dT_s");
  const Item* peak = t.get("peak_speed_dps");
  if (!dT && !peak) loader::fail(r.locAt(t.self, "dT_s"), "give dT_s or peak_speed_dps");
  if (dT && peak) r.fail(*peak, "give dT_s or peak_speed_dps, not both");
  if (dT) {
    const std::vector<Item> v = r.perJoint(*dT, n);
    for (int i = 0; i < n; ++i) {
      joints[i].dT_s = r.number(v[i]);
      locs[i].dT = r.loc(v[i]);
      if (joints[i].dT_s > 0.0 && joints[i].dT_s < limits::kMinDT_s)
        r.fail(v[i], "must be >= " + formatG(limits::kMinDT_s) + " s, got " + formatG(joints[i].dT_s) +
                         " (docs/experiment-format.md \"Limits\")");
    }
  } else {
    const std::vector<Item> v = r.perJoint(*peak, n);
    for (int i = 0; i < n; ++i) {
      const double pk = r.positive(v[i]) * units::kRadPerDeg;
      joints[i].dT_s = 2.0 * std::abs(joints[i].dtheta_rad) / pk;  // peak speed 2 |dtheta| / dT (Eq. 23)
      if (!(joints[i].dT_s > 0.0)) r.fail(v[i], "dtheta_deg = 0 gives dT_s = 0; give dT_s instead");
      if (joints[i].dT_s < limits::kMinDT_s)
        r.fail(v[i], "gives dT_s = 2 |dtheta| / peak speed = " + formatG(joints[i].dT_s) + " s, shorter than " +
                         formatG(limits::kMinDT_s) + " s (docs/experiment-format.md \"Limits\")");
      locs[i].dT = r.loc(v[i]);
    }
  }
}

}  // namespace

// family: split_cycle: timing, then the stroke (rule: eq25 or given per joint), then
// SplitCycleProfile's own checks (dT > 0, w_ss in (0, 1), finite), each at the right value.
std::vector<SplitCycleParams> readTrajectory(const Reader& r, const Item& item, int n) {
  const MapView t = r.map(item, kSplitCycleKeys);
  if (const Item* f = t.get("family")) r.choice(*f, {"split_cycle"});  // spline: readSplineTrajectory
  std::vector<SplitCycleParams> joints(static_cast<std::size_t>(n));
  std::vector<JointLocs> locs(static_cast<std::size_t>(n), JointLocs{r.loc(item), r.loc(item)});
  readTiming(r, t, n, joints, locs);
  if (const Item* rule = t.get("rule")) readEqualPeakSpeed(r, t, *rule, n, joints, locs);
  else readStroke(r, t, n, joints, locs);
  for (int i = 0; i < n; ++i) {
    try {
      SplitCycleProfile check(joints[i]);
    } catch (const std::invalid_argument& e) {
      rethrowAt(e.what(), Origins{{"dT_s", locs[i].dT}, {"w_ss", locs[i].w_ss}}, r.loc(item));
    }
  }
  return joints;
}

PoseSpec readPose(const Reader& r, const Item& item, int n) {
  const MapView m = r.map(item, {"theta_deg", "thetadot_radps", "thetaddot_radps2"});
  PoseSpec p;
  auto read = [&](const char* key, double scale, std::vector<double>& out) {
    out.assign(static_cast<std::size_t>(n), 0.0);
    if (const Item* x = m.get(key)) {
      const std::vector<Item> v = r.perJoint(*x, n);
      for (int i = 0; i < n; ++i) out[i] = r.number(v[i]) * scale;
    }
  };
  read("theta_deg", units::kRadPerDeg, p.theta_rad);
  read("thetadot_radps", 1.0, p.thetadot_radps);
  read("thetaddot_radps2", 1.0, p.thetaddot_radps2);
  return p;
}

}  // namespace loader
}  // namespace tailsim
