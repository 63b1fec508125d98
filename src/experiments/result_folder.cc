#include "experiments/result_folder.h"

#include <sys/types.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>
#include <nlohmann/json.hpp>

#include "experiments/case_journal.h"
#include "experiments/experiment_runner.h"
#include "experiments/model_registry.h"
#include "experiments/time_series_h5.h"
#include "common/atomic_file.h"

namespace tailsim {
namespace fs = std::filesystem;
using json = nlohmann::json;

void refuseRunResults(const std::string& dir, const std::string& command) {
  const fs::path root(dir);
  std::error_code ec;
  const std::optional<std::string> text = readResultFile((root / "summary.json").string());
  const json j = text ? json::parse(*text, nullptr, false) : json();
  if ((j.is_object() && j.contains("cases") && j.contains("swept_keys")) || fs::exists(root / "cases", ec) ||
      fs::exists(root / "cases.jsonl", ec) || fs::exists(root / "results.csv", ec))
    throw std::runtime_error(dir + " holds the results of `tailsim run` (summary.json, results.csv, cases): `tailsim " +
                             command + "` would replace them; choose another --out");
}

void claimDesignFolder(const std::string& dir, const std::vector<std::string>& outputs) {
  const fs::path root(dir);
  if (!hasManifest(dir)) {
    const std::optional<std::string> text = readResultFile((root / "summary.json").string());
    const json j = text ? json::parse(*text, nullptr, false) : json();
    if (j.is_object() && j.contains("wall_s") && j.contains("files") && j["files"].is_array()) {
      std::vector<std::string> own = {"summary.json"};  // all judged before the manifest exists
      for (const json& f : j["files"]) {
        if (!f.is_string()) continue;
        const fs::path p(f.get<std::string>());
        if (p.parent_path().empty()) own.push_back(p.string());
        if (p.parent_path() == "plots" && p.extension() == ".png")  // a figure: with its SVG and script
          for (const char* ext : {".png", ".svg", ".gp"}) own.push_back((p.parent_path() / p.stem()).string() + ext);
      }
      std::vector<std::pair<fs::path, std::string>> texts;
      for (const std::string& n : own)
        if (const std::optional<std::string> t = readResultFile((root / n).string())) texts.emplace_back(root / n, *t);
      for (const auto& [p, t] : texts) recordInManifest(p.parent_path().string(), p.filename().string(), t);
    }
  }
  for (const std::string& o : outputs) {
    const fs::path p = root / o;
    checkOwnedFile(p.parent_path().string(), p.filename().string());
  }
}

void removeDesignOutputs(const std::string& dir, const std::vector<std::string>& outputs) {
  claimDesignFolder(dir, outputs);  // every one of them tailsim's (or absent), judged again
  for (const std::string& o : outputs) {
    std::error_code ec;
    fs::remove(fs::path(dir) / o, ec);
  }
}

namespace runner {

// A JSON file of the folder (discarded, not an exception, when absent or not JSON; an error when
// it is not a regular file or too large: readResultFile).
json readJsonFile(const fs::path& p) {
  const std::optional<std::string> text = readResultFile(p.string());
  return text ? json::parse(*text, nullptr, false) : json(json::value_t::discarded);
}

// Whether p is a regular file itself (a symlink to one is not).
bool isRegularFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(fs::symlink_status(p, ec));
}

namespace {

// Which experiment's results a folder holds: {name, source}, from summary.json or, after an
// interrupted first run, from any case's result.json. Empty name: none.
std::pair<std::string, std::string> resultOwner(const fs::path& root) {
  auto owner = [](const json& j, const char* name_key) -> std::pair<std::string, std::string> {
    if (!j.is_object()) return {};
    const auto n = j.find(name_key);
    const auto src = j.find("source");
    if (n == j.end() || !n->is_string()) return {};
    return {n->get<std::string>(), src != j.end() && src->is_string() ? src->get<std::string>() : std::string()};
  };
  std::error_code ec;
  if (fs::exists(root / "summary.json", ec)) {
    const auto o = owner(readJsonFile(root / "summary.json"), "experiment");
    if (!o.first.empty()) return o;
  }
  if (fs::is_directory(root / "cases", ec))
    for (const auto& d : fs::directory_iterator(root / "cases", ec)) {
      const auto o = owner(readJsonFile(d.path() / "result.json"), "experiment");
      if (!o.first.empty()) return o;
    }
  if (const std::optional<std::string> line = firstJournalLine(root / "cases.jsonl")) {  // cases without a folder
    const auto o = owner(json::parse(*line, nullptr, false), "experiment");
    if (!o.first.empty()) return o;
  }
  return {};
}

bool holdsResults(const fs::path& root) {
  std::error_code ec;
  return fs::exists(root / "summary.json", ec) || fs::is_directory(root / "cases", ec) ||
         fs::exists(root / "cases.jsonl", ec);
}

// ---- Which files of a folder are tailsim's ----------------------------------------------------
// The files the runner writes at the top of a result folder (experiment.yaml, robot*.yaml,
// summary.json, results.csv) are named in DIR/.tailsim-manifest (atomic_file.h) before they are
// written. A file is tailsim's when the manifest names it with its current content; in a folder
// without a manifest (written before it existed) when its content is recognisably tailsim's.
// tailsim replaces and deletes only its own.
bool isRobotCopy(const std::string& n) {  // robot-<k>.yaml: a swept robot's copies
  return n.size() > 11 && n.compare(0, 6, "robot-") == 0 && n.compare(n.size() - 5, 5, ".yaml") == 0 &&
         std::all_of(n.begin() + 6, n.end() - 5, [](char ch) { return std::isdigit(static_cast<unsigned char>(ch)); });
}

std::vector<fs::path> memberFolders(const fs::path& root);

bool ownFile(const fs::path& root, const std::string& name) {
  if (name == "cases.jsonl") {  // appended case by case: recognised by content (its first line)
    const std::optional<std::string> line = firstJournalLine(root / name);
    return !line || line->empty() || journalEntry(json::parse(*line, nullptr, false));
  }
  const std::optional<std::string> text = readResultFile((root / name).string());
  if (!text) return true;  // absent: nothing to protect
  if (hasManifest(root.string())) return manifestNames(root.string(), name, *text);
  // No manifest: a folder of an earlier tailsim, recognised by content.
  if (name == "summary.json") {
    const json j = json::parse(*text, nullptr, false);
    return j.is_object() && j.contains("tailsim_version") && j.contains("experiment");
  }
  if (name == "results.csv") return text->compare(0, 21, "experiment,case,model") == 0;
  // experiment.yaml, robot*.yaml: beside tailsim's results (a suite's: in its member folders)
  return !resultOwner(root).first.empty() || !memberFolders(root).empty();
}


}  // namespace

void refuseForeignFiles(const fs::path& root, const std::vector<std::string>& names) {
  for (const std::string& name : names)
    if (!ownFile(root, name))
      throw std::runtime_error((root / name).string() + " was not written by tailsim (or was changed since): not "
                               "replaced; move it out of " + root.string() + " or choose another --out");
}

// Writes DIR/<name> (a top-level file of the folder) when what is there is tailsim's; else refuses.
// The first write into a folder without a manifest records its files recognised as tailsim's first.
void writeOwnFile(const fs::path& root, const std::string& name, const std::string& text) {
  if (!hasManifest(root.string())) {
    std::vector<std::string> names = {"experiment.yaml", "robot.yaml", "summary.json", "results.csv"};
    std::error_code ec;
    for (const auto& f : fs::directory_iterator(root, ec))
      if (isRobotCopy(f.path().filename().string())) names.push_back(f.path().filename().string());
    std::vector<std::pair<std::string, std::string>> own;  // (all judged before the manifest exists)
    for (const std::string& n : names)
      if (const std::optional<std::string> there = readResultFile((root / n).string()); there && ownFile(root, n))
        own.emplace_back(n, *there);
    for (const auto& [n, there] : own) recordInManifest(root.string(), n, there);
  }
  refuseForeignFiles(root, {name});
  recordInManifest(root.string(), name, text);
  writeFileAtomic((root / name).string(), text);
}

namespace {

// What --fresh deletes and keeps as it goes through a folder: removeIf deletes one entry when it
// is tailsim's, else notes it as kept; clearDir does so for the files of a folder, then removes
// the folder when it is empty.
struct FolderClearing {
  std::error_code ec;
  std::vector<std::string> kept;

  void removeIf(const fs::path& p, bool own) {
    if (!fs::exists(fs::symlink_status(p, ec))) return;
    if (own) fs::remove(p, ec);
    else kept.push_back(p.string());
  }
  static bool isTemp(const std::string& n) { return n.find(".tailsim-tmp.") != std::string::npos; }
  // Folders: delete tailsim's files in them, then the folder if it is empty.
  void clearDir(const fs::path& dir, const std::function<bool(const std::string&)>& own) {
    if (!fs::is_directory(fs::symlink_status(dir, ec))) {
      if (fs::exists(fs::symlink_status(dir, ec))) kept.push_back(dir.string());
      return;
    }
    for (const auto& f : fs::directory_iterator(dir, ec)) {
      const std::string n = f.path().filename().string();
      removeIf(f.path(), f.is_regular_file(ec) && !f.is_symlink(ec) && (isTemp(n) || own(n)));
    }
    fs::remove(dir, ec);  // only if now empty
  }
  // Folders of `tailsim plot` (figures, the result page): the files their manifest names unchanged.
  void clearManifested(const fs::path& dir) {
    if (!fs::is_directory(fs::symlink_status(dir, ec))) return;
    std::set<std::string> own = {".tailsim-manifest"};
    for (const auto& f : fs::directory_iterator(dir, ec)) {
      const std::string n = f.path().filename().string();
      try {
        if (const std::optional<std::string> t = readResultFile(f.path().string()); t && manifestNames(dir.string(), n, *t))
          own.insert(n);
      } catch (const std::exception&) {  // not a regular file: not tailsim's
      }
    }
    clearDir(dir, [&](const std::string& n) { return own.count(n) > 0; });
  }
};

// Stage 1: the case folders DIR/cases/<dir> (their result.json and <model>.csv), then DIR/cases;
// returns the case folders that held a result.json.
std::set<std::string> clearCaseFolders(FolderClearing& cl, const fs::path& root) {
  std::error_code& ec = cl.ec;
  std::set<std::string> case_dirs;
  const std::vector<std::string> models = modelNames();
  if (fs::is_directory(fs::symlink_status(root / "cases", ec))) {
    for (const auto& d : fs::directory_iterator(root / "cases", ec)) {
      if (!d.is_directory(ec) || d.is_symlink(ec)) {
        cl.kept.push_back(d.path().string());
        continue;
      }
      if (isRegularFile(d.path() / "result.json")) case_dirs.insert(d.path().filename().string());
      cl.clearDir(d.path(), [&](const std::string& n) {
        if (n == "result.json") return true;
        return std::any_of(models.begin(), models.end(), [&](const std::string& m) { return n == m + ".csv"; });
      });
    }
    fs::remove(root / "cases", ec);
  }
  return case_dirs;
}

// Stage 2: the folders of files named per case or per model: renders/<case dir>.{mp4,png} (of the
// case folders found and those summary.json lists), mjcf/<hash>.xml, time_series.h5.d/*.h5.
void clearSharedFolders(FolderClearing& cl, const fs::path& root, std::set<std::string>& case_dirs) {
  if (const json s = readJsonFile(root / "summary.json"); s.is_object() && s.contains("cases") && s["cases"].is_array())
    for (const json& c : s["cases"])
      if (c.is_object() && c.contains("dir") && c["dir"].is_string()) case_dirs.insert(c["dir"].get<std::string>());
  cl.clearDir(root / "renders", [&](const std::string& n) {
    const size_t dot = n.rfind('.');
    return dot != std::string::npos && (n.substr(dot) == ".mp4" || n.substr(dot) == ".png") &&
           case_dirs.count(n.substr(0, dot));
  });
  cl.clearDir(root / "mjcf", [](const std::string& n) {
    return n.size() == 20 && n.compare(16, 4, ".xml") == 0 &&
           std::all_of(n.begin(), n.begin() + 16, [](char ch) { return std::isxdigit(static_cast<unsigned char>(ch)); });
  });
  cl.clearDir(root / kH5Parts, [](const std::string& n) { return n.size() > 3 && n.compare(n.size() - 3, 3, ".h5") == 0; });
}

// Stage 3: the files of `tailsim plot` and `report` (page/cases, page, plots, report.md,
// figures.html, index.html) their manifest names unchanged, and time_series.h5 when it is whole.
void clearPlotsAndSeries(FolderClearing& cl, const fs::path& root) {
  cl.clearManifested(root / "page" / "cases");
  cl.clearManifested(root / "page");
  cl.clearManifested(root / "plots");
  {
    const fs::path h5 = root / "time_series.h5";
    cl.removeIf(h5, fs::is_regular_file(fs::symlink_status(h5, cl.ec)) && TimeSeriesH5Reader(h5.string()).ok());
  }
  for (const char* name : {"report.md", "figures.html", "index.html"}) {
    bool own = false;
    try {
      const std::optional<std::string> t = readResultFile((root / name).string());
      own = t && manifestNames(root.string(), name, *t);
    } catch (const std::exception&) {  // not a regular file: not tailsim's
    }
    cl.removeIf(root / name, own);
  }
}

// Stage 4: the top-level files the runner writes (ownFile), summary.json last.
void clearTopFiles(FolderClearing& cl, const fs::path& root) {
  std::vector<std::string> top = {"cases.jsonl", "results.csv", "experiment.yaml", "robot.yaml", "robot.xml"};
  for (const auto& f : fs::directory_iterator(root, cl.ec))
    if (isRobotCopy(f.path().filename().string())) top.push_back(f.path().filename().string());
  top.push_back("summary.json");  // last: ownFile of the others may read it
  for (const std::string& name : top) {
    bool own = false;
    try {
      own = ownFile(root, name);
    } catch (const std::exception&) {  // not a regular file: not tailsim's
    }
    cl.removeIf(root / name, own);
  }
}

}  // namespace

// The entries tailsim writes into a result folder (docs/ARCHITECTURE.md) are deleted, and in them
// only what tailsim writes: its top-level files when they are its own (ownFile), a case folder's
// result.json and <model>.csv, mjcf/<hash>.xml, renders/<case dir>.{mp4,png}, time_series.h5(.d),
// its temporary files, and the files of `tailsim plot` / `report` (plots/, page/, report.md,
// figures.html, index.html) that their folder's manifest names unchanged. Anything else stays
// (named on stderr).
void clearResultFolder(const fs::path& root) {
  FolderClearing cl;
  std::set<std::string> case_dirs = clearCaseFolders(cl, root);
  clearSharedFolders(cl, root, case_dirs);
  clearPlotsAndSeries(cl, root);
  clearTopFiles(cl, root);
  compactManifest(root.string());
  for (const std::string& k : cl.kept) std::fprintf(stderr, "note: --fresh kept %s (not written by tailsim)\n", k.c_str());
}

// The experiment file a folder's results come from: e's file, unless e is run from the copy in a
// result folder (DIR/experiment.yaml), whose results name the original; so a folder re-run from
// its own copy reproduces its files (docs/ARCHITECTURE.md "Result folder").
std::string recordedSource(const Experiment& e) {
  const fs::path p(e.source_file);
  if (p.filename() != "experiment.yaml") return e.source_file;
  const auto [name, source] = resultOwner(p.parent_path());
  return name == e.name && !source.empty() ? source : e.source_file;
}


namespace {

// Result folders of experiments inside DIR (a suite's layout: DIR/<experiment>/summary.json).
std::vector<fs::path> memberFolders(const fs::path& root) {
  std::vector<fs::path> out;
  std::error_code ec;
  if (!fs::is_directory(root, ec)) return out;
  for (const auto& d : fs::directory_iterator(root, ec)) {
    const std::string n = d.path().filename().string();
    if (n == "cases" || n == "renders" || n == "plots" || n == "page" || n == "mjcf" || n == kH5Parts) continue;
    if (d.is_directory(ec) && holdsResults(d.path())) out.push_back(d.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

// Refuses (before anything is written) to put experiment e's results into a folder that holds
// another experiment's: the second run would replace summary.json and orphan the first's cases.
// With fresh, the other results are removed first (tailsim's own entries only).
void claimFolder(const Experiment& e, const fs::path& root, bool fresh) {
  const auto [name, source] = resultOwner(root);
  const bool foreign = !name.empty() && (name != e.name || source != recordedSource(e));
  std::vector<fs::path> members = memberFolders(root);  // a suite's results where one experiment goes
  if (!foreign && members.empty()) return;
  if (!fresh) {
    const std::string what = foreign ? "the results of experiment '" + name + "' (" + source + ")"
                                     : "the results of a suite (" + members.front().string() + ", ...)";
    throw std::runtime_error(root.string() + " holds " + what + ", not of '" + e.name + "' (" + recordedSource(e) +
                             "); choose another --out, or add --fresh to delete them");
  }
  if (foreign) clearResultFolder(root);
  for (const fs::path& m : members) {
    clearResultFolder(m);
    std::error_code ec;
    fs::remove(m, ec);  // only if now empty (a lock file of its own stays: never delete a lock)
  }
}

// The suite's top folder must not hold a single experiment's results (they would hide the
// suite's members from `tailsim plot`); with fresh they are removed.
void claimSuiteFolder(const fs::path& root, bool fresh) {
  if (!holdsResults(root)) return;
  if (!fresh) {
    const auto [name, source] = resultOwner(root);
    throw std::runtime_error(root.string() + " holds the results of experiment '" + name + "' (" + source +
                             "), not of a suite; choose another --out, or add --fresh to delete them");
  }
  clearResultFolder(root);
}

// Temporary files of an earlier run that was killed: "<name>.tailsim-tmp.<pid>[.<k>][.<ext>]"
// (atomic writes, renders, figures, HDF5 parts; the infix is tailsim's alone), removed when their
// pid is no longer running (the run lock already excludes a concurrent run; this also spares a
// concurrent `tailsim plot` or `render`). Only in the folders tailsim writes: DIR, DIR/cases/*,
// DIR/renders, DIR/plots, DIR/time_series.h5.d. A file named "<name>.tmp.<pid>..." without the
// infix is a user's: kept, with a note.
int removeStaleTemps(const fs::path& root) {
  // The pid of "<name><infix><pid>[.<k>][.<ext>]" (1-10 digits), or -1 when n is not such a name.
  auto tempPid = [](const std::string& n, const std::string& infix) -> long {
    const size_t at = n.rfind(infix);
    if (at == std::string::npos || at == 0) return -1;
    size_t i = at + infix.size(), digits = 0;
    long pid = 0;
    for (; i < n.size() && std::isdigit(static_cast<unsigned char>(n[i])) && digits <= 10; ++i, ++digits)
      pid = pid * 10 + (n[i] - '0');
    if (digits == 0 || digits > 10) return -1;
    // then at most ".<digits>" and ".<alnum ext>"
    for (int part = 0; part < 2 && i < n.size(); ++part) {
      if (n[i] != '.' || i + 1 >= n.size()) return -1;
      ++i;
      while (i < n.size() && std::isalnum(static_cast<unsigned char>(n[i]))) ++i;
    }
    return i == n.size() ? pid : -1;
  };
  int removed = 0;
  std::error_code ec;
  auto clean = [&](const fs::path& dir) {
    if (!fs::is_directory(dir, ec)) return;
    for (const auto& f : fs::directory_iterator(dir, ec)) {
      const std::string n = f.path().filename().string();
      if (!f.is_regular_file(ec)) continue;
      const long pid = tempPid(n, ".tailsim-tmp.");
      if (pid <= 0 || pid > std::numeric_limits<pid_t>::max()) {
        const long other = tempPid(n, ".tmp.");
        if (processGone(other))
          std::fprintf(stderr, "note: kept %s (named like a temporary file, but not one of tailsim's)\n", f.path().string().c_str());
        continue;
      }
      const bool dead = processGone(pid);
      if ((dead || pid == ::getpid()) && fs::remove(f.path(), ec)) ++removed;
    }
  };
  clean(root);
  clean(root / kH5Parts);
  clean(root / "renders");
  clean(root / "plots");
  if (fs::is_directory(root / "cases", ec))
    for (const auto& d : fs::directory_iterator(root / "cases", ec))
      if (d.is_directory(ec)) clean(d.path());
  return removed;
}

}  // namespace runner
}  // namespace tailsim
