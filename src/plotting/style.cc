#include "plotting/style.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <map>
#include <regex>
#include <utility>
#include <vector>

#include "experiments/model_registry.h"
#include "plotting/gnuplot.h"
#include "plotting/result_folder.h"
#include "common/number_text.h"

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

std::string modelTitle(const std::string& model, bool articulated) {
  const ModelEntry* m = findModel(model);
  if (m && articulated && !m->articulated_title.empty()) return m->articulated_title;
  return modelTitle(model);
}

std::string modelShortTitle(const std::string& model) {
  const std::string t = modelTitle(model);
  const size_t open = t.find(" (");
  return open == std::string::npos ? t : t.substr(0, open);
}

std::string modelGlossary(const std::vector<std::string>& models) {
  std::string out;
  for (const ModelEntry& m : modelRegistry())
    if (!m.glossary.empty() && std::find(models.begin(), models.end(), m.name) != models.end())
      out += (out.empty() ? "" : "; ") + m.glossary;
  return out.empty() ? out : out + ".";
}

std::string gpPanelTitle(const std::string& model, const std::vector<SweepAxis>& axes) {
  std::string title = modelTitle(model);
  // "analytic (stiction)" with the friction law swept: the parenthesis would name one of its values
  if (const size_t open = title.find(" ("); open != std::string::npos && title.back() == ')') {
    const std::string inside = title.substr(open + 2, title.size() - open - 3);
    for (const SweepAxis& a : axes)
      if (std::find(a.values.begin(), a.values.end(), inside) != a.values.end()) title.erase(open);
  }
  std::string out = gpText(title), compared, unused;
  const std::vector<std::string> models = modelNames();
  for (const SweepAxis& a : axes) {
    const std::string section = a.key.substr(0, a.key.find('.'));
    if (section != model && std::find(models.begin(), models.end(), section) != models.end()) {
      unused += (unused.empty() ? "" : ", ") + keyDisplay(a.key).symbol;
      continue;
    }
    if (a.numeric) continue;
    std::vector<std::string> labels;
    for (const std::string& v : a.values) labels.push_back(gpValueLabel(a.key, v, false));
    // "paper coupling", "exact coupling" -> "paper vs exact coupling"
    const size_t sp = labels[0].rfind(' ');
    const std::string tail = sp == std::string::npos ? std::string() : labels[0].substr(sp);
    bool shared = !tail.empty();
    for (const std::string& l : labels)
      shared = shared && l.size() > tail.size() && l.compare(l.size() - tail.size(), tail.size(), tail) == 0;
    std::string vs;
    for (size_t i = 0; i < labels.size(); ++i)
      vs += (i ? " vs " : "") + (shared && i + 1 < labels.size() ? labels[i].substr(0, labels[i].size() - tail.size())
                                                                 : labels[i]);
    compared += (compared.empty() ? "" : " × ") + vs;
  }
  if (!compared.empty()) out += ": " + compared;
  if (!unused.empty()) out += (compared.empty() ? ": " : "; ") + unused + " not used";
  return out;
}

namespace {
// Series colours leave out the two model colours (blue, vermillion): a case curve never looks
// like a model curve. The five Okabe-Ito line colours first, then five darker or greyer ones
// (brown, grey, dark purple, olive, dark teal) apart from them and from each other in hue or
// lightness, so that up to ten curves of a figure never share a colour.
const char* const kSeries[] = {oi::kOrange, oi::kSkyBlue, oi::kGreen, oi::kPurple, oi::kBlack,
                               "#8C510A",   "#999999",    "#5E3C99",  "#9A9A00",  "#01665E"};
constexpr size_t kNumSeries = sizeof kSeries / sizeof kSeries[0];
}  // namespace

std::string seriesColor(size_t i) { return kSeries[i % kNumSeries]; }
int seriesDash(size_t i) { return 1 + static_cast<int>((i / kNumSeries) % 4); }
int seriesPoint(size_t i) {
  // filled circle, square, triangle up, triangle down, diamond; the same open; plus, cross, star
  static const int pt[] = {7, 5, 9, 11, 13, 6, 4, 8, 10, 12, 1, 2, 3};
  return pt[i % (sizeof pt / sizeof pt[0])];
}
size_t numSeriesColors() { return kNumSeries; }

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

std::string sequentialPalette(bool dark_at_low) {
  // white - orange - dark orange: neither model's colour
  if (dark_at_low) return std::string("set palette defined (0 '#7A4A00', 1 '") + oi::kOrange + "', 2 '#FFFDF7')\n";
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
  const std::string s = formatG(v);
  return s == "-0" ? "0" : s;
}

}  // namespace

std::string gpSymbols(const std::string& s) { return convert(s, true); }
std::string plainSymbols(const std::string& s) { return convert(s, false); }

size_t gpTextWidth(const std::string& s) {
  size_t n = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    if (c == '\\' && i + 1 < s.size()) continue;  // the escaped character counts, not the backslash
    if ((c == '_' || c == '^' || c == '{' || c == '}' || c == '@' || c == '&' || c == '~') &&
        (i == 0 || s[i - 1] != '\\'))
      continue;
    if ((c & 0xC0) == 0x80) continue;  // UTF-8 continuation byte
    // U+0300-U+036F (combining marks) are 0xCC 0x80-0xBF and 0xCD 0x80-0xAF
    if (c == 0xCC || (c == 0xCD && i + 1 < s.size() && static_cast<unsigned char>(s[i + 1]) < 0xB0)) continue;
    ++n;
  }
  return n;
}

std::string wrapGpText(const std::string& s, size_t max_chars) {
  if (gpTextWidth(s) <= max_chars) return s;
  // words: split at spaces outside {groups}
  std::vector<std::string> words;
  std::string w;
  int depth = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    const bool escaped = i > 0 && s[i - 1] == '\\';
    if (!escaped && c == '{') ++depth;
    if (!escaped && c == '}' && depth > 0) --depth;
    if (c == ' ' && depth == 0) {
      if (!w.empty()) words.push_back(w);
      w.clear();
    } else {
      w += c;
    }
  }
  if (!w.empty()) words.push_back(w);
  // segments: the words up to and including each " — ", kept on one line where they fit
  std::vector<std::vector<std::string>> segments(1);
  for (const std::string& word : words) {
    segments.back().push_back(word);
    if (word == "—") segments.emplace_back();
  }
  std::vector<std::string> lines(1);
  auto width = [](const std::string& t) { return gpTextWidth(t); };
  for (const auto& seg : segments) {
    std::string joined;
    for (const std::string& word : seg) joined += (joined.empty() ? "" : " ") + word;
    if (joined.empty()) continue;
    const std::string& cur = lines.back();
    if (cur.empty() ? width(joined) <= max_chars : width(cur) + 1 + width(joined) <= max_chars) {
      lines.back() += (cur.empty() ? "" : " ") + joined;
      continue;
    }
    if (!cur.empty() && width(joined) <= max_chars) {  // the whole segment on a line of its own
      lines.push_back(joined);
      continue;
    }
    for (const std::string& word : seg) {  // too long for any line: word by word
      const std::string& l = lines.back();
      if (l.empty() || width(l) + 1 + width(word) <= max_chars) lines.back() += (l.empty() ? "" : " ") + word;
      else lines.push_back(word);
    }
  }
  std::string out;
  for (const std::string& l : lines) out += (out.empty() ? "" : "\n") + l;
  return out;
}

size_t titleChars(int width_px, double font_pt) {
  const double per_char_px = 0.65 * font_pt;  // measured: 9.7 px for 15 pt Sans (pngcairo)
  return static_cast<size_t>(std::max(10.0, 0.88 * width_px / per_char_px));
}

std::string gpTitle(const std::string& enhanced, int width_px, double font_pt) {
  return gpQuote(wrapGpText(enhanced, titleChars(width_px, font_pt)));
}

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
    // A name of words ("foot_shape", "body_height", "mass": every part at least 3 letters) is
    // shown as words, with what it belongs to: "MuJoCo foot shape", "body mass"; a symbol-like
    // name ("l_F", "d_Q2C") stays a symbol.
    bool words = true;
    for (size_t a = 0, b; a <= d.plain.size(); a = b + 1) {
      b = d.plain.find('_', a);
      if (b == std::string::npos) b = d.plain.size();
      words = words && b - a >= 3;
    }
    if (words) {
      std::string w = d.plain;
      std::replace(w.begin(), w.end(), '_', ' ');
      const std::string section = key.substr(0, key.find('.'));
      // A model's own section: its title without the parenthesis ("MuJoCo foot shape").
      static const std::map<std::string, std::string> owner = {{"quadruped", "body "}, {"tail", "tail "}};
      if (key.find('.') != std::string::npos) {
        if (const auto it = owner.find(section); it != owner.end()) w = it->second + w;
        else if (findModel(section)) w = modelShortTitle(section) + " " + w;
      }
      d.plain = w;
      d.symbol = gpText(w);
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

namespace {
// The words of the figure name: the description up to its colon, "Fig. 6(a)" as "Fig. 6a"; the
// experiment's name with spaces for underscores when there is no description.
std::string figureHead(const std::string& description, const std::string& experiment) {
  if (description.empty()) {
    std::string s = experiment;
    for (char& c : s)
      if (c == '_') c = ' ';
    return s;
  }
  const std::string head = description.substr(0, description.find(':'));
  return std::regex_replace(head, std::regex(R"(Fig\. (\d+)\(([a-z])\))"), "Fig. $1$2");
}
}  // namespace

std::string figureName(const std::string& description, const std::string& experiment) {
  return description.empty() ? figureHead(description, experiment) : plainSymbols(figureHead(description, experiment));
}

std::string gpFigureName(const std::string& description, const std::string& experiment) {
  return description.empty() ? gpText(figureHead(description, experiment))
                             : gpSymbols(figureHead(description, experiment));
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
