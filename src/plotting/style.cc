#include "plotting/style.h"

#include <cctype>
#include <cstdio>
#include <map>
#include <regex>
#include <utility>
#include <vector>

#include "experiments/model_registry.h"
#include "plotting/result_folder.h"

namespace tailsim {

namespace oi = okabe_ito;

// Title and colour are the model's registry entry (experiments/model_registry.cc).
std::string modelColor(const std::string& model) {
  const ModelEntry* m = findModel(model);
  return m ? m->color : oi::kGreen;
}

std::string modelTitle(const std::string& model) {
  const ModelEntry* m = findModel(model);
  return m ? m->title : model;
}

namespace {
// Series colours leave out the two model colours (blue, vermillion): a case curve never looks
// like a model curve.
const char* const kSeries[] = {oi::kOrange, oi::kSkyBlue, oi::kGreen, oi::kPurple, oi::kBlack};
constexpr size_t kNumSeries = sizeof kSeries / sizeof kSeries[0];
}  // namespace

std::string seriesColor(size_t i) { return kSeries[i % kNumSeries]; }
int seriesDash(size_t i) { return 1 + static_cast<int>((i / kNumSeries) % 4); }

std::string categoricalColor(size_t i) {
  static const char* const c[] = {oi::kBlue, oi::kOrange, oi::kGreen, oi::kVermillion, oi::kPurple, oi::kSkyBlue, oi::kBlack};
  return c[i % 7];
}

std::string quantityColor(size_t i) {
  static const char* const q[] = {oi::kOrange, oi::kGreen, oi::kBlack};
  return q[i % 3];
}

std::string divergingPalette() {
  return std::string("set palette defined (-1 '") + oi::kBlue + "', -0.5 '#8CBFE0', 0 '#F7F7F7', 0.5 '#EEAD7E', 1 '" +
         oi::kVermillion + "')\n";
}

std::string sequentialPalette() {
  // white - orange - dark orange: neither model's colour
  return std::string("set palette defined (0 '#FFFDF7', 1 '") + oi::kOrange + "', 2 '#7A4A00')\n";
}

std::string gpText(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '_' || c == '^' || c == '@' || c == '&' || c == '~' || c == '{' || c == '}' || c == '\\') out += '\\';
    out += c;
  }
  return out;
}

namespace {

struct Sym {
  const char* id;
  const char* enhanced;
  const char* plain;
};

// Identifiers of tailsim's names and the paper's symbols; longest first where they share a prefix.
const std::vector<Sym>& symbols() {
  static const std::vector<Sym> s = {
      {"phi_net", "φ_{net}", "φ_net"},     {"phi_ddot", "φ̈", "φ̈"},         {"phidot", "φ̇", "φ̇"},
      {"phi", "φ", "φ"},                   {"dtheta", "Δθ", "Δθ"},           {"theta0", "θ_0", "θ0"},
      {"thetadot", "θ̇", "θ̇"},             {"thetaddot", "θ̈", "θ̈"},           {"theta", "θ", "θ"},
      {"d_Q2B", "d_{Q2B}", "d_Q2B"},       {"w_ss", "w_{ss}", "w_ss"},       {"mu_s", "μ_s", "μ_s"},
      {"mu_d", "μ_d", "μ_d"},              {"M_zT", "M_{z,T}", "M_z,T"},     {"M_zF", "M_{z,F}", "M_z,F"},
      {"MzT", "M_{z,T}", "M_z,T"},         {"MzF", "M_{z,F}", "M_z,F"},      {"I_zz", "I_{zz}", "I_zz"},
      {"L_F", "L_F", "L_F"},               {"dT", "ΔT", "ΔT"},               {"dQ2B", "d_{Q2B}", "d_Q2B"}};
  return s;
}

bool idChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

std::string convert(const std::string& s, bool enhanced) {
  std::string out;
  size_t i = 0;
  while (i < s.size()) {
    if (!idChar(s[i])) {
      out += enhanced ? gpText(std::string(1, s[i])) : std::string(1, s[i]);
      ++i;
      continue;
    }
    size_t j = i;
    while (j < s.size() && idChar(s[j])) ++j;
    const std::string word = s.substr(i, j - i);
    std::string rep;
    for (const Sym& y : symbols())
      if (word == y.id) rep = enhanced ? y.enhanced : y.plain;
    out += rep.empty() ? (enhanced ? gpText(word) : word) : rep;
    i = j;
  }
  return out;
}

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%g", v);
  std::string s = buf;
  return s == "-0" ? "0" : s;
}

}  // namespace

std::string gpSymbols(const std::string& s) { return convert(s, true); }
std::string plainSymbols(const std::string& s) { return convert(s, false); }

KeyDisplay keyDisplay(const std::string& key) {
  std::string leaf = leafKey(key);
  std::string joint;
  if (const size_t b = leaf.find('['); b != std::string::npos) {
    joint = leaf.substr(b + 1, leaf.size() - b - 2);
    leaf = leaf.substr(0, b);
  }
  static const std::map<std::string, KeyDisplay> known = {
      {"theta0_deg", {"θ_0", "θ0", "deg", 1}},
      {"dtheta_deg", {"Δθ", "Δθ", "deg", 1}},
      {"dT_s", {"ΔT", "ΔT", "s", 1}},
      {"w_ss", {"w_{ss}", "w_ss", "", 1}},
      {"d_Q2B_m", {"d_{Q2B}", "d_Q2B", "mm", 1e3}},
      {"links", {"n", "n", "links", 1}},
      {"theta_deg", {"θ", "θ", "deg", 1}},
      {"peak_speed_dps", {"peak joint speed", "peak joint speed", "deg/s", 1}},
      {"thetadot_max_dps", {"θ̇_{max}", "θ̇_max", "deg/s", 1}},
      {"mu_s", {"μ_s", "μ_s", "", 1}},
      {"mu_d", {"μ_d", "μ_d", "", 1}},
      {"t0_s", {"t_0", "t0", "s", 1}},
      {"coupling", {"coupling", "coupling", "", 1}},
      {"friction", {"friction law", "friction law", "", 1}}};
  KeyDisplay d;
  if (auto it = known.find(leaf); it != known.end()) {
    d = it->second;
  } else {
    static const std::vector<std::pair<std::string, std::string>> units = {
        {"_dps2", "deg/s²"}, {"_dps", "deg/s"}, {"_deg", "deg"}, {"_radps2", "rad/s²"},
        {"_radps", "rad/s"}, {"_rad", "rad"},   {"_kgm2", "kg m²"}, {"_kg", "kg"},
        {"_Nm", "N m"},      {"_N", "N"},       {"_mps", "m/s"},  {"_m", "m"}, {"_s", "s"}};
    d.symbol = gpText(leaf);
    d.plain = leaf;
    for (const auto& [suffix, unit] : units)
      if (leaf.size() > suffix.size() && leaf.compare(leaf.size() - suffix.size(), suffix.size(), suffix) == 0) {
        d.plain = leaf.substr(0, leaf.size() - suffix.size());
        d.symbol = gpSymbols(d.plain);
        d.unit = unit;
        break;
      }
  }
  if (!joint.empty()) {
    d.symbol += " (joint " + joint + ")";
    d.plain += " (joint " + joint + ")";
  }
  return d;
}

std::string gpAxisLabel(const std::string& key) {
  const KeyDisplay d = keyDisplay(key);
  if (leafKey(key) == "links") return "tail links n";
  return d.unit.empty() ? d.symbol : d.symbol + " [" + d.unit + "]";
}

namespace {

std::string valueLabel(const std::string& key, const std::string& value, bool with_symbol, bool enhanced) {
  const KeyDisplay d = keyDisplay(key);
  const std::string leaf = leafKey(key);
  const std::string sym = enhanced ? d.symbol : d.plain;
  const auto v = parseNumber(value);
  if (!v) {
    const std::string text = enhanced ? gpText(value) : value;
    if (leaf == "coupling") return text + " coupling";
    if (leaf == "friction") return text;
    return with_symbol ? sym + " = " + text : text;
  }
  const std::string n = num(*v * d.scale);
  if (leaf == "links") return with_symbol ? n + (n == "1" ? " link" : " links") : n;
  std::string shown = n;
  if (d.unit == "deg") shown += "°";
  else if (!d.unit.empty()) shown += " " + d.unit;
  return with_symbol ? sym + " = " + shown : shown;
}

}  // namespace

std::string gpValueLabel(const std::string& key, const std::string& value, bool with_symbol) {
  return valueLabel(key, value, with_symbol, true);
}
std::string plainValueLabel(const std::string& key, const std::string& value) {
  return valueLabel(key, value, true, false);
}

std::string figureName(const std::string& description, const std::string& experiment) {
  if (description.empty()) {
    std::string s = experiment;
    for (char& c : s)
      if (c == '_') c = ' ';
    return s;
  }
  std::string head = description.substr(0, description.find(':'));
  head = std::regex_replace(head, std::regex(R"(Fig\. (\d+)\(([a-z])\))"), "Fig. $1$2");
  return plainSymbols(head);
}

double figureOrder(const std::string& description) {
  std::smatch m;
  if (!std::regex_search(description, m, std::regex(R"(^Fig\. (\d+)(\(([a-z])\))?(.?))"))) return 1e6;
  double order = std::stod(m[1].str());
  if (m[3].matched) order += 0.01 * (m[3].str()[0] - 'a' + 1);
  // "Fig. 7 case with ...": a variant of the figure, after it.
  const std::string next = m[4].str();
  if (!m[3].matched && next != ":" && !next.empty()) order += 0.5;
  if (m[3].matched && next != ":" && !next.empty()) order += 0.5;
  return order;
}

}  // namespace tailsim
