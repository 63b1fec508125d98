#include "plotting/result_folder.h"
#include "plotting/style.h"


#include <algorithm>
#include <cctype>
#include <unordered_map>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "experiments/model_registry.h"
#include "experiments/time_series_h5.h"
#include "experiments/robot_model_cases.h"
#include "common/atomic_file.h"
#include "results/csv.h"

namespace tailsim {

namespace fs = std::filesystem;
using nlohmann::json;

std::optional<double> parseNumber(const std::string& s) {
  if (s.empty()) return std::nullopt;
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end == s.c_str()) return std::nullopt;
  while (*end == ' ') ++end;
  if (*end != '\0') return std::nullopt;
  return v;
}

double SweepAxis::number(size_t i) const {
  if (!numeric) return static_cast<double>(i);
  return *parseNumber(values.at(i));
}

int SweepAxis::indexOf(const std::string& value) const {
  for (size_t i = 0; i < values.size(); ++i)
    if (values[i] == value) return static_cast<int>(i);
  return -1;
}

std::string leafKey(const std::string& key) {
  const size_t dot = key.rfind('.');
  return dot == std::string::npos ? key : key.substr(dot + 1);
}

std::string axisLabel(const std::string& key) {
  std::string leaf = leafKey(key);
  std::string index;
  if (const size_t b = leaf.find('['); b != std::string::npos) {
    index = " (joint " + leaf.substr(b + 1, leaf.size() - b - 2) + ")";
    leaf = leaf.substr(0, b);
  }
  static const std::map<std::string, std::string> known = {
      {"theta0_deg", "θ0 [deg]"},       {"dtheta_deg", "Δθ [deg]"},
      {"dT_s", "ΔT [s]"},               {"w_ss", "w_ss"},
      {"d_Q2B_m", "d_Q2B [m]"},         {"links", "tail links n"},
      {"theta_deg", "θ [deg]"},         {"peak_speed_dps", "peak joint speed [deg/s]"},
      {"thetadot_max_dps", "θ̇_max [deg/s]"}, {"mu_s", "μ_s"},
      {"mu_d", "μ_d"},                  {"t0_s", "t0 [s]"}};
  if (auto it = known.find(leaf); it != known.end()) return it->second + index;
  static const std::vector<std::pair<std::string, std::string>> units = {
      {"_dps2", "deg/s²"}, {"_dps", "deg/s"}, {"_deg", "deg"}, {"_radps2", "rad/s²"},
      {"_radps", "rad/s"}, {"_rad", "rad"},   {"_kgm2", "kg m²"}, {"_kg", "kg"},
      {"_Nm", "N m"},      {"_N", "N"},       {"_mps", "m/s"},  {"_m", "m"}, {"_s", "s"}};
  for (const auto& [suffix, unit] : units)
    if (leaf.size() > suffix.size() && leaf.compare(leaf.size() - suffix.size(), suffix.size(), suffix) == 0)
      return leaf.substr(0, leaf.size() - suffix.size()) + " [" + unit + "]" + index;
  return leaf + index;
}

namespace {

std::string valueText(const json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_number()) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.12g", v.get<double>());
    return buf;
  }
  return v.dump();
}

double numberOr(const json& j, const char* key, double fallback) {
  auto it = j.find(key);
  return (it != j.end() && it->is_number()) ? it->get<double>() : fallback;
}

}  // namespace

RunRecord readRunRecord(const json& j) {
  RunRecord run;
  run.ok = j.value("ok", true);
  run.phi_net_deg = numberOr(j, "phi_net_deg", NAN);
  run.t_stop_s = numberOr(j, "t_stop_s", NAN);
  run.wall_time_s = numberOr(j, "wall_time_s", NAN);
  run.stick_slip_events = static_cast<int>(numberOr(j, "stick_slip_events", 0));
  if (auto x = j.find("extra"); x != j.end() && x->is_object())
    run.phi_net_uncertainty_deg = numberOr(*x, "phi_net_uncertainty_deg", NAN);
  if (j.contains("error") && j["error"].is_string()) run.error = j["error"].get<std::string>();
  if (auto w = j.find("warnings"); w != j.end() && w->is_array())
    for (const json& x : *w)
      if (x.is_string()) run.warnings.push_back(x.get<std::string>());
  return run;
}

namespace {

CaseRecord parseCase(const json& c) {
  CaseRecord r;
  r.name = c.value("name", std::string("base"));
  r.dir = c.value("dir", caseDirName(r.name));  // recorded by the run; older folders: the same mapping
  if (auto s = c.find("sweep"); s != c.end() && s->is_object())
    for (auto it = s->begin(); it != s->end(); ++it) r.sweep[it.key()] = valueText(it.value());
  if (auto v = c.find("verdict"); v != c.end() && v->is_string()) r.verdict = v->get<std::string>();
  if (auto runs = c.find("runs"); runs != c.end() && runs->is_object()) {
    for (auto it = runs->begin(); it != runs->end(); ++it) r.runs[it.key()] = readRunRecord(it.value());
  }
  return r;
}

json readJson(const fs::path& p) {
  // A regular file of the folder only (no symlink, FIFO or device; bounded: readResultFile).
  const std::optional<std::string> text = readResultFile(p.string());
  if (!text) throw std::runtime_error("cannot read " + p.string());
  try {
    return json::parse(*text);
  } catch (const json::exception& e) {
    throw std::runtime_error(p.string() + ": " + e.what());
  }
}

}  // namespace

std::string ExperimentResults::csvPath(const CaseRecord& c, const std::string& model) const {
  return (fs::path(dir) / "cases" / c.dir / (model + ".csv")).string();
}

TimeSeries ExperimentResults::series(const CaseRecord& c, const std::string& model) const {
  if (const ExperimentCase* rc = resolvedCase(c)) {
    if (rc->output.time_series == TimeSeriesOutput::kNone)
      throw std::runtime_error("case " + c.name + " has no time series (output.time_series: none): time-series "
                               "figures need output.time_series: full or thin; results.csv has its results");
    if (rc->output.time_series_file == TimeSeriesFile::kHdf5)
      return TimeSeriesH5Reader((fs::path(dir) / "time_series.h5").string()).read(c.dir, model);
  }
  return readCsv(csvPath(c, model));
}

std::string ExperimentResults::seriesNote() const {
  size_t none = 0;
  for (const CaseRecord& c : cases)
    if (const ExperimentCase* rc = resolvedCase(c); rc && rc->output.time_series == TimeSeriesOutput::kNone) ++none;
  if (none == 0) return {};
  return name + ": " + std::to_string(none) + " of " + std::to_string(cases.size()) +
         " cases have no time series (output.time_series: none); figures over time need output.time_series: full "
         "or thin, figures of phi_net over the swept values are drawn from results.csv";
}

std::string RunRecord::phiText() const {
  if (!ok || !std::isfinite(phi_net_deg)) return "n/a";
  char b[96];
  if (std::isfinite(phi_net_uncertainty_deg))
    std::snprintf(b, sizeof b, "%+.3f +- %.3f", phi_net_deg, phi_net_uncertainty_deg);
  else
    std::snprintf(b, sizeof b, "%+.3f", phi_net_deg);
  const bool uncertain = std::any_of(warnings.begin(), warnings.end(), [](const std::string& w) {
    return w.compare(0, sizeof kUncertainWarning - 1, kUncertainWarning) == 0;
  });
  return std::string(b) + (uncertain ? " (uncertain)" : "");
}

double ExperimentResults::phiNet(const CaseRecord& c, const std::string& model) const {
  auto it = c.runs.find(model);
  if (it == c.runs.end() || !it->second.ok) return NAN;
  return it->second.phi_net_deg;
}

const ExperimentCase* ExperimentResults::resolvedCase(const CaseRecord& c) const {
  const auto it = resolved.find(c.name);
  return it == resolved.end() ? nullptr : &it->second;
}

bool ExperimentResults::hasModel(const std::string& model) const {
  return std::find(models.begin(), models.end(), model) != models.end();
}

const CaseRecord* ExperimentResults::find(const std::map<std::string, std::string>& sweep) const {
  for (const CaseRecord& c : cases) {
    bool all = true;
    for (const auto& [k, v] : sweep) {
      auto it = c.sweep.find(k);
      if (it == c.sweep.end() || it->second != v) { all = false; break; }
    }
    if (all) return &c;
  }
  return nullptr;
}

std::vector<std::vector<const CaseRecord*>> caseGrid(const ExperimentResults& r, const SweepAxis& ay,
                                                     const SweepAxis& ax) {
  std::vector<std::vector<const CaseRecord*>> g(ay.values.size(), std::vector<const CaseRecord*>(ax.values.size()));
  auto index = [](const SweepAxis& a) {
    std::unordered_map<std::string, size_t> m;
    for (size_t i = 0; i < a.values.size(); ++i) m.emplace(a.values[i], i);
    return m;
  };
  const auto iy_of = index(ay), ix_of = index(ax);
  for (const CaseRecord& c : r.cases) {
    const auto vy = c.sweep.find(ay.key), vx = c.sweep.find(ax.key);
    if (vy == c.sweep.end() || vx == c.sweep.end()) continue;
    const auto iy = iy_of.find(vy->second), ix = ix_of.find(vx->second);
    if (iy == iy_of.end() || ix == ix_of.end()) continue;
    const CaseRecord*& cell = g[iy->second][ix->second];
    if (!cell) cell = &c;
  }
  return g;
}

namespace {

// A name for a message: control characters as '?', at most 120 bytes.
std::string shownName(const std::string& s) {
  std::string out = s.substr(0, 120);
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  return out + (s.size() > 120 ? "..." : "");
}

// A result folder may come from elsewhere: the names read back from it are input. The experiment
// name (figure stems, data files) follows the loader's rule (experimentNameProblem; an absent name
// is taken from experiment.yaml or the folder later); a case's folder is one caseDirName could have
// made: [A-Za-z0-9.=,_-] and '~', 1 to 100 bytes, not starting with '.' or '-'. Else an error
// naming the file.
void checkExperimentName(const std::string& name, const fs::path& file) {
  if (name.empty()) return;
  if (const std::string why = experimentNameProblem(name); !why.empty())
    throw std::runtime_error(file.string() + ": experiment name '" + shownName(name) + "' " + why +
                             " (this folder was not written by tailsim as it is)");
}
void checkCaseDir(const CaseRecord& c, const fs::path& file) {
  bool ok = !c.dir.empty() && c.dir.size() <= 100 && c.dir[0] != '.' && c.dir[0] != '-';
  for (const char ch : c.dir)
    ok = ok && (std::isalnum(static_cast<unsigned char>(ch)) || std::string(".=,_-~").find(ch) != std::string::npos);
  if (!ok)
    throw std::runtime_error(file.string() + ": case '" + shownName(c.name) + "' has the folder '" + shownName(c.dir) +
                             "', which tailsim never writes (1 to 100 of A-Z a-z 0-9 . = , _ - ~, not starting "
                             "with '.' or '-'; this folder was not written by tailsim as it is)");
}

// Stage 1 of loadResults: the experiment's name, source, kind, swept keys and cases from
// summary.json, or, from an interrupted run, its journal or its case folders.
void readCaseRecords(const fs::path& root, const std::string& dir, ExperimentResults& r,
                     std::vector<std::string>& keys) {
  if (fs::exists(root / "summary.json")) {
    const json s = readJson(root / "summary.json");
    r.name = s.value("experiment", std::string());
    checkExperimentName(r.name, root / "summary.json");
    r.source = s.value("source", std::string());
    r.description = s.value("description", std::string());
    r.kind = s.value("kind", std::string());
    if (auto k = s.find("swept_keys"); k != s.end() && k->is_array())
      for (const json& key : *k) keys.push_back(key.get<std::string>());
    if (auto cs = s.find("cases"); cs != s.end() && cs->is_array())
      for (const json& c : *cs) {
        r.cases.push_back(parseCase(c));
        checkCaseDir(r.cases.back(), root / "summary.json");
      }
  } else if (fs::exists(root / "cases.jsonl") && !fs::is_directory(root / "cases")) {
    // an interrupted run whose cases have no folder: its journal (a torn last line is skipped)
    std::istringstream in(readResultFile((root / "cases.jsonl").string()).value_or(std::string()));
    std::string line;
    while (std::getline(in, line)) {
      const json j = json::parse(line, nullptr, false);
      if (!j.is_object()) continue;
      if (r.name.empty()) checkExperimentName(r.name = j.value("experiment", std::string()), root / "cases.jsonl");
      if (r.source.empty()) r.source = j.value("source", std::string());
      r.cases.push_back(parseCase(j));
      checkCaseDir(r.cases.back(), root / "cases.jsonl");
    }
  } else if (fs::is_directory(root / "cases")) {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(root / "cases"))
      if (fs::exists(e.path() / "result.json")) files.push_back(e.path() / "result.json");
    std::sort(files.begin(), files.end());
    for (const fs::path& f : files) {
      const json j = readJson(f);
      if (r.name.empty()) checkExperimentName(r.name = j.value("experiment", std::string()), f);  // as the runner writes it
      if (r.source.empty()) r.source = j.value("source", std::string());
      r.cases.push_back(parseCase(j));
      checkCaseDir(r.cases.back(), f);
    }
  } else {
    throw std::runtime_error(dir + " is not a result folder (no summary.json, no cases/, no cases.jsonl)");
  }
}

// Stage 2: the cases as run, from the folder's own copies (experiment.yaml -> robot.yaml); fills
// in the kind, description, name and link count the records left open, or says why it cannot.
void resolveCases(const fs::path& root, ExperimentResults& r) {
  const bool kind_given = !r.kind.empty();
  if (!kind_given) r.kind = "simulate";
  if (!fs::exists(root / "experiment.yaml")) {
    r.resolve_error = (root / "experiment.yaml").string() + " is missing";
    return;
  }
  try {
    Experiment e = loadExperiment((root / "experiment.yaml").string());
    resolveRobotModels(e);  // a robot from its model file: the values the run used
    for (const ExperimentCase& c : e.cases) {
      r.resolved.emplace(c.name, c);
      r.articulated = r.articulated || static_cast<bool>(c.robot_model);
    }
    if (!kind_given && !e.cases.empty()) r.kind = name(e.cases.front().kind);
    if (r.description.empty()) r.description = e.description;
    if (r.name.empty()) r.name = e.name;
    r.links = e.cases.empty() ? 0 : e.cases.front().robot.numLinks();
    for (const ExperimentCase& c : e.cases)
      if (c.robot.numLinks() != e.cases.front().robot.numLinks()) r.links = 0;
  } catch (const std::exception& ex) {
    r.resolve_error = ex.what();
  }
}

// Stage 3: one axis per key with two or more values (summary order first, then any others found
// in the cases); a numeric axis's values in increasing order.
void findAxes(ExperimentResults& r, std::vector<std::string> keys) {
  for (const CaseRecord& c : r.cases)
    for (const auto& [k, v] : c.sweep)
      if (std::find(keys.begin(), keys.end(), k) == keys.end()) keys.push_back(k);
  for (const std::string& k : keys) {
    SweepAxis a;
    a.key = k;
    for (const CaseRecord& c : r.cases) {
      auto it = c.sweep.find(k);
      if (it != c.sweep.end() && a.indexOf(it->second) < 0) a.values.push_back(it->second);
    }
    if (a.values.size() < 2) continue;
    for (const std::string& v : a.values) a.numeric = a.numeric && parseNumber(v).has_value();
    if (a.numeric)
      std::stable_sort(a.values.begin(), a.values.end(),
                       [](const std::string& x, const std::string& y) { return *parseNumber(x) < *parseNumber(y); });
    r.axes.push_back(a);
  }
}

// Stage 4: the models that ran any case, in the registry's order (unknown ones last).
void findModels(const std::string& dir, ExperimentResults& r) {
  for (const CaseRecord& c : r.cases)
    for (const auto& [m, run] : c.runs)
      if (!r.hasModel(m)) {
        // a model name is part of figure and data file names too
        if (const std::string why = experimentNameProblem(m); !why.empty())
          throw std::runtime_error(dir + ": case '" + shownName(c.name) + "' has a run of the model '" + shownName(m) +
                                   "', a name that " + why + " (this folder was not written by tailsim as it is)");
        r.models.push_back(m);
      }
  std::stable_sort(r.models.begin(), r.models.end(), [](const std::string& a, const std::string& b) {
    const std::vector<std::string> names = modelNames();  // registry order, unknown ones last
    auto rank = [&](const std::string& m) { return std::find(names.begin(), names.end(), m) - names.begin(); };
    return rank(a) < rank(b);
  });
}

}  // namespace

ExperimentResults loadResults(const std::string& dir) {
  ExperimentResults r;
  r.dir = dir;
  const fs::path root(dir);
  std::vector<std::string> keys;
  readCaseRecords(root, dir, r, keys);
  resolveCases(root, r);
  if (r.name.empty()) r.name = root.filename().string();
  findAxes(r, keys);
  findModels(dir, r);
  return r;
}

// A subfolder is an experiment's result folder when it has summary.json, a journal, or a cases/
// folder with a case folder in it (the result page's DIR/page/cases holds only .js files).
namespace {
bool isExperimentFolder(const fs::path& p) {
  if (fs::exists(p / "summary.json") || fs::exists(p / "cases.jsonl")) return true;
  std::error_code ec;
  if (!fs::is_directory(p / "cases", ec)) return false;
  for (const auto& e : fs::directory_iterator(p / "cases", ec))
    if (e.is_directory()) return true;
  return false;
}
}  // namespace

std::vector<ExperimentResults> loadResultTree(const std::string& dir) {
  const fs::path root(dir);
  if (fs::exists(root / "summary.json")) return {loadResults(dir)};
  std::vector<fs::path> subs;
  if (fs::is_directory(root))
    for (const auto& e : fs::directory_iterator(root))
      if (e.is_directory() && isExperimentFolder(e.path())) subs.push_back(e.path());
  std::sort(subs.begin(), subs.end());
  if (subs.empty()) throw std::runtime_error(dir + " holds no result folder (no summary.json in it or its subfolders)");
  std::vector<ExperimentResults> out;
  for (const fs::path& p : subs) out.push_back(loadResults(p.string()));
  return out;
}

std::string warningShape(const std::string& w) {
  auto digit = [&](size_t i) { return i < w.size() && w[i] >= '0' && w[i] <= '9'; };
  std::string s;
  for (size_t i = 0; i < w.size();) {
    if (!digit(i)) {
      s += w[i++];
      continue;
    }
    s += '#';  // one number: digits with an optional fraction ("23", "21.2", "1e-3" -> "#e-#")
    while (digit(i) || (w[i] == '.' && digit(i + 1))) ++i;
  }
  return s;
}

std::vector<std::string> allModels(const std::vector<ExperimentResults>& results) {
  std::vector<std::string> out;
  for (const ExperimentResults& r : results)
    for (const std::string& m : r.models)
      if (std::find(out.begin(), out.end(), m) == out.end()) out.push_back(m);
  return out;
}

std::string ExperimentResults::modelTitle(const std::string& model) const {
  return tailsim::modelTitle(model, articulated);
}

}  // namespace tailsim
