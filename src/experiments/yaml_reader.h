// The experiment loader's reading of YAML values: where a value came from (Loc), the error every
// bad value raises (file:line:col: key: what), a sweep point's picks, and Reader, which reads one
// value (a number, a string, a choice, a map with its allowed keys, a list, one value per joint)
// with the sweeps of the current grid point resolved. YamlFields reads the fields a settings struct
// declares (settings/fields.h). Internal to the loader's files (experiment_loader.cc and the
// readers it calls); the public interface is experiment_loader.h.
#pragma once

#include <yaml-cpp/yaml.h>

#include "experiments/experiment_loader.h"
#include "experiments/yaml_file.h"
#include "common/number_text.h"
#include "settings/fields.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <initializer_list>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace tailsim {
namespace loader {

std::string joinList(std::initializer_list<const char*> names);
std::string joinKey(const std::string& parent, const std::string& k);
std::string indexKey(const std::string& parent, std::size_t i);

// A value quoted in an error message: at most kMaxQuoted bytes (cut at a UTF-8 character
// boundary, then "..."), line breaks shown as \n, so an error is one readable line whatever the
// input (a robot file that is /etc/passwd, a 10 MB value).
constexpr std::size_t kMaxQuoted = 80;
std::string clip(const std::string& v, std::size_t max = kMaxQuoted);
std::string quote(const std::string& v);

// Where a value came from.
struct Loc {
  const std::string* file = nullptr;  // points into the loader's long-lived file list
  YAML::Mark mark = YAML::Mark::null_mark();
  std::string key;  // dotted key
};

// "file:line:col: key: " of a Loc, as every message starts.
std::string locText(const Loc& at);

[[noreturn]] void fail(const Loc& at, const std::string& what);

// Re-throws a std::invalid_argument from tailsim::validate() / SplitCycleProfile as a
// ConfigError at the value its message names: the longest key in `at` that prefixes the message.
[[noreturn]] void rethrowAt(const std::string& msg, const std::map<std::string, Loc>& at, const Loc& fallback);

// One value of a sweep ({sweep: [...]} / {range: [...]}; experiment_loader.h, sweep_grid.cc).
struct SweepValue {
  YAML::Node node;          // the sweep element (undefined for a range value)
  bool from_range = false;  // true: `number` holds the value
  double number = 0.0;
  std::string text;         // as written (sweep) or %g (range)
  YAML::Mark mark;          // sweep element, or the range node
};

// The sweep value each swept dotted key takes at the current grid point.
using Picks = std::map<std::string, const SweepValue*>;

// How a value is named in a message: "a map", "a list", the quoted scalar, ...
std::string describe(const YAML::Node& n);

// A map that is a sweep: {sweep: [...]} or {range: [...]}.
bool isSweepMap(const YAML::Node& n);

// A plain (unquoted) scalar parsed as a finite number; false if it is not one.
bool parseNumber(const YAML::Node& n, double& out);

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
  [[noreturn]] void fail(const Item& it, const std::string& what) const { loader::fail(loc(it), what); }

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
      if (!kv.first.IsScalar()) loader::fail(Loc{file_, kv.first.Mark(), it.key}, "keys must be plain names");
      const std::string k = kv.first.Scalar();
      const Loc keyLoc{file_, kv.first.Mark(), joinKey(it.key, k)};
      if (std::find(allowed.begin(), allowed.end(), k) == allowed.end())
        loader::fail(keyLoc, unknownKeyMessage(k, allowed));
      if (m.get(k)) loader::fail(keyLoc, "duplicate key");
      const bool empty = kv.second.IsNull() || kv.second.Mark().is_null();
      m.fields.emplace_back(k, Item{kv.second, keyLoc.key, empty ? kv.first.Mark() : kv.second.Mark(), kv.first.Mark()});
    }
    return m;
  }

  const Item& need(const MapView& m, const std::string& k) const {
    const Item* it = m.get(k);
    if (!it) loader::fail(locAt(m.self, k), "required key is missing");
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

using Origins = std::map<std::string, Loc>;  // tailsim::validate() field name -> where it was set

// The keys a struct declares (settings/fields.h), YAML keys only (not internal ones).
using settings::declaredKeys;

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
    if (only.except != 0 && x == only.except) r_.fail(*it, "must not be " + std::to_string(x));
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

// An angle in degrees with |value| <= max_abs.
double boundedDeg(const Reader& r, const Item& it, double max_abs);

}  // namespace loader
}  // namespace tailsim
