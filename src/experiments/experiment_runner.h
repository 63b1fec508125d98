// Runs the cases of an experiment on worker threads and writes its result folder
// (docs/ARCHITECTURE.md): one folder per case, written the moment the case finishes, so an
// interrupted sweep run again resumes without redoing or losing finished cases.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "experiments/experiment_config.h"
#include "experiments/settings_json.h"
#include "experiments/experiment_loader.h"
#include "experiments/model_registry.h"
#include "results/time_series.h"

namespace tailsim {

struct RunOptions {
  std::string out_dir;           // result folder (a suite writes out_dir/<experiment>/)
  int threads = 0;               // worker threads; 0 = all cores; at most limits::kMaxThreads
                                 // (checkThreads); fewer start when the system refuses more
  bool progress = true;          // done/total, elapsed and ETA on stderr (redrawn on a TTY, a line
                                 // every 5 s otherwise)
  bool render = true;            // render cases whose experiment has a render section
  bool resume = true;            // skip cases whose result.json has this case's key (caseKey);
                                 // false (--fresh): start from an empty result folder (tailsim's
                                 // entries removed; with only_case just that case recomputed), and
                                 // results of another experiment in out_dir are deleted, not refused
  std::string only_case;         // run just this case ("" = all)
  long max_new_cases = -1;       // stop after this many newly run cases (tests of resuming)
  bool stop_on_sigint = false;   // Ctrl-C, SIGTERM, SIGHUP: start no new case, let running ones finish and save them
                                 // (RunStats::interrupted); a second Ctrl-C terminates the process
  int shard_index = 1;           // --shard K/N: run only the cases assigned to shard K (sharding.h)
  int shard_count = 1;
  bool merge_only = false;       // run nothing: every case must be finished in out_dir (tailsim merge)
  // merge: the shard folder a finished case was taken from (for messages); empty: not a merge.
  std::function<std::string(const std::string& experiment, const std::string& case_name, const std::string& case_dir)>
      case_origin;
  bool allow_other_build = false;  // finished cases of another tailsim build (version/commit) are reused
                                   // with a warning and recorded in summary.json ("other_builds"), not refused
  // Asked by the calling thread at least every 200 ms while cases run: true stops the run as the
  // first Ctrl-C does (no new case; running ones finish and are saved; RunStats::interrupted). The
  // Python module checks Python's signals here (tailsim.run() and Ctrl-C).
  std::function<bool()> should_stop;
};

// Throws std::invalid_argument unless 0 <= threads <= limits::kMaxThreads (common/work_limits.h).
void checkThreads(int threads);

struct RunStats {
  int total = 0;     // cases in the experiment(s)
  int ran = 0;       // cases run now
  int resumed = 0;   // cases found finished and skipped
  int failed = 0;    // model runs with ok == false
  double wall_time_s = 0;
  bool interrupted = false;  // stopped early (a signal, a full disk); resumed + ran cases are saved
  int stop_signal = 0;       // the signal that stopped it: SIGINT, SIGTERM or SIGHUP (0: none)
};

// DIR/.tailsim.lock, flock()ed while the object lives (created with DIR when absent): every command
// writing a result folder (run, merge's staging folder, optimize, maneuver) holds it, so a second one
// into the same folder fails at once ("DIR is in use by another tailsim run (pid N)"); the lock goes
// with the process (also on kill -9), the file stays.
class FolderLock {
 public:
  explicit FolderLock(const std::string& dir);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

// Throws (naming DIR) when DIR holds the results of `tailsim run` (its summary.json, results.csv,
// cases/ or cases.jsonl): `command` (optimize, maneuver) writes a summary.json of its own there.
void refuseRunResults(const std::string& dir, const std::string& command);
// Before `tailsim optimize` or `maneuver` writes into DIR: the files of an earlier tailsim's
// design folder (no manifest; summary.json with "files" and "wall_s") are recorded as tailsim's,
// then each of `outputs` (names relative to DIR, e.g. "plots/history.png") must be tailsim's
// (ownedFile), else std::runtime_error naming it, before any work.
void claimDesignFolder(const std::string& dir, const std::vector<std::string>& outputs);
// Removes those of `outputs` (files relative to dir) that are there, after claimDesignFolder
// has judged them tailsim's; a file a manifest no longer names stays.
void removeDesignOutputs(const std::string& dir, const std::vector<std::string>& outputs);

// Keeps only the models named in `only` in every case (none given: all). Throws ConfigError naming
// `file` for an unknown model name, or when the names select no model of any simulated case (the run
// would write empty results).
void selectModels(std::vector<Experiment>& suite, const std::vector<std::string>& only, const std::string& file);
// Throws ConfigError when no case of the suite is named `name` (empty: nothing to check), listing
// the case names (at most 20).
void requireCase(const std::vector<Experiment>& suite, const std::string& file, const std::string& name);

// All models of one case (no files written). Pose cases evaluate the analytic model only.
// `ctx`: caches shared by the cases of a run (model_registry.h), or nullptr.
std::vector<RunResult> runCase(const ExperimentCase& c, RunContext* ctx = nullptr);

// A run's entry under "runs" in summary.json and result.json ({"ok", "phi_net_deg", ...}).
nlohmann::json summaryJson(const RunSummary& s);

// The folder name of a case under DIR/cases/.
// Unique by construction: a name of [A-Za-z0-9.=,_-] (not starting with . or -, <= 100 chars) is
// its own folder; any other gets a sanitized, shortened form + "~" + 16 hex digits of its SHA-256.
std::string caseDirName(const std::string& case_name);

// The resume key of a case: SHA-256 of caseKeyText (settings_json.h), the canonical resolved case
// (every declared setting, the models run, rendering on or off and its settings, tailsim version
// and git commit). A finished case is reused only when its key matches.
std::string caseKey(const ExperimentCase& c, bool render);

RunStats runExperiment(const Experiment& e, const RunOptions& options);
RunStats runSuite(const std::vector<Experiment>& suite, const RunOptions& options);

}  // namespace tailsim
