// The runner's stages over a Job, one experiment's share of a run (docs/ARCHITECTURE.md "Where to
// start reading"): prepare (run_prepare.cc) finds what is finished and what is left, runJobs
// (run_pool.cc) runs the cases left on the worker threads, each by runAndWrite (run_case.cc), and
// writeSummary (run_summary.cc) writes the folder's summary.json and results.csv.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "experiments/case_journal.h"
#include "experiments/experiment_runner.h"
#include "experiments/model_registry.h"
#include "experiments/result_folder.h"
#include "experiments/results_table.h"
#include "experiments/time_series_h5.h"

namespace tailsim {
namespace runner {
namespace fs = std::filesystem;

// One experiment's share of a run: its folder, what is finished, what is left.
struct Job {
  const Experiment* e = nullptr;
  fs::path root;
  bool render = false;
  std::vector<std::string> keys;  // per case: caseKey()
  std::vector<std::string> dirs;  // per case: caseDirName()
  // Per case: its entry (result.json's content, a line of cases.jsonl) as compact JSON text; empty =
  // not finished. Text, not parsed JSON: a parsed entry takes ~10x its text's memory (10^5 cases
  // held 1.3 GB that way); writeSummary parses them one at a time.
  std::vector<std::string> entries;
  std::set<std::string> extra_names;  // writeSummary: every run's extra figures (results.csv columns)
  std::vector<size_t> todo;       // case indices to run now
  std::string source;             // recordedSource(*e), as found before the folder is written
  std::map<std::string, int> other_builds;  // "version commit" -> finished cases of that build reused
  std::map<std::string, std::set<std::string>> other_build_origins;  // "version commit" -> shard folders (merge)
  int total = 0, resumed = 0;
  std::unique_ptr<CaseJournal> journal;     // DIR/cases.jsonl (cases without a folder)
  std::vector<std::string> other_lines;     // per case: its journal line when not run now (else empty)
  // Cases with time_series_file: hdf5. Each finished case's groups are a file of their own,
  // DIR/time_series.h5.d/<dir>.h5, published (fsync, rename) before its journal line is appended,
  // so it survives any stop; writeSummary joins them with the published DIR/time_series.h5.
  bool any_h5 = false;
  std::unique_ptr<TimeSeriesH5Reader> published;  // DIR/time_series.h5 as found (may be !ok())
  std::vector<char> h5_from;                      // per case: kH5None, kH5Published or kH5Part
};

inline constexpr char kH5None = 0, kH5Published = 1, kH5Part = 2;

inline fs::path h5PartPath(const Job& job, size_t i) { return job.root / kH5Parts / (job.dirs[i] + ".h5"); }

inline bool keepsSeries(const ExperimentCase& c) { return c.output.time_series != TimeSeriesOutput::kNone; }
inline bool inH5(const ExperimentCase& c) { return keepsSeries(c) && c.output.time_series_file == TimeSeriesFile::kHdf5; }

// One experiment's job: its folder claimed and checked, its inputs written, its finished cases
// found (resumed) and the cases left to run (Job::todo).
// in_shard: per case, whether it belongs to this process's shard (--shard K/N; empty = all).
Job prepare(const Experiment& e, const RunOptions& opt, const fs::path& root, const std::vector<char>& in_shard = {});

// Runs one case and writes its folder; result.json last, as the "finished" marker.
std::string runAndWrite(const Job& job, size_t i, int& failed_runs, RunContext& ctx);

// One experiment's rows of a results table, read from its job's entries (after writeSummary: the
// part a table reads, {name, sweep, runs, verdict}, and the extras' names collected).
ResultsCsvInput tableInput(const Job& job);
// Writes DIR/summary.json and DIR/results.csv (from the same entries: every finished case,
// resumed ones included), after cases.jsonl in case order and time_series.h5.
void writeSummary(Job& job);

// All cases of all experiments share one pool of workers (workers share nothing mutable but
// the task counter; each writes only its own case folder and entry).
// suite_root: a suite's folder, which gets the results.csv of all members.
RunStats runJobs(std::vector<Job>& jobs, const RunOptions& opt, const std::string& label,
                 const fs::path& suite_root = {});

}  // namespace runner
}  // namespace tailsim
