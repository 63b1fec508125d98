#include "experiments/run_job.h"

#include <sys/stat.h>

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

#include "experiments/folder_inputs.h"
#include "experiments/render_case.h"
#include "experiments/settings_json.h"
#include "common/atomic_file.h"
#include "common/sha256.h"
#include "tailsim_version.h"

namespace tailsim {
namespace fs = std::filesystem;
using json = nlohmann::json;
namespace runner {
namespace {

// Whether case i's part is as tailsim wrote it: named with its content in time_series.h5.d's manifest.
bool h5PartIntact(const Job& job, size_t i) {
  try {
    const std::optional<std::string> text = readResultFile(h5PartPath(job, i).string());
    return text && manifestNames((job.root / kH5Parts).string(), job.dirs[i] + ".h5", *text);
  } catch (const std::exception&) {  // not a regular file
    return false;
  }
}

// A file at case i's part path that tailsim never wrote there (time_series.h5.d's manifest has no line
// for its name: tailsim names a part before it takes its name) is the user's: refused, not replaced. A
// part of tailsim's changed since (damaged) has its line: its case runs again and replaces it.
void refuseUserPart(const Job& job, size_t i) {
  const fs::path p = h5PartPath(job, i);
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(p, ec))) return;
  const std::optional<std::string> m = readResultFile((job.root / kH5Parts / ".tailsim-manifest").string());
  if (m && m->find("  " + job.dirs[i] + ".h5\n") != std::string::npos) return;
  throw std::runtime_error(p.string() + " was not written by tailsim: not replaced; move it out of " +
                           (job.root / kH5Parts).string() + " or choose another --out");
}

// The build an entry says computed it ("" for a label that is missing or not a string).
BuildId entryBuild(const json& j) {
  const auto text = [&](const char* k) {
    const auto it = j.find(k);
    return it != j.end() && it->is_string() ? it->get<std::string>() : std::string();
  };
  return {text("tailsim_version"), text("tailsim_git_commit")};
}

// Whether a run's entry has every field summaryJson writes, of its type: "ok" a boolean;
// "phi_net_deg" a number when ok, null when not; "at_rest" a boolean when ok, null when not;
// "t_stop_s" and "wall_time_s" numbers (null: not a number); "stick_slip_events" and
// "solver_steps" integers; "warnings" an array of strings; "error" (if any) a string; "extra"
// (if any) an object of numbers or nulls.
bool runEntryWhole(const json& run) {
  if (!run.is_object()) return false;
  const auto has = [&](const char* k, auto&& test) {
    const auto it = run.find(k);
    return it != run.end() && test(*it);
  };
  const auto numberOrNull = [](const json& v) { return v.is_number() || v.is_null(); };
  const auto integer = [](const json& v) { return v.is_number_integer(); };
  if (!has("ok", [](const json& v) { return v.is_boolean(); })) return false;
  const bool ok = run["ok"].get<bool>();
  const auto resultField = [ok](const json& v, bool (json::*is)() const noexcept) { return ok ? (v.*is)() : v.is_null(); };
  if (!has("phi_net_deg", [&](const json& v) { return resultField(v, &json::is_number); }) ||
      !has("at_rest", [&](const json& v) { return resultField(v, &json::is_boolean); }) ||
      !has("t_stop_s", numberOrNull) || !has("wall_time_s", numberOrNull) || !has("stick_slip_events", integer) ||
      !has("solver_steps", integer) ||
      !has("warnings", [](const json& v) {
        return v.is_array() && std::all_of(v.begin(), v.end(), [](const json& w) { return w.is_string(); });
      }))
    return false;
  if (run.contains("error") && !run["error"].is_string()) return false;
  if (run.contains("extra") &&
      (!run["extra"].is_object() || !std::all_of(run["extra"].begin(), run["extra"].end(), numberOrNull)))
    return false;
  return true;
}

// Whether a finished case's entry holds a whole result (runEntryWhole) for every model the case
// runs (a journal line edited or torn to `"runs": {}`, or with a field missing or mistyped, is not
// finished: the case runs again).
bool entryComplete(const json& j, const ExperimentCase& c) {
  const auto runs = j.find("runs");
  if (runs == j.end() || !runs->is_object() || runs->empty()) return false;
  for (const auto& [model, run] : runs->items())
    if (!runEntryWhole(run)) return false;
  if (c.kind != CaseKind::kSimulate) return true;
  for (const std::string& m : c.models)
    if (!runs->contains(m)) return false;
  return runs->size() == c.models.size();
}

}  // namespace

namespace {

// Stage 1: the job's cases: those run by this process (--case, --shard), the render switch, each
// case's key and folder name (two cases sharing a folder: refused).
Job planJob(const Experiment& e, const RunOptions& opt, const fs::path& root, const std::vector<char>& in_shard,
            std::vector<size_t>& todo_all) {
  Job job;
  job.e = &e;
  job.root = root;
  job.source = recordedSource(e);
  for (size_t i = 0; i < e.cases.size(); ++i)
    if ((opt.only_case.empty() || e.cases[i].name == opt.only_case) && (in_shard.empty() || in_shard[i]))
      todo_all.push_back(i);
  job.total = static_cast<int>(todo_all.size());
  // Render prerequisites are checked before anything runs.
  job.render = opt.render && !e.cases.empty() && e.cases.front().render.enabled;
  std::map<std::string, size_t> seen;  // folder -> case: unique by construction, checked
  for (size_t i = 0; i < e.cases.size(); ++i) {
    job.keys.push_back(caseKey(e.cases[i], job.render));
    job.dirs.push_back(caseDirName(e.cases[i].name));
    const auto [it, fresh_dir] = seen.emplace(job.dirs.back(), i);
    if (!fresh_dir)
      throw std::runtime_error("experiment " + e.name + ": cases '" + e.cases[it->second].name + "' and '" +
                               e.cases[i].name + "' would share the folder cases/" + job.dirs.back());
  }
  return job;
}

// Stage 2: the folder claimed (--fresh: cleared), a killed run's temporary files removed, its
// subfolders checked, its inputs written and the render prerequisites checked.
void readyFolder(const Job& job, const RunOptions& opt, const std::vector<size_t>& todo_all) {
  const Experiment& e = *job.e;
  const fs::path& root = job.root;
  const std::map<std::string, std::string> inputs = folderInputs(e);
  std::vector<std::string> input_names;
  for (const auto& [name, text] : inputs) input_names.push_back(name);
  refuseForeignFiles(root, input_names);  // before anything is written
  claimFolder(e, root, !opt.resume);
  if (!opt.resume && opt.only_case.empty()) clearResultFolder(root);  // --fresh: no stale case folders
  removeStaleTemps(root);
  const bool any_folder = std::any_of(todo_all.begin(), todo_all.end(), [&](size_t i) { return e.cases[i].output.caseFolder(); });
  // Every folder the run writes into is a real folder of DIR (never a link out of it), checked
  // before any work.
  for (const char* sub : {"cases", kH5Parts, "mjcf", "renders", "plots", "page"}) {
    struct stat st {};
    if (::lstat((root / sub).c_str(), &st) == 0) makeResultDir((root / sub).string());
  }
  for (size_t i : todo_all) {
    struct stat st {};
    if (e.cases[i].output.caseFolder() && ::lstat((root / "cases" / job.dirs[i]).c_str(), &st) == 0)
      makeResultDir((root / "cases" / job.dirs[i]).string());
  }
  fs::create_directories(root);  // (DIR itself, as given to --out, may be a link)
  if (any_folder) makeResultDir((root / "cases").string());
  // The inputs, so that the folder runs again on its own: experiment.yaml naming robot.yaml.
  compactManifest(root.string());
  for (const auto& [name, text] : inputs) writeOwnFile(root, name, text);
  if (job.render) checkRenderPrerequisites(e.cases.front().render, (root / "renders").string());
}

// Stage 3 (cases in HDF5): DIR/time_series.h5 opened only when it is as tailsim wrote it (its
// SHA-256 named in the folder's manifest): libhdf5 crashes on some damaged files, and copies others
// silently. A damaged time_series.h5 is not read: its cases run again (and the file is replaced).
void openPublishedH5(Job& job) {
  const fs::path h5 = job.root / "time_series.h5";
  bool intact = false;
  if (isRegularFile(h5)) {
    const std::optional<std::string> hash = sha256OfFile(h5.string());
    intact = hash && manifestNamesHash(job.root.string(), "time_series.h5", *hash);
    if (!intact)
      std::fprintf(stderr, "note: %s is not as tailsim wrote it (damaged or changed): not read, its cases run again\n",
                   h5.c_str());
  }
  job.published = std::make_unique<TimeSeriesH5Reader>(intact ? h5.string() : std::string());
}

// Where case i's whole group is: its own file (when intact), else the published file, else nowhere.
char findH5(const Job& job, size_t i, const std::vector<std::string>& models, const std::string& key) {
  const fs::path part = h5PartPath(job, i);
  if (h5PartIntact(job, i) && TimeSeriesH5Reader(part.string()).hasCase(job.dirs[i], key, models))
    return kH5Part;
  return job.published->hasCase(job.dirs[i], key, models) ? kH5Published : kH5None;
}

// Stage 4: the journal lines of cases not run now (--case, another shard's), kept when the journal
// is rewritten, and their HDF5 groups.
void keepOtherLines(Job& job, const std::vector<size_t>& todo_all, const std::map<std::string, std::string>& journal) {
  const Experiment& e = *job.e;
  std::vector<char> now(e.cases.size(), 0);
  for (size_t i : todo_all) now[i] = 1;
  job.other_lines.resize(e.cases.size());
  for (size_t i = 0; i < e.cases.size(); ++i)
    if (!now[i])
      if (auto it = journal.find(e.cases[i].name); it != journal.end()) {
        job.other_lines[i] = it->second;
        if (inH5(e.cases[i])) job.h5_from[i] = findH5(job, i, {}, job.keys[i]);  // its group stays too
      }
}

// Stage 5: each case run now is finished (its entry kept, resumed) or to run (Job::todo).
void sortFinished(Job& job, const RunOptions& opt, const std::vector<size_t>& todo_all,
                  std::map<std::string, std::string>& journal) {
  const Experiment& e = *job.e;
  const fs::path& root = job.root;
  for (size_t i : todo_all) {  // finished cases of an earlier, interrupted run
    const ExperimentCase& c = e.cases[i];
    json j;
    if (!opt.resume) {
    } else if (c.output.caseFolder()) {
      j = readJsonFile(root / "cases" / job.dirs[i] / "result.json");
    } else if (auto it = journal.find(c.name); it != journal.end()) {
      j = json::parse(it->second);
      std::string().swap(it->second);
    }
    // A case is reused only when everything its results depend on is unchanged (caseKey), and
    // its entry is whole (a result for every model it runs).
    // An entry with this build's key is this build's only when its own labels say so (an edited
    // label: neither this build's nor, its key not matching, another's: the case runs again).
    bool reuse = j.is_object() && j.value("key", std::string()) == job.keys[i] && j.value("name", std::string()) == c.name &&
                 entryComplete(j, c) && entryBuild(j) == thisBuild();
    if (!reuse && j.is_object() && j.value("name", std::string()) == c.name && entryComplete(j, c)) {
      // A finished case of another build, for the same inputs: refused unless allowed.
      const BuildId theirs = entryBuild(j);
      if (theirs != thisBuild() && j.value("key", std::string()) == sha256Hex(caseKeyText(c, job.render, theirs))) {
        const std::string build = "tailsim " + theirs.version + " (commit " +
                                  (theirs.git_commit.empty() ? "unknown" : theirs.git_commit) + ")";
        ++job.other_builds[build];
        if (opt.case_origin) job.other_build_origins[build].insert(opt.case_origin(e.name, c.name, job.dirs[i]));
        reuse = opt.allow_other_build;
      }
    }
    if (reuse && inH5(c)) {
      std::vector<std::string> models;
      for (const auto& run : j["runs"].items()) models.push_back(run.key());
      job.h5_from[i] = findH5(job, i, models, j.value("key", std::string()));
      reuse = job.h5_from[i] != kH5None;
    }
    if (reuse) {
      job.entries[i] = j.dump();
      ++job.resumed;
      continue;
    }
    job.h5_from[i] = kH5None;
    if (inH5(c)) refuseUserPart(job, i);
    job.todo.push_back(i);
  }
}

// Stage 6: finished cases of another tailsim build: refused, or with --allow-other-build kept
// with a warning.
void reportOtherBuilds(const Job& job, const RunOptions& opt) {
  if (job.other_builds.empty()) return;
  std::string list;
  int n = 0;
  for (const auto& [build, count] : job.other_builds) {
    list += (list.empty() ? "" : ", ") + std::to_string(count) + " by " + build;
    n += count;
  }
  // Where those cases are: DIR, or for a merge the shard folders they come from.
  std::string where = job.root.string();
  if (opt.case_origin) {
    std::set<std::string> shards;
    for (const auto& [build, o] : job.other_build_origins) shards.insert(o.begin(), o.end());
    where.clear();
    for (const std::string& s : shards) where += (where.empty() ? "" : ", ") + s;
    where = "merge: " + where;
  }
  const std::string self = "tailsim " + std::string(kVersion) + " (commit " + (*kGitCommit ? kGitCommit : "unknown") + ")";
  if (!opt.allow_other_build)
    throw std::runtime_error(where + " hold" + (opt.case_origin ? "" : "s") +
                             " finished cases computed by another tailsim build (" + list +
                             "; this is " + self + "): " +
                             (opt.merge_only ? "merge shards of one build, or add --allow-other-build to keep them"
                                             : "add --fresh to recompute them, or --allow-other-build to keep them") +
                             " (recorded in summary.json)");
  std::fprintf(stderr, "warning: %s: %d finished case%s of another tailsim build kept (%s; this is %s)\n",
               where.c_str(), n, n == 1 ? "" : "s", list.c_str(), self.c_str());
}

// Stage 7: DIR/cases.jsonl compacted: one line per finished case, whatever earlier runs appended.
void compactJournal(const Job& job) {
  const Experiment& e = *job.e;
  std::string lines;
  for (size_t i = 0; i < e.cases.size(); ++i)
    if (!job.entries[i].empty() && !e.cases[i].output.caseFolder()) lines += job.entries[i] + "\n";
    else if (!job.other_lines[i].empty()) lines += job.other_lines[i] + "\n";
  writeFileAtomic((job.root / "cases.jsonl").string(), lines);
}

}  // namespace

// in_shard: per case, whether it belongs to this process's shard (--shard K/N; empty = all).
Job prepare(const Experiment& e, const RunOptions& opt, const fs::path& root, const std::vector<char>& in_shard) {
  std::vector<size_t> todo_all;
  Job job = planJob(e, opt, root, in_shard, todo_all);
  readyFolder(job, opt, todo_all);
  job.entries.resize(e.cases.size());
  // Cases without a folder are finished when DIR/cases.jsonl has them; with their time series in
  // HDF5, only when their group is whole with the same key in their own file
  // (DIR/time_series.h5.d/<dir>.h5, written before the journal line) or in the published
  // DIR/time_series.h5 (else they run again).
  const bool any_journal =
      std::any_of(todo_all.begin(), todo_all.end(), [&](size_t i) { return !e.cases[i].output.caseFolder(); });
  job.any_h5 = std::any_of(e.cases.begin(), e.cases.end(), [](const ExperimentCase& c) { return inH5(c); });
  std::map<std::string, std::string> journal = readJournal(root / "cases.jsonl", true);
  const bool had_journal = !journal.empty() || isRegularFile(root / "cases.jsonl");
  job.h5_from.assign(e.cases.size(), kH5None);
  if (job.any_h5) openPublishedH5(job);
  keepOtherLines(job, todo_all, journal);
  sortFinished(job, opt, todo_all, journal);
  reportOtherBuilds(job, opt);
  if (opt.merge_only && !job.todo.empty())
    throw std::runtime_error("merge: case '" + e.cases[job.todo.front()].name + "' of experiment " + e.name +
                             " is finished in none of the shard folders (run its shard, or the shard again)");
  if (had_journal) compactJournal(job);
  if (any_journal || had_journal) job.journal = std::make_unique<CaseJournal>(root / "cases.jsonl");
  return job;
}

}  // namespace runner
}  // namespace tailsim
