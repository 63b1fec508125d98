// YAML experiment files -> validated ExperimentCases (docs/experiment-format.md).
//
// Two passes over an experiment file: (1) find every sweep ({sweep: [...]} / {range: [...]}) and
// remember it by its dotted key; (2) for every point of the sweep grid, read the whole file again
// with each sweep replaced by its value at that point, building and validating one ExperimentCase.
// Every case is built before anything is returned, so a bad value anywhere in the grid is
// reported before any work starts. Each error names file:line:col and the dotted key.
#include "experiments/experiment_loader.h"
#include "experiments/yaml_file.h"

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
using namespace loader;
namespace {

bool isSuite(const YAML::Node& doc) { return doc.IsMap() && doc["experiments"]; }

Experiment readExperiment(Loader& L, const std::string* file, const YAML::Node& doc) {
  Experiment e;
  e.source_file = *file;

  std::vector<Sweep> sweeps;
  collectSweeps(file, doc, "", sweeps);
  for (const Sweep& s : sweeps)
    if (s.key == "name") fail(Loc{file, s.values.front().mark, s.key}, "the experiment name cannot be swept");
  double total = 1.0;
  for (const Sweep& s : sweeps) total *= static_cast<double>(s.values.size());
  if (total > static_cast<double>(kMaxCases))
    fail(Loc{file, doc.Mark(), ""}, "the sweeps make " + formatG(total) + " cases, more than " + std::to_string(kMaxCases));

  // Case-name labels: the leaf key, or the dotted key where two swept leaves share a name.
  std::vector<std::string> label;
  for (const Sweep& s : sweeps) {
    e.swept_keys.push_back(s.key);
    const std::size_t dot = s.key.rfind('.');
    label.push_back(dot == std::string::npos ? s.key : s.key.substr(dot + 1));
  }
  std::vector<std::string> shown = label;
  for (std::size_t i = 0; i < label.size(); ++i)
    if (std::count(label.begin(), label.end(), label[i]) > 1) shown[i] = sweeps[i].key;

  std::vector<std::size_t> idx(sweeps.size(), 0);  // odometer; the last sweep varies fastest
  for (;;) {
    Picks picks;
    std::string caseName;
    std::map<std::string, std::string> values;
    for (std::size_t i = 0; i < sweeps.size(); ++i) {
      const SweepValue& v = sweeps[i].values[idx[i]];
      picks[sweeps[i].key] = &v;
      caseName += (i ? "," : "") + shown[i] + "=" + v.text;
      values[sweeps[i].key] = v.text;
    }
    const Reader r(file, &picks);
    ExperimentCase c = readCase(L, r, doc, *file);
    c.name = sweeps.empty() ? "base" : caseName;
    c.sweep_values = std::move(values);
    e.cases.push_back(std::move(c));

    std::size_t i = sweeps.size();
    while (i > 0 && ++idx[i - 1] == sweeps[i - 1].values.size()) idx[--i] = 0;
    if (i == 0) break;
  }
  if (const WorkExcess x = checkExperimentWork(e.cases); !x.what.empty()) fail(Loc{file, doc.Mark(), ""}, x.what);
  e.name = e.cases.front().experiment;
  if (doc["description"] && doc["description"].IsScalar()) e.description = doc["description"].Scalar();
  return e;
}

void readSuite(Loader& L, const std::string* file, const YAML::Node& doc, std::vector<std::string>& stack,
               std::vector<Experiment>& out, std::map<std::string, std::string>& names, WorkTotal& total) {
  const Reader r(file, nullptr);
  const MapView m = r.map(r.root(doc), {"experiments", "description"});
  if (const Item* d = m.get("description")) r.string(*d);
  const Item& list = r.need(m, "experiments");
  const std::vector<Item> entries = r.list(list);
  if (entries.empty()) r.fail(list, "needs at least one experiment file");
  stack.push_back(*file);
  for (const Item& entry : entries) {
    const std::string rel = r.string(entry);
    const std::string* path = L.keep(resolveRelative(*file, rel));
    std::error_code ec;
    if (!fs::is_regular_file(*path, ec)) r.fail(entry, "experiment file not found: " + *path);
    if (std::find(stack.begin(), stack.end(), *path) != stack.end()) r.fail(entry, "suite includes itself: " + *path);
    const YAML::Node sub = parseYaml(path);
    try {
      requireInputFor(sub, *path, "run");
    } catch (const ConfigError& e) {
      r.fail(entry, e.what());
    }
    if (isSuite(sub)) {
      if (stack.size() >= kMaxSuiteDepth)
        r.fail(entry, "suites are nested more than " + std::to_string(kMaxSuiteDepth) +
                          " deep (a suite listing a suite listing a suite ...)");
      readSuite(L, path, sub, stack, out, names, total);
      continue;
    }
    Experiment e = readExperiment(L, path, sub);
    const auto [it, fresh] = names.emplace(e.name, *path);
    if (!fresh) r.fail(entry, "experiment name '" + e.name + "' is already used by " + it->second);
    // The members together, bounded as one experiment's work (and at most kMaxSuiteCases cases), as they load.
    total += totalWork(e.cases);
    if (total.cases > static_cast<double>(kMaxSuiteCases))
      r.fail(entry, "the suite's experiments up to this one make " + formatG(total.cases) + " cases, more than " +
                        std::to_string(kMaxSuiteCases) + " (docs/experiment-format.md \"Limits\"): split the suite");
    if (const std::string x = workTotalExcess(total, "suite's " + formatG(total.cases) + " cases up to this experiment");
        !x.empty())
      r.fail(entry, x);
    out.push_back(std::move(e));
  }
  stack.pop_back();
}

}  // namespace

std::string experimentNameProblem(const std::string& nm, std::size_t max_chars) {
  const bool control = std::any_of(nm.begin(), nm.end(), [](char ch) {
    return static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f;
  });
  // A leading '|', '<' or '$' would make gnuplot read a file name made from it as a shell pipe
  // or a datablock (gpFileName guards the scripts as well).
  if (nm.empty() || nm.size() > max_chars || nm == "." || nm == ".." || control ||
      nm.find_first_of("/\\") != std::string::npos || std::string("-|<$").find(nm[0]) != std::string::npos)
    return "must be a folder name: 1 to " + std::to_string(max_chars) +
           " characters, no '/', '\\' or control characters, not '.' or '..', not starting with '-', '|', '<' or '$'";
  return "";
}

Experiment loadExperiment(const std::string& path) {
  Loader L;
  const std::string* file = L.keep(absolutePath(path));
  std::error_code ec;
  if (!fs::is_regular_file(*file, ec)) throw ConfigError(*file + ": experiment file not found");
  // Its path goes into summary.json, which must be UTF-8: refuse now, not after every case ran.
  if (invalidUtf8At(*file) != std::string::npos)
    throw ConfigError(clip(*file, 200) + ": the file's path is not UTF-8; rename it");
  const YAML::Node doc = parseYaml(file);
  requireInputFor(doc, path, "run");
  if (isSuite(doc))
    fail(Loc{file, doc["experiments"].Mark(), "experiments"}, "this is a suite file; load it with loadExperimentSuite");
  return readExperiment(L, file, doc);
}

Experiment loadExperimentText(const std::string& text, const std::string& label) {
  Loader L;
  const std::string* file = L.keep(label);
  const YAML::Node doc = parseYamlText(file, text);
  if (isSuite(doc))
    fail(Loc{file, doc["experiments"].Mark(), "experiments"}, "a suite is given by its file; use loadExperimentSuite");
  return readExperiment(L, file, doc);
}

RobotFileData loadRobotFile(const std::string& name_or_path) {
  if (name_or_path.empty()) throw ConfigError("robot: needs a built-in robot name (paper) or the path of a robot file");
  const std::string abs = isBuiltinRobotName(name_or_path)
                              ? builtinRobotFile(name_or_path, Loc{&name_or_path, YAML::Mark::null_mark(), ""})
                                                           : absolutePath(name_or_path);
  std::error_code ec;
  if (!fs::is_regular_file(abs, ec)) throw ConfigError(abs + ": robot file not found");
  const std::unique_ptr<RobotFile> rf = readRobotFile(abs);
  RobotFileData d{rf->file, rf->base, {}};
  for (const auto& [n, links] : rf->tails) d.tails[n] = links.front();  // per-joint actuator keys: joint 1's
  return d;
}

std::vector<Experiment> loadExperimentSuite(const std::string& path) {
  Loader L;
  const std::string* file = L.keep(absolutePath(path));
  std::error_code ec;
  if (!fs::is_regular_file(*file, ec)) throw ConfigError(*file + ": experiment file not found");
  // Its path goes into summary.json, which must be UTF-8: refuse now, not after every case ran.
  if (invalidUtf8At(*file) != std::string::npos)
    throw ConfigError(clip(*file, 200) + ": the file's path is not UTF-8; rename it");
  const YAML::Node doc = parseYaml(file);
  requireInputFor(doc, path, "run");
  std::vector<Experiment> out;
  if (!isSuite(doc)) {
    out.push_back(readExperiment(L, file, doc));
    return out;
  }
  std::vector<std::string> stack;
  std::map<std::string, std::string> names;
  WorkTotal total;
  readSuite(L, file, doc, stack, out, names, total);
  return out;
}

}  // namespace tailsim
