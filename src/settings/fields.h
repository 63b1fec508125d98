// Declaring a settings struct's fields once.
//
// Every settings struct has, next to it, a field list
//     template <class V, class S> settings::For<S, T> declareFields(V& v, S& s) { v.number(...); ... }
// naming each field's key (with its unit, as written in YAML and JSON), its doc string, its allowed
// range or enum values and, for an angle given in degrees but kept in radians, the conversion. The
// default is the struct's own member initializer (a visitor reads it from `S{}`). The visitors are:
// the YAML loader (YamlFields in experiments/yaml_reader.h), validation (validateFields below), the JSON
// writer/reader of the resolved case (experiments/settings_json.cc), the JSON Schema and the key
// tables of docs/experiment-format.md (experiments/settings_schema.cc). A new setting is one line in
// its struct's declareFields (plus the member); nothing else lists keys.
//
// A visitor V provides, for S either T or const T:
//   number(const Field&, double&, Limits)           a finite double within Limits
//   integer(const Field&, int&, Limits, IntSet)     an integer within Limits (and in IntSet if given)
//   boolean(const Field&, bool&)
//   choice(const Field&, E&, const EnumNames<E>&)   an enum, written as its name
//   text(const Field&, std::string&, TextRule)      a string (non-empty, or one of a list)
//   numbers(const Field&, std::array<double,N>&)    a fixed-length list of numbers
//   internal(const Field&, T&)                      not a YAML key, but written to the resolved case
#pragma once

#include <array>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace tailsim {
namespace settings {

// The return type of a struct's declareFields: void, for S = T or const T only.
template <class S, class T>
using For = std::enable_if_t<std::is_same<std::remove_const_t<S>, T>::value>;

// One field: its key (unit in the name) and what it means.
struct Field {
  const char* key;
  const char* doc;
  // For a value given in other units than it is kept in: SI value = given value * scale, and the
  // resolved JSON keeps the SI value under si_key (exact: no conversion round trip).
  double scale = 1.0;
  const char* si_key = nullptr;
};

// An allowed interval; an open end excludes its bound.
struct Limits {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false, hi_open = false;

  static Limits any() { return {}; }
  static Limits positive() { return {0.0, std::numeric_limits<double>::infinity(), true, false}; }
  static Limits nonNegative() { return {0.0, std::numeric_limits<double>::infinity(), false, false}; }
  static Limits atLeast(double lo) { return {lo, std::numeric_limits<double>::infinity(), false, false}; }
  static Limits closed(double lo, double hi) { return {lo, hi, false, false}; }
  static Limits open(double lo, double hi) { return {lo, hi, true, true}; }

  bool hasLo() const { return std::isfinite(lo); }
  bool hasHi() const { return std::isfinite(hi); }
  bool ok(double v) const {
    if (!std::isfinite(v)) return false;
    if (hasLo() && (lo_open ? !(v > lo) : !(v >= lo))) return false;
    if (hasHi() && (hi_open ? !(v < hi) : !(v <= hi))) return false;
    return true;
  }
  // "be > 0", "be >= 1", "lie in [0.001, 1000]", "lie in (0, 1)", "be <= 5" (empty: any number).
  std::string text(bool integer = false) const {
    auto g = [](double x) {
      char b[32];
      std::snprintf(b, sizeof b, "%g", x);
      return std::string(b);
    };
    if (hasLo() && hasHi()) {
      if (integer && !lo_open && !hi_open) return "be in " + g(lo) + ".." + g(hi);
      return std::string("lie in ") + (lo_open ? "(" : "[") + g(lo) + ", " + g(hi) + (hi_open ? ")" : "]");
    }
    if (hasLo()) return std::string("be ") + (lo_open ? "> " : ">= ") + g(lo);
    if (hasHi()) return std::string("be ") + (hi_open ? "< " : "<= ") + g(hi);
    return "";
  }
};

// Integers allowed within Limits: only these (empty: all), only multiples of multiple_of, never
// `except` (0: no exception; e.g. a front of 0 or at least 2 points).
struct IntSet {
  std::vector<int> one_of;
  int multiple_of = 1;
  const char* why = "";  // why multiple_of, for messages
  int except = 0;
  IntSet() = default;
  IntSet(std::initializer_list<int> v) : one_of(v) {}
  static IntSet multiple(int k, const char* why) {
    IntSet s;
    s.multiple_of = k;
    s.why = why;
    return s;
  }
  static IntSet not_(int k) {
    IntSet s;
    s.except = k;
    return s;
  }
};

// An enum's values and their names.
template <class E>
struct EnumName {
  E value;
  const char* name;
};
template <class E>
using EnumNames = std::vector<EnumName<E>>;

template <class E>
const char* nameOf(const EnumNames<E>& names, E v) {
  for (const auto& n : names)
    if (n.value == v) return n.name;
  return "?";
}
template <class E>
bool valueOf(const EnumNames<E>& names, const std::string& s, E& out) {
  for (const auto& n : names)
    if (s == n.name) {
      out = n.value;
      return true;
    }
  return false;
}
template <class E>
std::vector<std::string> namesOf(const EnumNames<E>& names) {
  std::vector<std::string> v;
  for (const auto& n : names) v.push_back(n.name);
  return v;
}

// A string field: must it be non-empty, must it be one of a list?
struct TextRule {
  bool non_empty = false;
  std::vector<std::string> one_of;  // empty: any string
};

// Checks every declared field of `s` (a struct built in code, or read from JSON): throws
// std::invalid_argument("<section>.<key>: must ...").
class FieldValidator {
 public:
  explicit FieldValidator(std::string prefix) : prefix_(std::move(prefix)) {}
  void number(const Field& f, double x, Limits l) const {
    if (!l.ok(x)) {
      char b[32];
      std::snprintf(b, sizeof b, "%g", x);
      bad(f, "must " + (l.text().empty() ? std::string("be a finite number") : l.text()) + ", got " + b);
    }
  }
  void integer(const Field& f, int x, Limits l, const IntSet& only = {}) const {
    if (!l.ok(x)) bad(f, "must " + l.text(true) + ", got " + std::to_string(x));
    if (!only.one_of.empty()) {
      bool in = false;
      for (int k : only.one_of) in = in || k == x;
      if (!in) bad(f, "is not one of the allowed values, got " + std::to_string(x));
    }
    if (x % only.multiple_of) bad(f, "must be a multiple of " + std::to_string(only.multiple_of) + ", got " + std::to_string(x));
    if (only.except != 0 && x == only.except) bad(f, "must not be " + std::to_string(x));
  }
  void boolean(const Field&, bool) const {}
  template <class E>
  void choice(const Field& f, E x, const EnumNames<E>& names) const {
    if (std::string(nameOf(names, x)) == "?") bad(f, "is not one of the allowed values");
  }
  void text(const Field& f, const std::string& x, const TextRule& rule) const {
    if (rule.non_empty && x.empty()) bad(f, "must not be empty");
    if (!rule.one_of.empty() && !(x.empty() && !rule.non_empty)) {  // "" = not given, when allowed
      bool in = false;
      for (const auto& k : rule.one_of) in = in || k == x;
      if (!in) bad(f, "is not one of the allowed values, got '" + x + "'");
    }
  }
  template <std::size_t N>
  void numbers(const Field& f, const std::array<double, N>& x) const {
    for (double v : x)
      if (!std::isfinite(v)) bad(f, "must be finite numbers");
  }
  template <class T>
  void internal(const Field&, const T&) const {}

 private:
  [[noreturn]] void bad(const Field& f, const std::string& what) const {
    throw std::invalid_argument(prefix_ + f.key + " " + what);
  }
  std::string prefix_;
};

// The keys a declaration names, in its order (the loader's lists of allowed keys, and the order
// its "allowed here" messages list them in).
struct KeyLister {
  std::vector<std::string> keys;
  void add(const Field& f) { keys.push_back(f.key); }
  template <class T, class... R>
  void number(const Field& f, T&, R&&...) { add(f); }
  template <class T, class... R>
  void perJoint(const Field& f, T&, R&&...) { add(f); }
  template <class... R>
  void knotLists(const Field& f, R&&...) { add(f); }
  template <class T, class... R>
  void choice(const Field& f, T&, R&&...) { add(f); }
  template <class T, class... R>
  void text(const Field& f, T&, R&&...) { add(f); }
  template <class T, class... R>
  void integer(const Field& f, T&, R&&...) { add(f); }
  template <class T>
  void boolean(const Field& f, T&) { add(f); }
  template <class T>
  void numbers(const Field& f, T&) { add(f); }
  template <class T>
  void internal(const Field&, T&) {}  // not a YAML key
  // trajectory_section.h's kinds: perJoint, knotLists above. The design sections' kinds
  // (optimize_section.h):
  template <class... R>
  void interval(const Field& f, R&&...) { add(f); }
  template <class... R>
  void jointLimit(const Field& f, R&&...) { add(f); }
  template <class... R>
  void integerList(const Field& f, R&&...) { add(f); }
  template <class... R>
  void section(const Field& f, R&&...) { add(f); }
  template <class... R>
  void nameOrSection(const Field& f, R&&...) { add(f); }
};

template <class S>
std::vector<std::string> declaredKeys() {
  KeyLister v;
  S s{};
  declareFields(v, s);
  return v.keys;
}

// prefix: what precedes each key in the message, e.g. "quadruped." or "tail link 2 ".
template <class S>
void validateFields(const S& s, const std::string& prefix) {
  FieldValidator v(prefix);
  declareFields(v, s);
}

}  // namespace settings
}  // namespace tailsim
