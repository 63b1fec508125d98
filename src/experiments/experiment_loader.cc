// YAML experiment files -> validated ExperimentCases (docs/experiment-format.md).
//
// Two passes over an experiment file: (1) find every sweep ({sweep: [...]} / {range: [...]}) and
// remember it by its dotted key; (2) for every point of the sweep grid, read the whole file again
// with each sweep replaced by its value at that point, building and validating one ExperimentCase.
// Every case is built before anything is returned, so a bad value anywhere in the grid is
// reported before any work starts. Each error names file:line:col and the dotted key.
#include "experiments/experiment_loader.h"
#include "experiments/yaml_file.h"

#include <dlfcn.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include "experiments/model_registry.h"
#include "experiments/work_estimate.h"
#include "results/work_limits.h"
#include "results/number_text.h"
#include "settings/units.h"
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
namespace {

namespace fs = std::filesystem;


std::string joinList(std::initializer_list<const char*> names) {
  std::string s;
  for (const char* n : names) s += (s.empty() ? "" : ", ") + std::string(n);
  return s;
}

std::string joinKey(const std::string& parent, const std::string& k) {
  return parent.empty() ? k : parent + "." + k;
}
std::string indexKey(const std::string& parent, std::size_t i) { return parent + "[" + std::to_string(i) + "]"; }

// A value quoted in an error message: at most kMaxQuoted bytes (cut at a UTF-8 character
// boundary, then "..."), line breaks shown as \n, so an error is one readable line whatever the
// input (a robot file that is /etc/passwd, a 10 MB value).
constexpr std::size_t kMaxQuoted = 80;
std::string clip(const std::string& v, std::size_t max = kMaxQuoted) {
  std::size_t n = v.size();
  bool cut = false;
  if (n > max) {
    n = max;
    while (n > 0 && (static_cast<unsigned char>(v[n]) & 0xC0) == 0x80) --n;  // not inside a character
    cut = true;
  }
  std::string s;
  for (std::size_t i = 0; i < n; ++i) {
    if (v[i] == '\n') s += "\\n";
    else if (v[i] == '\r') s += "\\r";
    else s += v[i];
  }
  return cut ? s + "..." : s;
}
std::string quote(const std::string& v) { return "'" + clip(v) + "'"; }

// Where a value came from.
struct Loc {
  const std::string* file = nullptr;  // points into the loader's long-lived file list
  YAML::Mark mark = YAML::Mark::null_mark();
  std::string key;  // dotted key
};

// "file:line:col: key: " of a Loc, as every message starts.
std::string locText(const Loc& at) {
  std::string s = at.file ? *at.file : std::string("<unknown file>");
  if (!at.mark.is_null()) s += ":" + std::to_string(at.mark.line + 1) + ":" + std::to_string(at.mark.column + 1);
  s += ": ";
  if (!at.key.empty()) s += clip(at.key, 200) + ": ";
  return s;
}

[[noreturn]] void fail(const Loc& at, const std::string& what) { throw ConfigError(locText(at) + clip(what, 2000)); }

// Re-throws a std::invalid_argument from tailsim::validate() / SplitCycleProfile as a
// ConfigError at the value its message names: the longest key in `at` that prefixes the message.
[[noreturn]] void rethrowAt(const std::string& msg, const std::map<std::string, Loc>& at, const Loc& fallback) {
  const std::pair<const std::string, Loc>* best = nullptr;
  for (const auto& kv : at)
    if (msg.compare(0, kv.first.size(), kv.first) == 0 && (!best || kv.first.size() > best->first.size())) best = &kv;
  if (!best) fail(fallback, msg);
  std::string rest = msg.substr(best->first.size());
  while (!rest.empty() && rest.front() == ' ') rest.erase(rest.begin());
  fail(best->second, rest.empty() ? msg : rest);
}

// ---------------------------------------------------------------------------------------------
// Sweeps

struct SweepValue {
  YAML::Node node;          // the sweep element (undefined for a range value)
  bool from_range = false;  // true: `number` holds the value
  double number = 0.0;
  std::string text;         // as written (sweep) or %g (range)
  YAML::Mark mark;          // sweep element, or the range node
};

struct Sweep {
  std::string key;  // dotted key
  std::vector<SweepValue> values;
};

using Picks = std::map<std::string, const SweepValue*>;

std::string describe(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Null: return "nothing (empty value)";
    case YAML::NodeType::Map: return "a map";
    case YAML::NodeType::Sequence: return "a list";
    case YAML::NodeType::Scalar: return quote(n.Scalar());
    default: return "nothing";
  }
}

bool isSweepMap(const YAML::Node& n) { return n.IsMap() && (n["sweep"] || n["range"]); }

// A plain (unquoted) scalar parsed as a finite number; false if it is not one.
bool parseNumber(const YAML::Node& n, double& out) {
  if (!n.IsScalar() || n.Tag() == "!") return false;
  try {
    out = n.as<double>();
  } catch (const YAML::Exception&) {
    return false;
  }
  return true;
}

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

// ---------------------------------------------------------------------------------------------
// Reading values, with sweeps resolved

struct Item {
  YAML::Node node;
  std::string key;  // dotted key
  YAML::Mark mark;  // of the value (of its key when the value is empty)
  YAML::Mark key_mark = YAML::Mark::null_mark();  // of its key in the parent map: where a missing child is reported
};

struct MapView {
  Item self;
  std::vector<std::pair<std::string, Item>> fields;  // file order
  const Item* get(const std::string& k) const {
    for (const auto& f : fields)
      if (f.first == k) return &f.second;
    return nullptr;
  }
};

class Reader {
 public:
  Reader(const std::string* file, const Picks* picks) : file_(file), picks_(picks) {}

  const std::string* file() const { return file_; }
  Item root(const YAML::Node& doc) const { return Item{doc, "", doc.Mark()}; }

  const SweepValue* pick(const Item& it) const {
    if (!picks_) return nullptr;
    auto f = picks_->find(it.key);
    return f == picks_->end() ? nullptr : f->second;
  }
  Loc loc(const Item& it) const {
    const SweepValue* sv = pick(it);
    return Loc{file_, sv ? sv->mark : it.mark, it.key};
  }
  // Where a key missing from `parent` is reported: the parent's own key, else the parent.
  Loc locAt(const Item& parent, const std::string& k) const {
    return Loc{file_, parent.key_mark.is_null() ? parent.mark : parent.key_mark, joinKey(parent.key, k)};
  }
  [[noreturn]] void fail(const Item& it, const std::string& what) const { tailsim::fail(loc(it), what); }

  MapView map(const Item& it, std::initializer_list<const char*> allowed) const {
    return map(it, std::vector<std::string>(allowed.begin(), allowed.end()));
  }
  MapView map(const Item& it, const std::vector<std::string>& allowed) const {
    if (pick(it)) fail(it, "a sweep can replace a single value only, not a section or list");
    if (!it.node.IsMap()) {
      if (it.key.empty()) fail(it, "the file must be a map of key: value, got " + describe(it.node));
      fail(it, "expected a map of key: value, got " + describe(it.node));
    }
    if (!picks_ && isSweepMap(it.node)) fail(it, "sweeps are allowed in experiment files only");
    MapView m{it, {}};
    for (const auto& kv : it.node) {
      if (!kv.first.IsScalar()) tailsim::fail(Loc{file_, kv.first.Mark(), it.key}, "keys must be plain names");
      const std::string k = kv.first.Scalar();
      const Loc keyLoc{file_, kv.first.Mark(), joinKey(it.key, k)};
      if (std::find(allowed.begin(), allowed.end(), k) == allowed.end())
        tailsim::fail(keyLoc, unknownKeyMessage(k, allowed));
      if (m.get(k)) tailsim::fail(keyLoc, "duplicate key");
      const bool empty = kv.second.IsNull() || kv.second.Mark().is_null();
      m.fields.emplace_back(k, Item{kv.second, keyLoc.key, empty ? kv.first.Mark() : kv.second.Mark(), kv.first.Mark()});
    }
    return m;
  }

  const Item& need(const MapView& m, const std::string& k) const {
    const Item* it = m.get(k);
    if (!it) tailsim::fail(locAt(m.self, k), "required key is missing");
    return *it;
  }

  std::vector<Item> list(const Item& it) const {
    if (pick(it)) fail(it, "a sweep can replace a single value only, not a section or list");
    if (!it.node.IsSequence()) fail(it, "expected a list [a, b, ...], got " + describe(it.node));
    std::vector<Item> out;
    for (std::size_t i = 0; i < it.node.size(); ++i) {
      const YAML::Node e = it.node[i];
      out.push_back(Item{e, indexKey(it.key, i), e.Mark().is_null() || e.IsNull() ? it.mark : e.Mark()});
    }
    return out;
  }

  // One value, or one per joint: a list of exactly n values.
  std::vector<Item> perJoint(const Item& it, int n) const {
    if (pick(it) || !it.node.IsSequence()) return std::vector<Item>(static_cast<std::size_t>(n), it);
    std::vector<Item> v = list(it);
    if (static_cast<int>(v.size()) != n)
      fail(it, "has " + std::to_string(v.size()) + " values but the tail has " + std::to_string(n) +
                   " joints: give one value for all joints or one per joint");
    return v;
  }

  double number(const Item& it) const {
    const SweepValue* sv = pick(it);
    if (sv && sv->from_range) return sv->number;
    const YAML::Node& n = sv ? sv->node : it.node;
    scalarOrFail(it, n, "a number");
    if (n.Tag() == "!") fail(it, "expected a number, got the string " + quote(n.Scalar()));
    double v;
    if (!parseNumber(n, v)) fail(it, "expected a number, got " + describe(n));
    if (!std::isfinite(v)) fail(it, "must be a finite number, got " + quote(n.Scalar()));
    return v;
  }
  double positive(const Item& it) const {
    const double v = number(it);
    if (!(v > 0.0)) fail(it, "must be > 0, got " + formatG(v));
    return v;
  }
  double nonNegative(const Item& it) const {
    const double v = number(it);
    if (v < 0.0) fail(it, "must be >= 0, got " + formatG(v));
    return v;
  }
  int integer(const Item& it, long lo, long hi = std::numeric_limits<int>::max()) const {
    const double v = number(it);
    if (v != std::floor(v)) fail(it, "expected an integer, got " + formatG(v));
    if (v < static_cast<double>(lo) || v > static_cast<double>(hi))
      fail(it, hi == std::numeric_limits<int>::max()
                   ? "must be >= " + std::to_string(lo) + ", got " + formatG(v)
                   : "must be in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got " + formatG(v));
    return static_cast<int>(v);
  }
  bool boolean(const Item& it) const {
    const SweepValue* sv = pick(it);
    if (sv && sv->from_range) fail(it, "expected true or false, got a range value");
    const YAML::Node& n = sv ? sv->node : it.node;
    scalarOrFail(it, n, "true or false");
    bool b = false;
    bool ok = n.Tag() != "!";
    if (ok) {
      try {
        b = n.as<bool>();
      } catch (const YAML::Exception&) {
        ok = false;
      }
    }
    if (!ok) fail(it, "expected true or false, got " + describe(n));
    return b;
  }
  std::string string(const Item& it) const {
    const SweepValue* sv = pick(it);
    if (sv && sv->from_range) fail(it, "expected a string, got a range value");
    const YAML::Node& n = sv ? sv->node : it.node;
    scalarOrFail(it, n, "a string");
    return n.Scalar();
  }
  template <class E>
  E choice(const Item& it, const settings::EnumNames<E>& names) const {
    const std::string s = string(it);
    E v{};
    if (!settings::valueOf(names, s, v)) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + std::string(n.name);
      fail(it, "unknown value " + quote(s) + " (allowed: " + list + ")");
    }
    return v;
  }
  std::string choice(const Item& it, std::initializer_list<const char*> allowed) const {
    const std::string s = string(it);
    if (std::find_if(allowed.begin(), allowed.end(), [&](const char* a) { return s == a; }) == allowed.end())
      fail(it, "unknown value " + quote(s) + " (allowed: " + joinList(allowed) + ")");
    return s;
  }
  std::string choice(const Item& it, const std::vector<std::string>& allowed) const {
    const std::string s = string(it);
    if (std::find(allowed.begin(), allowed.end(), s) == allowed.end()) {
      std::string list;
      for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
      fail(it, "unknown value " + quote(s) + " (allowed: " + list + ")");
    }
    return s;
  }

 private:
  void scalarOrFail(const Item& it, const YAML::Node& n, const char* expected) const {
    if (n.IsScalar()) return;
    if (!picks_ && isSweepMap(n)) fail(it, "sweeps are allowed in experiment files only");
    fail(it, std::string("expected ") + expected + ", got " + describe(n));
  }

  const std::string* file_;
  const Picks* picks_;
};

// ---------------------------------------------------------------------------------------------
// Robot files

using Origins = std::map<std::string, Loc>;  // tailsim::validate() field name -> where it was set

// The keys a struct declares (settings/fields.h), YAML keys only (not internal ones).
struct KeyLister {
  std::vector<std::string> keys;
  void add(const settings::Field& f) { keys.push_back(f.key); }
  template <class... T>
  void number(const settings::Field& f, T&&...) { add(f); }
  template <class... T>
  void integer(const settings::Field& f, T&&...) { add(f); }
  template <class... T>
  void boolean(const settings::Field& f, T&&...) { add(f); }
  template <class... T>
  void choice(const settings::Field& f, T&&...) { add(f); }
  template <class... T>
  void text(const settings::Field& f, T&&...) { add(f); }
  template <class... T>
  void numbers(const settings::Field& f, T&&...) { add(f); }
  template <class... T>
  void internal(const settings::Field&, T&&...) {}
};
template <class S>
std::vector<std::string> declaredKeys() {
  KeyLister k;
  const S s{};
  declareFields(k, s);
  return k.keys;
}

// Reads the declared fields of one struct from a YAML map: each present key (every key when
// `all`) is read, type- and range-checked at its file:line:col, and stored (times its scale).
// Where a key was set goes into `origin` under origin_prefix + key (for validate()'s messages).
class YamlFields {
 public:
  YamlFields(const Reader& r, const MapView& m, bool all, bool check_ranges, Origins* origin, std::string origin_prefix)
      : r_(r), m_(m), all_(all), ranges_(check_ranges), origin_(origin), prefix_(std::move(origin_prefix)) {}

  void number(const settings::Field& f, double& x, const settings::Limits& l) {
    const Item* it = get(f);
    if (!it) return;
    const double v = r_.number(*it);
    if (ranges_ && !l.ok(v)) r_.fail(*it, "must " + l.text() + ", got " + formatG(v));
    x = v * f.scale;
  }
  void integer(const settings::Field& f, int& x, const settings::Limits& l, const settings::IntSet& only = {}) {
    const Item* it = get(f);
    if (!it) return;
    const long lo = l.hasLo() ? static_cast<long>(std::ceil(l.lo)) : std::numeric_limits<int>::min();
    const long hi = l.hasHi() ? static_cast<long>(std::floor(l.hi)) : std::numeric_limits<int>::max();
    x = r_.integer(*it, lo, hi);
    if (!only.one_of.empty() && std::find(only.one_of.begin(), only.one_of.end(), x) == only.one_of.end()) {
      std::string list;
      for (int k : only.one_of) list += (list.empty() ? "" : ", ") + std::to_string(k);
      r_.fail(*it, "must be one of " + list + ", got " + std::to_string(x));
    }
    if (x % only.multiple_of)
      r_.fail(*it, (only.multiple_of == 2 ? std::string("must be even") : "must be a multiple of " + std::to_string(only.multiple_of)) +
                       (*only.why ? std::string(" (") + only.why + ")" : "") + ", got " + std::to_string(x));
  }
  void boolean(const settings::Field& f, bool& x) {
    if (const Item* it = get(f)) x = r_.boolean(*it);
  }
  template <class E>
  void choice(const settings::Field& f, E& x, const settings::EnumNames<E>& names) {
    const Item* it = get(f);
    if (!it) return;
    const std::string v = r_.string(*it);
    if (!settings::valueOf(names, v, x)) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + std::string(n.name);
      r_.fail(*it, "unknown value " + quote(v) + " (allowed: " + list + ")");
    }
  }
  void text(const settings::Field& f, std::string& x, const settings::TextRule& rule) {
    const Item* it = get(f);
    if (!it) return;
    const std::string v = r_.string(*it);
    if (rule.non_empty && v.empty()) r_.fail(*it, "must not be empty");
    if (!rule.one_of.empty() && std::find(rule.one_of.begin(), rule.one_of.end(), v) == rule.one_of.end()) {
      std::string list;
      for (const auto& n : rule.one_of) list += (list.empty() ? "" : ", ") + n;
      r_.fail(*it, "unknown value " + quote(v) + " (allowed: " + list + ")");
    }
    x = v;
  }
  template <std::size_t N>
  void numbers(const settings::Field& f, std::array<double, N>& x) {
    const Item* it = get(f);
    if (!it) return;
    const std::vector<Item> v = r_.list(*it);
    if (v.size() != N) r_.fail(*it, "needs " + std::to_string(N) + " values, got " + std::to_string(v.size()));
    for (std::size_t i = 0; i < N; ++i) x[i] = r_.number(v[i]);
  }
  template <class T>
  void internal(const settings::Field&, T&) {}

 private:
  const Item* get(const settings::Field& f) {
    const Item* it = all_ ? &r_.need(m_, f.key) : m_.get(f.key);
    if (it && origin_) (*origin_)[prefix_ + f.key] = r_.loc(*it);
    return it;
  }
  const Reader& r_;
  const MapView& m_;
  bool all_, ranges_;
  Origins* origin_;
  std::string prefix_;
};

// The map at `item` with the keys S declares; reads them into `s`.
template <class S>
MapView readDeclared(const Reader& r, const Item& item, S& s, bool all = false, Origins* origin = nullptr,
                     const std::string& origin_prefix = "", bool check_ranges = true) {
  static const std::vector<std::string> keys = declaredKeys<S>();
  const MapView m = r.map(item, keys);
  YamlFields v(r, m, all, check_ranges, origin, origin_prefix);
  declareFields(v, s);
  return m;
}

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
        tailsim::fail(r.locAt(m.self, k), "required key is missing (or give the size: {mass_kg, size_m: [l, w, h]})");
}

// friction: mu_s and mu_d always; the continuous law's thresholds are checked where that law is
// chosen (requireContinuousThresholds).
const char* const kContinuousKeys[] = {"phidot_s_radps", "phidot_d_radps", "v_s_mps", "v_d_mps"};
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

struct RobotFile {
  std::string file;  // absolute path
  RobotParams base;  // tail empty
  Origins origin;    // quadruped.*, friction.*, gravity_mps2
  std::map<int, std::vector<TailLink>> tails;  // tails.n: its n links (the same link, but for per-joint actuator keys)
  std::map<int, Origins> tail_origin;  // keys "tail link 1 <field>"
};

// ---------------------------------------------------------------------------------------------
// Reading a YAML file within bounds: the file is read whole (at most
// kMaxYamlBytes), then walked once as parser events before any node is built. The walk refuses,
// at the offending line:col, nesting deeper than kMaxYamlDepth, more than kMaxYamlNodes nodes
// counting every alias as the nodes it stands for (an alias "bomb" expands exponentially), an
// alias inside the node it names (a cycle: `a: &a [*a]`), and text that is not valid UTF-8.
// Only then does yaml-cpp build the node tree, which every later step can walk recursively.

struct YamlLimitError {
  YAML::Mark mark;
  std::string what;
};

// Offset of the first byte of `s` that is not part of valid UTF-8, or npos.
std::size_t invalidUtf8At(const std::string& s) {
  const auto* p = reinterpret_cast<const unsigned char*>(s.data());
  const std::size_t n = s.size();
  for (std::size_t i = 0; i < n;) {
    const unsigned c = p[i];
    std::size_t len;
    unsigned min;
    if (c < 0x80) {
      ++i;
      continue;
    } else if ((c & 0xE0) == 0xC0) {
      len = 2, min = 0x80;
    } else if ((c & 0xF0) == 0xE0) {
      len = 3, min = 0x800;
    } else if ((c & 0xF8) == 0xF0) {
      len = 4, min = 0x10000;
    } else {
      return i;
    }
    if (i + len > n) return i;
    unsigned cp = c & (0xFF >> (len + 1));
    for (std::size_t k = 1; k < len; ++k) {
      if ((p[i + k] & 0xC0) != 0x80) return i;
      cp = (cp << 6) | (p[i + k] & 0x3F);
    }
    if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return i;  // overlong, too big, surrogate
    i += len;
  }
  return std::string::npos;
}

class YamlBounds : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& m, YAML::anchor_t a) override { leaf(m, a); }
  void OnScalar(const YAML::Mark& m, const std::string&, YAML::anchor_t a, const std::string& v) override {
    const std::size_t bad = invalidUtf8At(v);
    if (bad != std::string::npos) {
      char b[96];
      std::snprintf(b, sizeof b, "text must be UTF-8; byte 0x%02X at byte %zu of this value is not",
                    static_cast<unsigned char>(v[bad]), bad + 1);
      throw YamlLimitError{m, b};
    }
    leaf(m, a);
  }
  void OnAlias(const YAML::Mark& m, YAML::anchor_t a) override {
    const auto f = anchors_.find(a);
    if (f == anchors_.end()) throw YamlLimitError{m, "an alias inside the node it names (a cycle) is not allowed"};
    add(m, f->second.nodes);
    reach(m, depth() + f->second.height);
  }
  void OnSequenceStart(const YAML::Mark& m, const std::string&, YAML::anchor_t a, YAML::EmitterStyle::value) override {
    open(m, a);
  }
  void OnSequenceEnd() override { close(); }
  void OnMapStart(const YAML::Mark& m, const std::string&, YAML::anchor_t a, YAML::EmitterStyle::value) override {
    open(m, a);
  }
  void OnMapEnd() override { close(); }

 private:
  struct Open {
    YAML::anchor_t anchor;
    long nodes_before;
    int deepest;  // deepest nesting reached inside, counting this node
  };
  struct Anchored {
    long nodes;  // nodes it stands for, itself included
    int height;  // nesting levels it adds (0 for a single value)
  };
  int depth() const { return static_cast<int>(stack_.size()); }
  void reach(const YAML::Mark& m, int d) {
    if (d > kMaxYamlDepth)
      throw YamlLimitError{m, "lists and maps are nested more than " + std::to_string(kMaxYamlDepth) + " levels deep"};
    if (!stack_.empty()) stack_.back().deepest = std::max(stack_.back().deepest, d);
  }
  void add(const YAML::Mark& m, long n) {
    nodes_ += n;
    if (nodes_ > kMaxYamlNodes)
      throw YamlLimitError{m, "more than " + std::to_string(kMaxYamlNodes) +
                                  " values, lists and maps (counting what every alias *name stands for)"};
  }
  void leaf(const YAML::Mark& m, YAML::anchor_t a) {
    add(m, 1);
    if (a) anchors_[a] = Anchored{1, 0};
  }
  void open(const YAML::Mark& m, YAML::anchor_t a) {
    add(m, 1);
    reach(m, depth() + 1);
    stack_.push_back(Open{a, nodes_ - 1, depth() + 1});
  }
  void close() {
    const Open o = stack_.back();
    stack_.pop_back();
    if (o.anchor) anchors_[o.anchor] = Anchored{nodes_ - o.nodes_before, o.deepest - depth()};
    if (!stack_.empty()) stack_.back().deepest = std::max(stack_.back().deepest, o.deepest);
  }

  std::vector<Open> stack_;
  std::map<YAML::anchor_t, Anchored> anchors_;
  long nodes_ = 0;
};

// The whole file, or a ConfigError naming it and the OS error.
std::string readFileBounded(const std::string& file) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw ConfigError(file + ": cannot read the file: " + std::strerror(errno));
  std::string text;
  char buf[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int err = errno;
      ::close(fd);
      throw ConfigError(file + ": cannot read the file: " + std::strerror(err));
    }
    if (n == 0) break;
    if (text.size() + static_cast<std::size_t>(n) > kMaxYamlBytes) {
      ::close(fd);
      throw ConfigError(file + ": the file is larger than " + std::to_string(kMaxYamlBytes >> 20) +
                        " MiB; experiment, suite and robot files are small YAML files");
    }
    text.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fd);
  return text;
}

// `text` as the YAML document of `file` (the name its errors carry), within the same bounds.
YAML::Node parseYamlText(const std::string* file, const std::string& text) {
  if (text.size() > kMaxYamlBytes)
    throw ConfigError(*file + ": the text is larger than " + std::to_string(kMaxYamlBytes >> 20) +
                      " MiB; experiment, suite and robot files are small YAML files");
  // A NUL byte is not text (yaml-cpp reads it as the end of its input, then reports an escape or a
  // number at some other place): refused at its own line and column first.
  if (const std::size_t nul = text.find('\0'); nul != std::string::npos) {
    const std::size_t line_start = text.rfind('\n', nul);
    YAML::Mark at;
    at.pos = static_cast<int>(nul);
    at.line = static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(nul), '\n'));
    at.column = static_cast<int>(line_start == std::string::npos ? nul : nul - line_start - 1);
    fail(Loc{file, at, ""}, "a NUL byte (0x00): the file is not text");
  }
  try {
    {
      std::istringstream in(text);
      YAML::Parser parser(in);
      YamlBounds bounds;
      parser.HandleNextDocument(bounds);
    }
    YAML::Node doc = YAML::Load(text);
    if (doc.IsNull() && doc.Mark().is_null())
      fail(Loc{file, YAML::Mark(), ""}, "the file holds no YAML value (it is empty or only comments): expected a map of "
                                         "key: value (docs/experiment-format.md)");
    return doc;
  } catch (const YamlLimitError& e) {
    fail(Loc{file, e.mark, ""}, e.what);
  } catch (const YAML::ParserException& e) {
    fail(Loc{file, e.mark, ""}, "YAML syntax error: " + e.msg);
  } catch (const YAML::Exception& e) {
    fail(Loc{file, e.mark, ""}, std::string("YAML error: ") + e.what());
  }
}

YAML::Node parseYaml(const std::string* file) { return parseYamlText(file, readFileBounded(*file)); }

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

// ---------------------------------------------------------------------------------------------
// Experiment files

struct Loader {
  std::vector<std::unique_ptr<std::string>> files;  // stable storage for Loc::file
  std::map<std::string, std::unique_ptr<RobotFile>> robots;

  const std::string* keep(const std::string& s) {
    files.push_back(std::make_unique<std::string>(s));
    return files.back().get();
  }
  const RobotFile& robot(const std::string& abs, const Loc& at) {
    auto f = robots.find(abs);
    if (f != robots.end()) return *f->second;
    std::error_code ec;
    if (!fs::is_regular_file(abs, ec)) fail(at, "robot file not found: " + abs);
    return *(robots[abs] = readRobotFile(abs));
  }
};

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

// An angle in degrees with |value| <= max_abs.
double boundedDeg(const Reader& r, const Item& it, double max_abs) {
  const double v = r.number(it);
  if (!(std::abs(v) <= max_abs))
    r.fail(it, "must lie in [-" + formatG(max_abs) + ", " + formatG(max_abs) + "] deg, got " + formatG(v) +
                   " (docs/experiment-format.md \"Limits\")");
  return v;
}

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

std::vector<SplitCycleParams> readTrajectory(const Reader& r, const Item& item, int n) {
  const MapView t = r.map(item, kSplitCycleKeys);
  if (const Item* f = t.get("family")) r.choice(*f, {"split_cycle"});  // spline: readSplineTrajectory
  std::vector<SplitCycleParams> joints(static_cast<std::size_t>(n));
  std::vector<JointLocs> locs(static_cast<std::size_t>(n), JointLocs{r.loc(item), r.loc(item)});

  // w_ss, t0_s: both forms. Defaults 0.25 and 0.
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

  if (const Item* rule = t.get("rule")) {
    r.choice(*rule, {"eq25"});
    for (const char* k : {"theta0_deg", "dtheta_deg", "dT_s", "peak_speed_dps"})
      if (const Item* x = t.get(k)) r.fail(*x, "not allowed with rule: eq25 (Eq. 25 sets it)");
    const Item* dps = t.get("thetadot_max_dps");
    const Item* radps = t.get("thetadot_max_radps");
    if (!dps && !radps) tailsim::fail(r.locAt(t.self, "thetadot_max_dps"), "rule: eq25 needs thetadot_max_dps or thetadot_max_radps");
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
  } else {
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
    if (!dT && !peak) tailsim::fail(r.locAt(t.self, "dT_s"), "give dT_s or peak_speed_dps");
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
  // SplitCycleProfile's own checks (dT > 0, w_ss in (0, 1), finite), at the right value.
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

MujocoSettings readMujoco(const Reader& r, const Item& item) {
  MujocoSettings s;
  if (!r.pick(item) && item.node.IsMap())
    if (const YAML::Node b = item.node["body_height_m"])
      tailsim::fail(Loc{r.file(), b.Mark(), joinKey(item.key, "body_height_m")},
                    "not a key: the MuJoCo body stands at the robot's COM height, quadruped.com_height_m "
                    "(one key for both)");
  const MapView m = readDeclared(r, item, s);
  // MuJoCo's own rules on solref and solimp (element by element).
  if (const Item* x = m.get("solref")) {
    const std::vector<Item> v = r.list(*x);
    // MuJoCo: both > 0 (time constant, damping ratio) or direct (-stiffness, -damping).
    if (s.solref[0] > 0.0 && !(s.solref[1] > 0.0)) r.fail(v[1], "damping ratio must be > 0 when solref[0] > 0");
    if (s.solref[0] < 0.0 && s.solref[1] > 0.0) r.fail(v[1], "must be <= 0 (-damping) when solref[0] < 0");
    if (s.solref[0] == 0.0) r.fail(v[0], "must not be 0");
  }
  if (const Item* x = m.get("solimp")) {
    const std::vector<Item> v = r.list(*x);
    for (int i : {0, 1, 3})
      if (!(s.solimp[i] > 0.0 && s.solimp[i] < 1.0)) r.fail(v[i], "must lie in (0, 1), got " + formatG(s.solimp[i]));
    if (!(s.solimp[2] > 0.0)) r.fail(v[2], "width must be > 0, got " + formatG(s.solimp[2]));
    if (!(s.solimp[4] >= 1.0)) r.fail(v[4], "power must be >= 1, got " + formatG(s.solimp[4]));
  }
  return s;
}

// tail_end_s: when the tail stops (kind: simulate), or < 0 (kind: pose, no time series).
OutputSettings readOutput(const Reader& r, const Item& item, double tail_end_s) {
  OutputSettings o;
  const MapView m = readDeclared(r, item, o);
  // The time series needs at least 2 rows (t = 0 and the end); a longer spacing is a mistake.
  const double t_end = o.runEnd(tail_end_s);
  if (tail_end_s >= 0 && o.sample_dt_s > t_end) {
    const Item* at = m.get("sample_dt_s") ? m.get("sample_dt_s") : m.get("duration_s") ? m.get("duration_s") : &item;
    r.fail(*at, "sample_dt_s = " + formatG(o.sample_dt_s) + " s is longer than the run (" + formatG(t_end) +
                    " s): the time series needs at least 2 rows");
  }
  return o;
}

// run_end_s: simulated seconds of the run (the video shows at most that), or < 0 when unknown.
// Field limits: render_settings.h, the same the renderer checks.
RenderSettings readRender(const Reader& r, const Item& item, double run_end_s) {
  RenderSettings s;
  s.enabled = true;  // the section's presence asks for a video
  if (item.node.IsNull() && !r.pick(item)) return s;  // `render:` with nothing: all defaults
  const MapView m = readDeclared(r, item, s);
  if (const Item* x = m.get("size")) {  // a frame-size preset (render_settings.h)
    if (m.get("width") || m.get("height")) r.fail(*x, "give either size or width/height, not both");
    for (const RenderSizePreset& p : kRenderSizePresets)
      if (s.size == p.name) s.width = p.width, s.height = p.height;
  }
  if (run_end_s >= 0.0) {
    const double span = s.duration_s > 0.0 ? std::min(s.duration_s, run_end_s) : run_end_s;
    const double frames = renderFrameCount(span, s);
    if (!(frames <= kRenderMaxFrames)) {
      const Item* at = m.get("duration_s") ? m.get("duration_s") : m.get("slowmo") ? m.get("slowmo") : m.get("fps") ? m.get("fps") : &item;
      r.fail(*at, "the video would have " + formatG(frames) + " frames (" + formatG(span) + " s simulated x fps " +
                      std::to_string(s.fps) + " x slowmo " + formatG(s.slowmo) + "), more than " +
                      formatG(kRenderMaxFrames) + ": lower fps, slowmo or render.duration_s");
    }
  }
  return s;
}

// Refuses a case whose work estimate (experiments/work_estimate.h) exceeds a limit, at the first
// key among the estimate's culprits that the file sets (else at the section, else the file).
void checkCaseWork(const Reader& r, const MapView& top, const ExperimentCase& c) {
  const WorkExcess x = checkWork(c);
  if (x.what.empty()) return;
  const Item* first_section = nullptr;
  for (const std::string& key : x.keys) {
    const std::size_t dot = key.find('.');
    const Item* sec = top.get(key.substr(0, dot));
    if (!sec) continue;
    if (!first_section) first_section = sec;
    const YAML::Node& secNode = sec->node;
    if (r.pick(*sec) || !secNode.IsMap()) continue;
    const YAML::Node v = secNode[key.substr(dot + 1)];
    if (v) r.fail(Item{v, key, v.Mark().is_null() ? sec->mark : v.Mark()}, x.what);
  }
  if (first_section) r.fail(*first_section, x.what);
  r.fail(r.root(top.self.node), x.what);
}

// effects.friction: continuous needs the law's thresholds (robot file or the experiment's friction:):
// phidot_s/d_radps always, v_s/d_mps when translation is simulated.
void requireContinuousThresholds(const Reader& r, const MapView& top, const ExperimentCase& c, const Origins& origin) {
  if (c.effects.friction != FrictionLaw::kContinuous) return;
  const Item* eff = top.get("effects");
  // effects.friction: continuous is set there. (No Item assignment: a YAML::Node's operator=
  // would rewrite the document.)
  const bool direct = !r.pick(*eff) && eff->node.IsMap() && eff->node["friction"];
  const Item at = direct ? Item{eff->node["friction"], "effects.friction", eff->node["friction"].Mark()} : *eff;
  for (const char* k : kContinuousKeys) {
    const bool translation = k[0] == 'v';
    if (translation && !c.effects.translation) continue;
    if (!origin.count(std::string("friction.") + k))
      r.fail(at, std::string("the continuous law needs friction.") + k + " (in the robot file or the experiment's friction:)" +
                     (translation ? "; or effects: {translation: false}" : ""));
  }
}

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
        if (!kv.first.IsScalar()) tailsim::fail(Loc{r.file(), kv.first.Mark(), j->key}, "keys must be joint names");
        const std::string name = kv.first.Scalar();
        if (name.empty()) tailsim::fail(Loc{r.file(), kv.first.Mark(), j->key}, "a joint name must not be empty");
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

// Pass 2: one case, with the sweeps resolved by `r`.
ExperimentCase readCase(Loader& L, const Reader& r, const YAML::Node& doc, const std::string& source) {
  const Item root = r.root(doc);
  static const std::vector<std::string> kTopKeys = [] {
    std::vector<std::string> k = {"name",         "description", "robot", "kind",  "tail",  "quadruped",
                                  "friction",     "gravity_mps2", "trajectory", "pose", "models"};
    for (const std::string& s : sectionKeys()) k.push_back(s);  // experiment_config.h forEachSection
    return k;
  }();
  const MapView top = r.map(root, kTopKeys);
  ExperimentCase c;
  c.source_file = source;
  const Item& name = r.need(top, "name");
  c.experiment = r.string(name);
  // The name becomes a folder (a suite's OUT/<name>/, render's OUT/<name>/): one safe path component.
  if (const std::string why = experimentNameProblem(c.experiment); !why.empty()) r.fail(name, why);
  if (const Item* d = top.get("description")) r.string(*d);

  // Robot file, then the experiment's overrides; or a robot from its MuJoCo model file.
  const Item& robotItem = r.need(top, "robot");
  const bool modelRobot = !r.pick(robotItem) && robotItem.node.IsMap();
  static const RobotFile kNoRobotFile{};
  const RobotFile* rfp = &kNoRobotFile;
  if (modelRobot) {
    readRobotModel(r, robotItem, source, c);
    for (const char* k : {"quadruped", "friction", "gravity_mps2"})
      if (const Item* x = top.get(k))
        r.fail(*x, "not used with robot: {mjcf: ...}: derived from the model file (robot.mu sets the friction)");
  } else {
    const std::string robotRel = r.string(robotItem);
    if (robotRel.empty()) r.fail(robotItem, "needs a built-in robot name (paper) or the path of a robot file");
    c.robot_file = isBuiltinRobotName(robotRel) ? builtinRobotFile(robotRel, r.loc(robotItem))
                                                : resolveRelative(source, robotRel);
    rfp = &L.robot(c.robot_file, r.loc(robotItem));
  }
  const RobotFile& rf = *rfp;
  c.robot = rf.base;
  Origins origin = rf.origin;

  if (const Item* k = top.get("kind")) c.kind = r.choice(*k, kindNames());

  if (const Item* t = top.get("tail")) {
    const MapView tm = r.map(*t, {"links", "custom", "mount"});
    const Item* links = tm.get("links");
    const Item* custom = tm.get("custom");
    if (const Item* mount = tm.get("mount")) {
      if (!modelRobot) r.fail(*mount, "only used with a robot from its model file (robot: {mjcf: PATH})");
      static const std::vector<std::string> kMountKeys = declaredKeys<TailMount>();
      const MapView mm = readDeclared(r, *mount, c.robot_model->mount);
      for (const std::string& k : kMountKeys)
        if (const Item* x = mm.get(k)) c.robot_model_at["tail.mount." + k] = locText(r.loc(*x));
      if (const Item* b = mm.get("body"))
        if (c.robot_model->mount.body.empty()) r.fail(*b, "must not be empty (absent: the root body)");
    }
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
    if (f == rf.tails.end()) tailsim::fail(r.locAt(root, "tail"), "missing, and robot file " + rf.file + " has no tails.1");
    c.robot.tail = f->second;
    origin.insert(rf.tail_origin.at(1).begin(), rf.tail_origin.at(1).end());
  }
  if (const Item* q = top.get("quadruped")) readQuadruped(r, *q, false, c.robot.quadruped, origin);
  if (const Item* f = top.get("friction")) readFriction(r, *f, false, c.robot.friction, origin);
  if (const Item* g = top.get("gravity_mps2")) {
    c.robot.gravity_mps2 = r.number(*g);
    origin["gravity_mps2"] = r.loc(*g);
  }
  if (modelRobot) {
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
  const int n = c.robot.numLinks();

  const Item* traj = top.get("trajectory");
  const Item* pose = top.get("pose");
  if (c.kind == CaseKind::kSimulate) {
    if (pose) r.fail(*pose, "only used with kind: pose");
    if (!traj) tailsim::fail(r.locAt(root, "trajectory"), "required for kind: simulate");
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
  // The settings sections (experiment_config.h forEachSection): declared fields, read by
  // readDeclared; the few with checks across keys or defaults from elsewhere have their own reader.
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
  if (c.robot_model) {
    if (const Item* x = top.get("render"))
      r.fail(*x, "videos of a robot from its model file are not drawn yet: leave render: out");
    if (c.kind != CaseKind::kSimulate) r.fail(*top.get("kind"), "a robot from its model file runs kind: simulate only");
  }
  requireContinuousThresholds(r, top, c, origin);
  checkCaseWork(r, top, c);
  return c;
}

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

YAML::Node loadBoundedYaml(const std::string& path) { return parseYaml(&path); }

std::string unknownKeyMessage(const std::string& key, const std::vector<std::string>& allowed) {
  // Optimal string alignment distance (an edit: insert, delete, replace, swap two neighbours), case ignored.
  auto distance = [](const std::string& a, const std::string& b) {
    auto lower = [](char ch) { return static_cast<char>(std::tolower(static_cast<unsigned char>(ch))); };
    std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
    for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
    for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i)
      for (std::size_t j = 1; j <= b.size(); ++j) {
        const bool same = lower(a[i - 1]) == lower(b[j - 1]);
        d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (same ? 0 : 1)});
        if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) && lower(a[i - 2]) == lower(b[j - 1]))
          d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    return d[a.size()][b.size()];
  };
  std::string list, best;
  std::size_t best_d = key.size() <= 3 ? 1 : 2;  // the most edits still taken for a misspelling
  bool found = false;
  for (const std::string& a : allowed) {
    list += (list.empty() ? "" : ", ") + a;
    if (key.size() > 200) continue;  // no quadratic work on a pathological key
    const std::size_t dist = distance(key, a);
    if (dist <= best_d && (!found || dist < best_d)) best = a, best_d = dist, found = true;
  }
  return "unknown key" + (found ? "; did you mean '" + best + "'?" : std::string()) + " (allowed here: " + list + ")";
}

namespace {

// An input file's kind from its top-level keys: "optimize", "maneuver", "experiment" (also a
// suite), "robot", or "" (none of these).
std::string inputKindOf(const YAML::Node& doc) {
  if (!doc.IsMap()) return "";
  const YAML::Node kind = doc["kind"];
  if (kind && kind.IsScalar() && (kind.Scalar() == "optimize" || kind.Scalar() == "maneuver")) return kind.Scalar();
  if (doc["experiments"] || doc["robot"]) return "experiment";
  if (doc["tails"] || (doc["quadruped"] && doc["friction"] && !doc["name"])) return "robot";
  return "";
}

std::string inputNote(const std::string& kind, const std::string& path) {
  if (kind == "robot")
    return path + " is a robot file: name it in an experiment's robot: key (docs/experiment-format.md \"Robot file\")";
  const std::string command = kind == "experiment" ? "run" : kind;
  return path + " is " + (kind == "experiment" ? "an experiment" : "a" + std::string(kind == "optimize" ? "n " : " ") + kind) +
         " file: run it with `tailsim " + command + " " + path + " --out DIR`";
}

}  // namespace

void requireInputFor(const YAML::Node& doc, const std::string& path, const std::string& command) {
  const std::string kind = inputKindOf(doc);
  if (kind.empty() || kind == (command == "run" ? "experiment" : command)) return;
  throw ConfigError(inputNote(kind, path));
}

std::string inputFileNote(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return "";
  try {
    const std::string kind = inputKindOf(loadBoundedYaml(path));
    return kind.empty() ? "" : inputNote(kind, path);
  } catch (const std::exception&) {
    return "";
  }
}

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
