#include "experiments/folder_inputs.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "models/mujoco/robot_import.h"
#include "common/sha256.h"

namespace tailsim {

namespace {

std::string readWhole(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

// Byte offset of a node's first character: from its line and column (0-based in yaml-cpp).
size_t offsetOf(const std::string& text, const YAML::Mark& m) {
  size_t at = 0;
  for (int line = 0; line < m.line; ++line) {
    at = text.find('\n', at);
    if (at == std::string::npos) return std::string::npos;
    ++at;
  }
  return at + static_cast<size_t>(m.column);
}

// Length of the scalar written at `at` whose value is `value`: a quoted scalar up to its closing
// quote, a plain one as long as its value. npos when the text there is not that scalar.
size_t scalarLength(const std::string& text, size_t at, const std::string& value) {
  if (at >= text.size()) return std::string::npos;
  const char q = text[at];
  if (q == '"' || q == '\'') {
    for (size_t i = at + 1; i < text.size() && text[i] != '\n'; ++i) {
      if (q == '"' && text[i] == '\\') { ++i; continue; }
      if (text[i] == q) {
        if (q == '\'' && i + 1 < text.size() && text[i + 1] == '\'') { ++i; continue; }
        return i + 1 - at;
      }
    }
    return std::string::npos;
  }
  return text.compare(at, value.size(), value) == 0 ? value.size() : std::string::npos;
}

struct Replacement {
  size_t at, length;
  std::string by;
};

}  // namespace

std::map<std::string, std::string> folderInputs(const Experiment& e) {
  if (e.cases.empty()) throw std::runtime_error("experiment " + e.name + " has no cases");
  const std::string text = readWhole(e.source_file);
  const YAML::Node root = YAML::Load(text);  // the loader has read this file already: it parses
  const YAML::Node robot = root["robot"];
  auto cannot = [&](const YAML::Node& n, const std::string& why) {
    return std::runtime_error(e.source_file + ":" + std::to_string(n.Mark().line + 1) + ":" +
                              std::to_string(n.Mark().column + 1) + ": robot: cannot copy into the result folder: " + why);
  };
  // Each written robot value -> the file it resolved to (from the cases, i.e. the loader's answer).
  std::vector<std::pair<YAML::Node, std::string>> values;  // scalar node, robot file
  if (e.cases.front().robot_model) {
    // A robot from its model file: the model as tailsim compiles it (includes inlined, asset folders
    // absolute, missing-file visual geoms dropped), which stands and derives the same robot.
    const YAML::Node file = robot.IsMap() ? robot["mjcf"] : YAML::Node();
    if (!file || !file.IsScalar()) throw cannot(robot, "robot.mjcf is not a single value");
    const ExperimentCase& first = e.cases.front();
    for (const ExperimentCase& c : e.cases)
      if (!c.robot_derived || c.robot_model->file != first.robot_model->file)
        throw cannot(file, c.robot_derived ? "cases use different model files" : "the robot was not derived");
    const size_t at = offsetOf(text, file.Mark());
    const size_t len = scalarLength(text, at, file.Scalar());
    if (len == std::string::npos) throw cannot(file, "its value is not written on one line");
    std::map<std::string, std::string> out;
    out["robot.xml"] = first.robot_derived->model.xml;
    out["experiment.yaml"] = std::string(text).replace(at, len, "robot.xml");
    return out;
  }
  if (robot.IsScalar()) {
    for (const ExperimentCase& c : e.cases)
      if (c.robot_file != e.cases.front().robot_file) throw cannot(robot, "cases use different robot files");
    values.emplace_back(robot, e.cases.front().robot_file);
  } else if (robot.IsMap() && robot["sweep"] && robot["sweep"].IsSequence()) {
    for (const YAML::Node& v : robot["sweep"]) {
      const auto c = std::find_if(e.cases.begin(), e.cases.end(), [&](const ExperimentCase& k) {
        const auto s = k.sweep_values.find("robot");
        return s != k.sweep_values.end() && s->second == v.Scalar();
      });
      if (c == e.cases.end()) throw cannot(v, "no case uses robot " + v.Scalar());
      values.emplace_back(v, c->robot_file);
    }
  } else {
    throw cannot(robot, "robot: is neither a value nor a sweep of values");
  }
  std::map<std::string, std::string> out;
  std::vector<Replacement> edits;
  for (size_t k = 0; k < values.size(); ++k) {
    const auto& [node, file] = values[k];
    const std::string name = values.size() == 1 ? "robot.yaml" : "robot-" + std::to_string(k + 1) + ".yaml";
    out[name] = readWhole(file);
    const size_t at = offsetOf(text, node.Mark());
    const size_t len = scalarLength(text, at, node.Scalar());
    if (len == std::string::npos) throw cannot(node, "its value is not written on one line");
    edits.push_back({at, len, name});
  }
  std::string yaml = text;
  std::sort(edits.begin(), edits.end(), [](const Replacement& a, const Replacement& b) { return a.at > b.at; });
  for (const Replacement& r : edits) yaml.replace(r.at, r.length, r.by);
  out["experiment.yaml"] = yaml;
  return out;
}

std::string withValueAt(const std::string& file, const std::string& text, const std::vector<std::string>& path,
                        const std::string& by) {
  YAML::Node v = YAML::Load(text);
  std::string key;
  for (const std::string& k : path) {
    key += (key.empty() ? "" : ".") + k;
    const YAML::Node& map = v;  // const: looking a key up must not add it
    v = map.IsMap() && map[k] ? YAML::Node(map[k]) : YAML::Node(YAML::NodeType::Undefined);
    if (!v.IsDefined()) break;
  }
  if (!v.IsDefined() || !v.IsScalar()) throw std::runtime_error(file + ": " + key + ": expected a value to copy the folder's inputs");
  const size_t at = offsetOf(text, v.Mark());
  const size_t len = scalarLength(text, at, v.Scalar());
  if (len == std::string::npos) throw std::runtime_error(file + ": " + key + ": its value is not written on one line");
  std::string out = text;
  out.replace(at, len, by);
  return out;
}

std::string suiteFolderFile(const std::vector<Experiment>& suite) {
  std::string s =
      "# The suite as run: each member's experiment file as copied into its result folder (its robot:\n"
      "# names the robot file copied beside it). `tailsim run DIR/experiment.yaml --out NEW` runs it again.\n"
      "experiments:\n";
  for (const Experiment& e : suite) {
    std::string q;  // double-quoted: a name may hold any character YAML gives a meaning
    for (char ch : e.name + "/experiment.yaml") q += (ch == '"' || ch == '\\') ? std::string("\\") + ch : std::string(1, ch);
    s += "  - \"" + q + "\"\n";
  }
  return s;
}

std::string mjcfFileName(const std::string& xml) { return "mjcf/" + sha256Hex(xml).substr(0, 16) + ".xml"; }

}  // namespace tailsim
