// Reading any of tailsim's input files as YAML within bounds (yaml_file.h, experiment_loader.h
// limits), the unknown-key message every reader gives, and telling the kinds of input file apart.
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
namespace loader {

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

}  // namespace loader

namespace fs = std::filesystem;
using loader::parseYaml;

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

}  // namespace tailsim
