// The loader's value reading (yaml_reader.h): messages, locations, and the value helpers Reader uses.
#include "experiments/yaml_reader.h"

#include <cmath>
#include <map>
#include <string>

namespace tailsim {
namespace loader {

std::string joinList(std::initializer_list<const char*> names) {
  std::string s;
  for (const char* n : names) s += (s.empty() ? "" : ", ") + std::string(n);
  return s;
}

std::string joinKey(const std::string& parent, const std::string& k) {
  return parent.empty() ? k : parent + "." + k;
}
std::string indexKey(const std::string& parent, std::size_t i) { return parent + "[" + std::to_string(i) + "]"; }

std::string clip(const std::string& v, std::size_t max) {
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

std::string locText(const Loc& at) {
  std::string s = at.file ? *at.file : std::string("<unknown file>");
  if (!at.mark.is_null()) s += ":" + std::to_string(at.mark.line + 1) + ":" + std::to_string(at.mark.column + 1);
  s += ": ";
  if (!at.key.empty()) s += clip(at.key, 200) + ": ";
  return s;
}

[[noreturn]] void fail(const Loc& at, const std::string& what) { throw ConfigError(locText(at) + clip(what, 2000)); }

[[noreturn]] void rethrowAt(const std::string& msg, const std::map<std::string, Loc>& at, const Loc& fallback) {
  const std::pair<const std::string, Loc>* best = nullptr;
  for (const auto& kv : at)
    if (msg.compare(0, kv.first.size(), kv.first) == 0 && (!best || kv.first.size() > best->first.size())) best = &kv;
  if (!best) fail(fallback, msg);
  std::string rest = msg.substr(best->first.size());
  while (!rest.empty() && rest.front() == ' ') rest.erase(rest.begin());
  fail(best->second, rest.empty() ? msg : rest);
}

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

bool parseNumber(const YAML::Node& n, double& out) {
  if (!n.IsScalar() || n.Tag() == "!") return false;
  try {
    out = n.as<double>();
  } catch (const YAML::Exception&) {
    return false;
  }
  return true;
}

double boundedDeg(const Reader& r, const Item& it, double max_abs) {
  const double v = r.number(it);
  if (!(std::abs(v) <= max_abs))
    r.fail(it, "must lie in [-" + formatG(max_abs) + ", " + formatG(max_abs) + "] deg, got " + formatG(v) +
                   " (docs/experiment-format.md \"Limits\")");
  return v;
}

}  // namespace loader
}  // namespace tailsim
