// Sweeps in an experiment file: {sweep: [v1, v2, ...]} and {range: [start, stop, step]}, found
// and checked in pass 1 (loader_parts.h); experiment_loader.cc expands their grid into cases.
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

Sweep parseSweep(const std::string* file, const YAML::Node& n, const std::string& key) {
  const Loc here{file, n.Mark(), key};
  if (n.size() != 1) fail(here, "a sweep is {sweep: [v1, v2, ...]} or {range: [start, stop, step]}, with no other keys");
  Sweep s{key, {}};
  if (const YAML::Node list = n["sweep"]) {
    if (!list.IsSequence() || list.size() == 0)
      fail(Loc{file, list.Mark(), key}, "sweep: needs a non-empty list of values, got " + describe(list));
    if (list.size() > kMaxSweepValues)
      fail(Loc{file, list.Mark(), key}, "sweep: more than " + std::to_string(kMaxSweepValues) + " values");
    std::set<std::string> seen;
    for (const YAML::Node& v : list) {
      if (!v.IsScalar()) fail(Loc{file, v.Mark().is_null() ? list.Mark() : v.Mark(), key},
                              "sweep values must be single values, got " + describe(v));
      if (!seen.insert(v.Scalar()).second) fail(Loc{file, v.Mark(), key}, "value " + quote(v.Scalar()) + " appears twice in the sweep");
      SweepValue sv;
      sv.node = v;
      sv.text = v.Scalar();
      sv.mark = v.Mark();
      s.values.push_back(sv);
    }
    return s;
  }
  const YAML::Node r = n["range"];
  const Loc rl{file, n.Mark(), key};
  if (!r.IsSequence() || r.size() != 3) fail(rl, "range: needs [start, stop, step], got " + describe(r));
  double a[3];
  for (int i = 0; i < 3; ++i) {
    if (!parseNumber(r[i], a[i])) fail(rl, "range: [start, stop, step] must be numbers, got " + describe(r[i]));
    if (!std::isfinite(a[i])) fail(rl, "range: values must be finite, got " + quote(r[i].Scalar()));
  }
  const double start = a[0], stop = a[1], step = a[2];
  if (step == 0.0) fail(rl, "range: step must not be 0");
  if ((stop - start) * step < 0.0) fail(rl, "range: step " + formatG(step) + " moves away from stop " + formatG(stop));
  // stop is included within 1e-9 |step|.
  const double count = std::floor((stop - start) / step + 1e-9) + 1.0;
  if (count > static_cast<double>(kMaxSweepValues))
    fail(rl, "range: more than " + std::to_string(kMaxSweepValues) + " values");
  std::set<std::string> seen;
  const double tol = 1e-9 * std::abs(step);
  for (long i = 0; i < static_cast<long>(count); ++i) {
    double v = start + static_cast<double>(i) * step;  // no accumulated rounding
    if (std::abs(v - stop) <= tol) v = stop;
    if (std::abs(v) <= tol) v = 0.0;
    SweepValue sv;
    sv.from_range = true;
    sv.number = v;
    sv.text = formatG(v);
    sv.mark = n.Mark();
    if (!seen.insert(sv.text).second)
      fail(rl, "range: values " + sv.text + " are not distinct at %g precision; list them with sweep: [...]");
    s.values.push_back(sv);
  }
  return s;
}

// Pass 1: every sweep in the document, in file order.
void collectSweeps(const std::string* file, const YAML::Node& n, const std::string& key, std::vector<Sweep>& out) {
  if (n.IsMap()) {
    if (isSweepMap(n)) {
      out.push_back(parseSweep(file, n, key));
      return;
    }
    for (const auto& kv : n)
      if (kv.first.IsScalar()) collectSweeps(file, kv.second, joinKey(key, kv.first.Scalar()), out);
  } else if (n.IsSequence()) {
    for (std::size_t i = 0; i < n.size(); ++i) collectSweeps(file, n[i], indexKey(key, i), out);
  }
}

}  // namespace loader
}  // namespace tailsim
