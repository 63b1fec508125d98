#include "experiments/experiment_runner.h"

#include <algorithm>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "experiments/folder_inputs.h"
#include "experiments/run_job.h"
#include "experiments/sharding.h"
#include "common/work_limits.h"

namespace tailsim {
namespace fs = std::filesystem;

void selectModels(std::vector<Experiment>& suite, const std::vector<std::string>& only, const std::string& file) {
  if (only.empty()) return;
  const std::vector<std::string> known = modelNames();
  std::string known_list;
  for (const std::string& k : known) known_list += (known_list.empty() ? "" : ", ") + k;
  for (const std::string& m : only)
    if (std::find(known.begin(), known.end(), m) == known.end())
      throw ConfigError("unknown model '" + m + "' (models: " + known_list + ")");
  bool any_simulate = false, any_left = false;
  std::set<std::string> had;  // the models the file's simulated cases list, for the message
  for (Experiment& e : suite)
    for (ExperimentCase& c : e.cases) {
      if (c.kind != CaseKind::kSimulate) continue;  // pose cases evaluate the analytic loads whatever is listed
      any_simulate = true;
      std::vector<std::string> keep;
      for (const std::string& m : c.models) {
        had.insert(m);
        if (std::find(only.begin(), only.end(), m) != only.end()) keep.push_back(m);
      }
      any_left = any_left || !keep.empty();
      c.models = keep;
    }
  if (any_simulate && !any_left) {
    std::string sel, lst;
    for (const std::string& m : only) sel += (sel.empty() ? "" : ", ") + m;
    for (const std::string& m : had) lst += (lst.empty() ? "" : ", ") + m;
    throw ConfigError(file + ": the models selected (" + sel + ") are none of those its cases run (" + lst +
                      "): nothing would run");
  }
}

void requireCase(const std::vector<Experiment>& suite, const std::string& file, const std::string& name) {
  if (name.empty()) return;
  std::vector<std::string> names;  // in file order, each once
  std::set<std::string> listed;     // (a set: a 10^5-case sweep must not cost 10^10 comparisons)
  for (const Experiment& e : suite)
    for (const ExperimentCase& c : e.cases) {
      if (c.name == name) return;
      if (listed.insert(c.name).second) names.push_back(c.name);
    }
  std::string list;
  const size_t show = std::min<size_t>(names.size(), 20);
  for (size_t i = 0; i < show; ++i) list += (i ? ", " : "") + names[i];
  if (names.size() > show) list += ", ... (" + std::to_string(names.size() - show) + " more)";
  throw ConfigError("no case named '" + name + "' in " + file + "; cases: " + (list.empty() ? "(none)" : list));
}

namespace {
using RunLock = FolderLock;
using runner::claimFolder;
using runner::claimSuiteFolder;
using runner::Job;
using runner::prepare;
using runner::runJobs;
using runner::writeOwnFile;
}  // namespace

void checkThreads(int threads) {
  if (threads < 0 || threads > limits::kMaxThreads)
    throw std::invalid_argument("threads must lie in 0.." + std::to_string(limits::kMaxThreads) + " (0: all cores), got " +
                                std::to_string(threads));
}

RunStats runExperiment(const Experiment& e, const RunOptions& opt) {
  checkThreads(opt.threads);
  if (opt.resume) claimFolder(e, opt.out_dir, false);  // refuse before the lock file is created
  const RunLock lock(opt.out_dir);
  const std::vector<std::vector<char>> in_shard =
      opt.shard_count > 1 ? shardMembership({e}, {opt.shard_index, opt.shard_count}) : std::vector<std::vector<char>>(1);
  std::vector<Job> jobs;
  jobs.push_back(prepare(e, opt, opt.out_dir, in_shard.front()));
  if (jobs.front().total == 0 && !opt.only_case.empty()) throw std::runtime_error("experiment " + e.name + " has no case named '" + opt.only_case + "'");
  return runJobs(jobs, opt, e.name);
}

RunStats runSuite(const std::vector<Experiment>& suite, const RunOptions& opt) {
  checkThreads(opt.threads);
  if (suite.size() == 1) return runExperiment(suite.front(), opt);
  if (opt.resume) {  // refuse before the lock file is created
    claimSuiteFolder(opt.out_dir, false);
    for (const Experiment& e : suite) claimFolder(e, fs::path(opt.out_dir) / e.name, false);
  }
  const RunLock lock(opt.out_dir);  // one lock for the suite's folder and its members
  claimSuiteFolder(opt.out_dir, !opt.resume);
  const std::vector<std::vector<char>> in_shard = opt.shard_count > 1
                                                      ? shardMembership(suite, {opt.shard_index, opt.shard_count})
                                                      : std::vector<std::vector<char>>(suite.size());
  std::vector<Job> jobs;
  for (size_t k = 0; k < suite.size(); ++k)
    jobs.push_back(prepare(suite[k], opt, fs::path(opt.out_dir) / suite[k].name, in_shard[k]));
  writeOwnFile(opt.out_dir, "experiment.yaml", suiteFolderFile(suite));
  return runJobs(jobs, opt, fs::path(opt.out_dir).filename().string(), opt.out_dir);
}

}  // namespace tailsim
