#include "experiments/run_job.h"

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

#include "common/atomic_file.h"
#include "common/sha256.h"
#include "tailsim_version.h"

namespace tailsim {
namespace fs = std::filesystem;
using json = nlohmann::json;
namespace runner {
namespace {

// The finished entries of a job, in case order, each parsed on its own (Job::entries).
template <class F>
void forEachEntry(const Job& job, const F& f) {
  for (const std::string& text : job.entries)
    if (!text.empty()) f(json::parse(text));
}

}  // namespace

// One experiment's rows of a results table, read from its job's entries (after writeSummary: the
// part a table reads, {name, sweep, runs, verdict}, and the extras' names collected).
ResultsCsvInput tableInput(const Job& job) {
  return {job.e->name, job.e->swept_keys, [&job](const std::function<void(const json&)>& f) { forEachEntry(job, f); },
          &job.extra_names};
}

namespace {

// Removes the part files DIR/time_series.h5.d's manifest names with their current content, then
// the manifest and the folder if nothing else is left in it; anything else (a user's file, a part
// changed since) stays, with a note.
void removeH5Parts(const fs::path& parts) {
  std::error_code ec;
  if (!fs::is_directory(fs::symlink_status(parts, ec))) return;
  std::vector<fs::path> own;
  std::vector<std::string> kept;
  for (const auto& f : fs::directory_iterator(parts, ec)) {
    const std::string n = f.path().filename().string();
    if (n == ".tailsim-manifest") continue;
    std::optional<std::string> hash;
    if (f.is_regular_file(ec) && !f.is_symlink(ec) && n.size() > 3 && n.compare(n.size() - 3, 3, ".h5") == 0)
      hash = sha256OfFile(f.path().string());
    if (hash && manifestNamesHash(parts.string(), n, *hash)) own.push_back(f.path());
    else kept.push_back(f.path().string());
  }
  for (const fs::path& p : own) fs::remove(p, ec);
  if (kept.empty()) {
    fs::remove(parts / ".tailsim-manifest", ec);
    fs::remove(parts, ec);
    return;
  }
  compactManifest(parts.string());
  for (const std::string& k : kept) std::fprintf(stderr, "note: kept %s (not written by tailsim)\n", k.c_str());
}

// DIR/time_series.h5 from the published file's groups and the finished cases' files of their own
// (DIR/time_series.h5.d), which are then removed (removeH5Parts). When the published file already holds exactly
// the finished cases it is left as it is (a resume that ran nothing copies nothing).
void publishTimeSeriesH5(Job& job) {
  std::vector<size_t> from_published, from_parts;
  for (size_t i = 0; i < job.h5_from.size(); ++i) {
    if (job.h5_from[i] == kH5Published) from_published.push_back(i);
    if (job.h5_from[i] == kH5Part) from_parts.push_back(i);
  }
  const fs::path parts = job.root / kH5Parts;
  std::error_code ec;
  if (from_parts.empty() && job.published && job.published->ok() &&
      job.published->caseDirs().size() == from_published.size()) {
    removeH5Parts(parts);
    return;
  }
  {
    // Space for every group copied, reserved before libhdf5 writes (it must never meet a full disk):
    // a group's copy is no larger than the file it comes from (each part also holds a superblock
    // and root group the joined file does not repeat); the joined file's root group adds an index
    // entry per group (kH5LinkBytes, a wide margin) and its own header (kH5FileBytes).
    constexpr long long kH5LinkBytes = 1024, kH5FileBytes = 64 << 10;
    long long bytes = kH5FileBytes + kH5LinkBytes * static_cast<long long>(from_published.size() + from_parts.size());
    if (!from_published.empty()) bytes += static_cast<long long>(fs::file_size(job.published->path(), ec));
    for (size_t i : from_parts) bytes += static_cast<long long>(fs::file_size(h5PartPath(job, i), ec));
    // In a child process: a damaged file (its manifest line matching) crashes libhdf5, not tailsim.
    const std::string what = (from_published.empty() ? std::string() : job.published->path() + " or ") + "a part in " +
                             parts.string();
    runHdf5Isolated(what, [&] {
      TimeSeriesH5Writer out((job.root / "time_series.h5").string(), H5Storage::kDisk, bytes);
      for (size_t i : from_published) out.copyCase(*job.published, job.dirs[i]);
      for (size_t i : from_parts) {
        const TimeSeriesH5Reader part(h5PartPath(job, i).string());
        if (!part.ok()) throw std::runtime_error("cannot read " + h5PartPath(job, i).string());
        out.copyCase(part, job.dirs[i]);
      }
      job.published.reset();  // (closed before the rename replaces it)
      out.publish();
    });
    job.published.reset();  // (the child replaced it)
  }
  const std::optional<std::string> hash = sha256OfFile((job.root / "time_series.h5").string());
  if (!hash) throw std::runtime_error("cannot read back " + (job.root / "time_series.h5").string());
  recordHashInManifest(job.root.string(), "time_series.h5", *hash);
  removeH5Parts(parts);
}

}  // namespace

// Writes DIR/summary.json and DIR/results.csv (from the same entries: every finished case,
// resumed ones included). summary.json is s.dump(1) of {header..., "cases": [entries...]}, written
// from the entries' text one at a time instead of from one JSON tree of all of them (a sweep of
// 10^5 cases held them as parsed JSON: 1.3 GB).
void writeSummary(Job& job) {
  const Experiment& e = *job.e;
  if (job.journal) {  // the finished cases without a folder, in case order (CaseJournal)
    job.journal->close();
    std::string lines;
    for (size_t i = 0; i < job.entries.size(); ++i)
      if (!job.entries[i].empty() && !e.cases[i].output.caseFolder()) lines += job.entries[i] + "\n";
      else if (!job.other_lines[i].empty()) lines += job.other_lines[i] + "\n";
    writeFileAtomic((job.root / "cases.jsonl").string(), lines);
  }
  if (job.any_h5) publishTimeSeriesH5(job);
  json s;
  s["experiment"] = e.name;
  s["tailsim_version"] = kVersion;
  if (*kGitCommit) s["tailsim_git_commit"] = kGitCommit;
  s["description"] = e.description;
  s["source"] = job.source;
  s["kind"] = e.cases.empty() ? "simulate" : name(e.cases.front().kind);
  s["swept_keys"] = e.swept_keys;
  if (!job.other_builds.empty()) s["other_builds"] = job.other_builds;  // --allow-other-build: cases reused from them
  s["cases"] = json::array();
  // "cases" is the first key (sorted), so its empty array is the first match; JSON strings cannot
  // hold an unescaped quote, so no string value matches.
  std::string text = s.dump(1);
  const std::string empty = "\"cases\": []";
  const size_t at = text.find(empty);
  std::string cases = "[";
  bool first = true;
  for (std::string& entry_text : job.entries) {
    if (entry_text.empty()) continue;
    json entry = json::parse(entry_text);  // the one parse of this entry
    entry.erase("experiment");  // said once, in the header
    entry.erase("source");
    if (entry.value("tailsim_version", std::string()) == kVersion &&
        entry.value("tailsim_git_commit", std::string()) == kGitCommit) {  // said once, in the header
      entry.erase("tailsim_version");
      entry.erase("tailsim_git_commit");
    }
    // An element of an array at depth 1 of an indent-1 dump: every line two spaces further in.
    std::string d = entry.dump(1);
    std::string nested;
    nested.reserve(d.size() + d.size() / 8);
    for (char ch : d) {
      nested += ch;
      if (ch == '\n') nested += "  ";
    }
    cases += (first ? "\n  " : ",\n  ") + nested;
    first = false;
    // From here on the entry serves results tables only: keep what they read.
    json row = json::object();
    for (const char* k : {"name", "sweep", "runs", "verdict"})
      if (auto it = entry.find(k); it != entry.end()) row[k] = std::move(*it);
    if (const auto runs = row.find("runs"); runs != row.end() && runs->is_object())
      for (const auto& [model, run] : runs->items())
        if (const auto x = run.find("extra"); x != run.end() && x->is_object())
          for (const auto& [name, v] : x->items()) job.extra_names.insert(name);
    entry_text = row.dump();
  }
  cases += first ? "]" : "\n ]";
  text.replace(at + empty.size() - 2, 2, cases);
  writeOwnFile(job.root, "summary.json", text);
  writeOwnFile(job.root, "results.csv", resultsCsv({tableInput(job)}));
}

}  // namespace runner
}  // namespace tailsim
