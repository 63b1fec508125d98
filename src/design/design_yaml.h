// The YAML reading of the design layer's experiment files (kind: optimize, kind: maneuver) with the
// loader's conventions: ConfigError "<file>:<line>:<col>: <key>: <what>", unknown and duplicate keys
// refused. Internal to src/design/.
#pragma once

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "experiments/experiment_loader.h"
#include "experiments/yaml_file.h"
#include "common/number_text.h"

namespace tailsim {
namespace design_yaml {

namespace fs = std::filesystem;

inline std::string fmtG(double v) { return formatG(v, 10); }  // "%.10g"

// One value with where it came from.
struct Val {
  YAML::Node node;
  std::string key;
  YAML::Mark mark;
};

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}
  const std::string& file() const { return file_; }
  [[noreturn]] void fail(const YAML::Mark& m, const std::string& key, const std::string& what) const {
    std::string s = file_;
    if (!m.is_null()) s += ":" + std::to_string(m.line + 1) + ":" + std::to_string(m.column + 1);
    s += ": ";
    if (!key.empty()) s += key + ": ";
    throw ConfigError(s + what);
  }
  [[noreturn]] void fail(const Val& v, const std::string& what) const { fail(v.mark, v.key, what); }

  // The map's entries; a key not in `allowed` (or twice) is an error at the key.
  std::vector<std::pair<std::string, Val>> map(const Val& v, std::initializer_list<const char*> allowed) const {
    return map(v, std::vector<std::string>(allowed.begin(), allowed.end()));
  }
  std::vector<std::pair<std::string, Val>> map(const Val& v, const std::vector<std::string>& names) const {
    if (!v.node.IsMap()) fail(v, "expected a map of key: value");
    std::vector<std::pair<std::string, Val>> out;
    for (const auto& kv : v.node) {
      const std::string key = v.key.empty() ? kv.first.Scalar() : v.key + "." + kv.first.Scalar();
      if (!kv.first.IsScalar()) fail(kv.first.Mark(), v.key, "keys must be plain names");
      const std::string k = kv.first.Scalar();
      if (std::find(names.begin(), names.end(), k) == names.end())
        fail(kv.first.Mark(), key, unknownKeyMessage(k, names));
      for (const auto& e : out)
        if (e.first == k) fail(kv.first.Mark(), key, "duplicate key");
      const bool empty = kv.second.IsNull() || kv.second.Mark().is_null();
      out.emplace_back(k, Val{kv.second, key, empty ? kv.first.Mark() : kv.second.Mark()});
    }
    return out;
  }
  static const Val* get(const std::vector<std::pair<std::string, Val>>& m, const std::string& k) {
    for (const auto& e : m)
      if (e.first == k) return &e.second;
    return nullptr;
  }
  double number(const Val& v) const {
    if (!v.node.IsScalar()) fail(v, "expected a number");
    double x = 0;
    try {
      x = v.node.as<double>();
    } catch (const YAML::Exception&) {
      fail(v, "expected a number, got '" + v.node.Scalar() + "'");
    }
    if (!std::isfinite(x)) fail(v, "must be finite");
    return x;
  }
  double inRange(const Val& v, double lo, double hi) const {
    const double x = number(v);
    if (!(x >= lo && x <= hi)) fail(v, "must lie in [" + fmtG(lo) + ", " + fmtG(hi) + "], got " + fmtG(x));
    return x;
  }
  int integer(const Val& v, int lo, int hi) const {
    const double x = number(v);
    if (x != std::floor(x)) fail(v, "must be a whole number, got " + fmtG(x));
    if (!(x >= lo && x <= hi)) fail(v, "must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + fmtG(x));
    return static_cast<int>(x);
  }
  std::string choice(const Val& v, std::initializer_list<const char*> options) const {
    std::string names;
    for (const char* o : options) names += (names.empty() ? "" : ", ") + std::string(o);
    if (!v.node.IsScalar()) fail(v, "expected one of: " + names);
    const std::string s = v.node.Scalar();
    if (std::none_of(options.begin(), options.end(), [&](const char* o) { return s == o; }))
      fail(v, "'" + s + "' is not one of: " + names);
    return s;
  }
  bool boolean(const Val& v) const {
    const std::string s = choice(v, {"true", "false"});
    return s == "true";
  }
  std::string text(const Val& v) const {
    if (!v.node.IsScalar()) fail(v, "expected a string");
    return v.node.Scalar();
  }
  std::vector<Val> list(const Val& v, std::size_t min, std::size_t max) const {
    if (!v.node.IsSequence()) fail(v, "expected a list [a, b, ...]");
    if (v.node.size() < min || v.node.size() > max)
      fail(v, "expected " + (min == max ? std::to_string(min) : std::to_string(min) + " to " + std::to_string(max)) +
                  " values, got " + std::to_string(v.node.size()));
    std::vector<Val> out;
    for (std::size_t i = 0; i < v.node.size(); ++i)
      out.push_back(Val{v.node[i], v.key + "[" + std::to_string(i) + "]", v.node[i].Mark().is_null() ? v.mark : v.node[i].Mark()});
    return out;
  }
  // [lo, hi] with lo <= hi, both in [min, max].
  std::pair<double, double> interval(const Val& v, double min, double max) const {
    const std::vector<Val> l = list(v, 2, 2);
    const double a = inRange(l[0], min, max), b = inRange(l[1], min, max);
    if (a > b) fail(v, "expected [low, high] with low <= high, got [" + fmtG(a) + ", " + fmtG(b) + "]");
    return {a, b};
  }

 private:
  std::string file_;
};



using Map = std::vector<std::pair<std::string, Val>>;

// A required key of map m (as Reader::map returns it) whose node is parent.
inline const Val& need(const Reader& r, const Map& m, const Val& parent, const char* k) {
  const Val* v = Reader::get(m, k);
  if (!v) r.fail(parent.mark, parent.key.empty() ? k : parent.key + "." + k, "required key is missing");
  return *v;
}

// The keys every design file (kind optimize, kind maneuver) starts with: name (one safe path
// component of at most max_name_chars bytes, experimentNameProblem), description, kind (must be
// `kind`) and base (an experiment file, relative to this one).
struct DesignHead {
  std::string name, description, base_file;
};
inline DesignHead readDesignHead(const Reader& r, const Val& root, const Map& top, const std::string& source_file,
                                 const char* kind, std::size_t max_name_chars) {
  DesignHead h;
  h.name = r.text(need(r, top, root, "name"));
  if (const std::string why = experimentNameProblem(h.name, max_name_chars); !why.empty()) r.fail(need(r, top, root, "name"), why);
  if (const Val* d = Reader::get(top, "description")) h.description = r.text(*d);
  r.choice(need(r, top, root, "kind"), {kind});
  const Val& base = need(r, top, root, "base");
  h.base_file = (fs::path(source_file).parent_path() / r.text(base)).lexically_normal().string();
  std::error_code ec;  // a name too long for the file system is an error here, not an exception
  if (fs::is_directory(h.base_file, ec))
    r.fail(base, h.base_file + " is a folder: base names a one-case experiment file (kind: simulate)");
  if (!fs::is_regular_file(h.base_file, ec))
    r.fail(base, "no such experiment file: " + h.base_file + (ec ? " (" + ec.message() + ")" : std::string()));
  // A design file as the base (e.g. the optimize file itself): said here, at this key.
  std::string base_kind;
  try {
    const YAML::Node doc = loadBoundedYaml(h.base_file);
    if (doc.IsMap() && doc["kind"] && doc["kind"].IsScalar()) base_kind = doc["kind"].Scalar();
  } catch (const std::exception&) {
    // the experiment loader names the file's own error at its line
  }
  if (base_kind == "optimize" || base_kind == "maneuver")
    r.fail(base, h.base_file + " is a kind: " + base_kind +
                     " file: base names a one-case experiment file (kind: simulate), e.g. a best.yaml of tailsim "
                     "optimize or the experiment your design starts from");
  return h;
}

// A design file opened: its root map, its top-level keys (the head and one `section`), the head
// read. base() and section() are the nodes later errors point at.
struct DesignFile {
  Val root;
  Map top;
  DesignHead head;
  std::string section_key;
  const Val& base(const Reader& r) const { return need(r, top, root, "base"); }
  const Val& section(const Reader& r) const { return need(r, top, root, section_key.c_str()); }
};
// max_name_chars: shorter than an experiment's kMaxNameChars when the command derives a longer
// name from it (optimize's best.yaml is named <name>_best).
// A design file's base experiment must give its robot by numbers: one from a model file (robot:
// {mjcf: ...}) runs as the articulated robot, which the design commands do not search on.
inline void refuseModelFileBase(const Reader& r, const Val& base, bool from_model_file, const char* command) {
  if (from_model_file)
    r.fail(base, std::string("the base experiment takes its robot from a model file (robot: {mjcf: ...}); `tailsim ") +
                     command +
                     "` works on the robot's numbers: write them once with `tailsim robot MODEL --write-robot "
                     "ROBOT.yaml` (docs/your-robot.md), give its tail entry the joints' limits, and name ROBOT.yaml as "
                     "the base's robot");
}

inline DesignFile openDesignFile(const Reader& r, const std::string& source_file, const char* kind, const char* section,
                                 std::size_t max_name_chars = kMaxNameChars) {
  DesignFile f{Val{loadBoundedYaml(source_file), "", YAML::Mark()}, {}, {}, section};
  if (!f.root.node.IsMap()) r.fail(f.root, "the file must be a map of key: value");
  requireInputFor(f.root.node, source_file, kind);  // an experiment file given to optimize names `tailsim run`
  f.top = r.map(f.root, {"name", "description", "kind", "base", section});
  f.head = readDesignHead(r, f.root, f.top, source_file, kind, max_name_chars);
  return f;
}

}  // namespace design_yaml
}  // namespace tailsim
