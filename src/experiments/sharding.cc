#include "experiments/sharding.h"
#include "common/stop_signals.h"
#include "experiments/time_series_h5.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <set>
#include <csignal>
#include <ctime>
#include <sstream>
#include <stdexcept>
#include <signal.h>
#include <unistd.h>

#include "experiments/experiment_runner.h"
#include "experiments/robot_model_cases.h"
#include "common/atomic_file.h"
#include "common/sha256.h"

#include <map>
#include <nlohmann/json.hpp>

namespace tailsim {

namespace {
bool parsePositive(const std::string& s, int& out) {
  if (s.empty() || s.size() > 9 || !std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return false;
  out = std::atoi(s.c_str());
  return out >= 1;
}
}  // namespace

ShardSpec parseShard(const std::string& text) {
  const auto slash = text.find('/');
  ShardSpec s;
  if (slash == std::string::npos || !parsePositive(text.substr(0, slash), s.index) ||
      !parsePositive(text.substr(slash + 1), s.count) || s.index > s.count || s.count > kMaxShards)
    throw std::invalid_argument("--shard " + text + ": want K/N with 1 <= K <= N <= " + std::to_string(kMaxShards) +
                                " (e.g. 3/8: the third of 8 shards)");
  return s;
}

double expectedCaseCostS(const WorkEstimate& w) {
  double c = 0.0;
  std::vector<std::string> charged;  // cost groups already charged their fixed and per-row cost
  for (const ModelEntry* m : w.models) {
    if (m->cost_group.empty() || std::find(charged.begin(), charged.end(), m->cost_group) == charged.end())
      c += m->cost_fixed_s + m->cost_per_row_s * w.rows;
    if (!m->cost_group.empty()) charged.push_back(m->cost_group);
  }
  for (const WorkEstimate::ModelSteps& m : w.model_steps) c += m.model->cost_per_step_s * m.steps.steps;
  c += 5e-3 * w.render_frames;
  return c;
}

std::vector<int> assignShards(const std::vector<double>& cost, int n_shards) {
  if (n_shards < 1) throw std::invalid_argument("assignShards: n_shards must be >= 1");
  std::vector<size_t> order(cost.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return cost[a] > cost[b]; });
  std::vector<double> load(static_cast<size_t>(n_shards), 0.0);
  std::vector<int> shard(cost.size(), 0);
  for (size_t i : order) {
    const int s = static_cast<int>(std::min_element(load.begin(), load.end()) - load.begin());  // first minimum
    shard[i] = s;
    load[static_cast<size_t>(s)] += std::max(0.0, cost[i]);
  }
  return shard;
}

std::vector<std::vector<char>> shardMembership(const std::vector<Experiment>& suite, ShardSpec shard) {
  std::vector<double> cost;
  for (const Experiment& e : suite)
    for (const ExperimentCase& c : e.cases) cost.push_back(expectedCaseCostS(estimateWork(c)));
  const std::vector<int> a = assignShards(cost, shard.count);
  std::vector<std::vector<char>> in(suite.size());
  size_t k = 0;
  for (size_t i = 0; i < suite.size(); ++i)
    for (size_t j = 0; j < suite[i].cases.size(); ++j) in[i].push_back(a[k++] == shard.index - 1);
  return in;
}

namespace {
namespace fs = std::filesystem;

std::string readAll(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

// Files a run writes about the whole folder (rebuilt by the merge) or that belong to no case.
bool rebuiltOrTransient(const fs::path& rel) {
  const std::string n = rel.filename().string();
  if (n == ".tailsim.lock" || n == ".tailsim-manifest" || n == "summary.json" || n == "results.csv" || n == "report.md" ||
      n == "figures.html")
    return true;
  if (n.find(".tmp.") != std::string::npos || n.find(".tailsim-tmp.") != std::string::npos) return true;  // an interrupted writer's temporary
  for (const auto& part : rel)
    if (part == "plots") return true;
  return false;
}

// A finished case's entry (result.json, a cases.jsonl line) as compared between shards: its JSON
// without the measured wall times (two runs of one case differ in nothing else).
std::string comparable(const std::string& text) {
  nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (!j.is_object()) return text;
  if (auto runs = j.find("runs"); runs != j.end() && runs->is_object())
    for (auto& [model, run] : runs->items())
      if (run.is_object()) run.erase("wall_time_s");
  return j.dump();
}

// The same case finished in two shards must have the same result (identical duplicates are fine).
void requireSameResult(const std::string& a_text, const std::string& b_text, const std::string& case_name,
                       const std::string& a_dir, const std::string& b_dir) {
  if (comparable(a_text) != comparable(b_text))
    throw std::runtime_error("merge: case '" + case_name + "' has different results in " + a_dir + " and " + b_dir +
                             " (not shards of one run; merge one of them)");
}

// Per-case outputs (cases/<dir>/..., renders/<dir>.*): the first shard that has the case wins.
bool perCase(const fs::path& rel) {
  for (const auto& part : rel)
    if (part == "cases" || part == "renders") return true;
  return false;
}

// The folder a case's files live in (for "first shard wins" of a whole case): <...>/cases/<dir>.
fs::path caseFolderOf(const fs::path& rel) {
  fs::path out;
  bool next = false;
  for (const auto& part : rel) {
    out /= part;
    if (next) return out;
    next = part == "cases";
  }
  return rel;  // renders/<file>: the file itself
}
}  // namespace

namespace {
// A shard's HDF5 file (time_series.h5 or a part) is merged only when its SHA-256 is named in its
// folder's manifest: else std::runtime_error naming the file and the shard.
void requireIntactH5(const fs::path& file, const std::string& shard) {
  const std::optional<std::string> hash = sha256OfFile(file.string());
  if (!hash || !manifestNamesHash(file.parent_path().string(), file.filename().string(), *hash))
    throw std::runtime_error("merge: " + file.string() + " of shard " + shard +
                             " is not as tailsim wrote it (damaged or changed): not merged; run that shard again "
                             "(tailsim run ... --shard K/N --out " + shard + ")");
}
}  // namespace

namespace {
// The file that marks a folder as a merge's staging folder, named in its manifest with this content.
const char* const kStageMarker = ".tailsim-merge-stage";
const char* const kStageMarkerText = "tailsim merge staging folder\n";

struct MergeStopped {
  int sig;
};

// True when DIR holds nothing but what a merge writes first into its new staging folder (its
// manifest, the marker or the marker's temporary): a merge killed between creating the folder and
// marking it left that, and removing it loses nothing.
bool onlyFirstStageFiles(const fs::path& dir) {
  std::error_code ec;
  const std::string marker_tmp = std::string(kStageMarker) + ".tailsim-tmp.";
  for (auto it = fs::directory_iterator(dir, ec); !ec && it != fs::directory_iterator(); it.increment(ec)) {
    const std::string n = it->path().filename().string();
    std::error_code e2;
    if (!it->is_regular_file(e2) || it->is_symlink(e2) || it->file_size(e2) > 256) return false;
    if (n != ".tailsim-manifest" && n != kStageMarker && n.compare(0, marker_tmp.size(), marker_tmp) != 0) return false;
  }
  return !ec;
}

// Removes OUT.merge.tmp.<pid> folders beside OUT whose pid is no running process and that the
// marker in their manifest shows to be a merge's staging folder (or that hold only what a merge
// writes first, see onlyFirstStageFiles); anything else is left alone.
void removeStaleStages(const fs::path& out) {
  std::error_code ec;
  const std::string prefix = out.filename().string() + ".merge.tmp.";
  for (auto it = fs::directory_iterator(out.parent_path(), ec); !ec && it != fs::directory_iterator(); it.increment(ec)) {
    const std::string n = it->path().filename().string();
    if (n.size() <= prefix.size() || n.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string digits = n.substr(prefix.size());
    if (digits.size() > 9 || !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
      continue;
    const pid_t pid = static_cast<pid_t>(std::atol(digits.c_str()));
    if (pid <= 0 || pid == ::getpid() || !processGone(pid)) continue;
    std::error_code e2;
    if (it->is_symlink(e2) || !it->is_directory(e2)) continue;
    if (!manifestNames(it->path().string(), kStageMarker, kStageMarkerText) && !onlyFirstStageFiles(it->path())) continue;
    fs::remove_all(it->path(), e2);
  }
}
// Throws MergeStopped when SIGINT, SIGTERM or SIGHUP arrived.
void checkStop(StopSignals& signals) {
  if (const int sig = signals.pending()) throw MergeStopped{sig};
}

// Stage 1: every shard is a result folder outside `out`, and every shard comes from the same inputs:
// their experiment.yaml copies are byte-identical.
void checkShards(const std::vector<std::string>& shard_dirs, const fs::path& out, const std::string& out_dir) {
  std::error_code ec;
  std::string exp_text;
  for (const std::string& d : shard_dirs) {
    const fs::path e = fs::path(d) / "experiment.yaml";
    if (!fs::is_regular_file(e, ec))
      throw std::runtime_error("merge: " + d + " is not a tailsim result folder (no experiment.yaml)");
    const fs::path shard = fs::absolute(d).lexically_normal();
    if (shard == out) throw std::runtime_error("merge: --out must not be a shard folder");
    // A folder inside a shard would be merged as part of that shard (symbolic links resolved).
    std::error_code ec_out, ec_shard;
    const fs::path real_out = fs::weakly_canonical(out, ec_out), real_shard = fs::weakly_canonical(shard, ec_shard);
    const fs::path in_shard = real_out.lexically_relative(real_shard);
    if (!ec_out && !ec_shard && !in_shard.empty() && *in_shard.begin() != ".." && in_shard != ".")
      throw std::runtime_error("merge: the merged folder " + out_dir + " is inside the shard " + d +
                               ": choose a folder outside the shards");
    const std::string t = readAll(e);
    if (exp_text.empty()) exp_text = t;
    else if (t != exp_text)
      throw std::runtime_error("merge: " + d + "/experiment.yaml differs from " + shard_dirs.front() +
                               "/experiment.yaml: the shards are not of the same run");
  }
}

// What the copy of the shards has gathered so far.
struct MergeState {
  fs::path stage;                                                            // the staging folder
  std::vector<fs::path> taken_cases;                                         // case folders of the earlier shards
  std::map<fs::path, std::string> taken_by;                                  // case folder -> the shard folder it was taken from
  std::map<std::string, std::pair<std::string, std::string>> journal_lines;  // name -> {line, shard}
  std::set<fs::path> merged_h5;                                              // the staging folder's time_series.h5 files
};

// A cases.jsonl (finished cases without a folder): every shard's lines, appended; the same case in
// two shards must have the same result.
void mergeJournal(const fs::path& file, const fs::path& rel, const std::string& d, MergeState& ms) {
  const fs::path dst = ms.stage / rel;
  const std::string text = readResultFile(file.string()).value_or(std::string());
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    if (!j.is_object() || !j.contains("name") || !j["name"].is_string()) continue;
    const std::string name = (rel.parent_path() / j["name"].get<std::string>()).string();
    const auto [at, first] = ms.journal_lines.emplace(name, std::make_pair(line, d));
    if (!first) requireSameResult(at->second.first, line, j["name"].get<std::string>(), at->second.second, d);
  }
  fs::create_directories(dst.parent_path());
  std::ofstream(dst, std::ios::binary | std::ios::app) << text;
}

// One file of shard d (rel: its path in the shard) into the staging folder: journals appended,
// time_series.h5 merged group by group, a case's files from the first shard that has the case, the
// inputs checked equal to the earlier shards'. this_shard_cases collects the shard's case folders.
void mergeShardFile(const fs::path& file, const fs::path& rel, const std::string& d, MergeState& ms,
                    std::vector<fs::path>& this_shard_cases, MergeStats& st) {
  std::error_code ec;
  const fs::path dst = ms.stage / rel;
  if (rel.filename() == "cases.jsonl") return mergeJournal(file, rel, d, ms);
  if (rel.filename() == "time_series.h5") {  // every shard's case groups (the first shard's win)
    requireIntactH5(file, d);  // libhdf5 crashes on some damaged files
    fs::create_directories(dst.parent_path());
    runHdf5Isolated(file.string() + " (shard " + d + ")", [&] { mergeTimeSeriesH5(file.string(), dst.string()); });
    ms.merged_h5.insert(dst);
    return;
  }
  if (rel.parent_path().filename() == "time_series.h5.d" && rel.extension() == ".h5") {  // an unjoined case
    requireIntactH5(file, d);
    fs::create_directories(dst.parent_path());
    fs::copy_file(file, dst, fs::copy_options::overwrite_existing);
    recordInManifest(dst.parent_path().string(), rel.filename().string(), readAll(dst));
    ++st.files_copied;
    return;
  }
  if (perCase(rel)) {
    const fs::path cf = caseFolderOf(rel);
    if (std::find(ms.taken_cases.begin(), ms.taken_cases.end(), cf) != ms.taken_cases.end()) {  // earlier shard's
      if (rel.filename() == "result.json" && fs::exists(ms.stage / rel, ec))
        requireSameResult(readResultFile((ms.stage / rel).string()).value_or(""), readResultFile(file.string()).value_or(""),
                          cf.filename().string(), ms.taken_by[cf], d);
      return;
    }
    ms.taken_by.emplace(cf, d);
    if (std::find(this_shard_cases.begin(), this_shard_cases.end(), cf) == this_shard_cases.end())
      this_shard_cases.push_back(cf);
  } else if (fs::exists(dst, ec)) {  // inputs and MJCF copies: the same in every shard
    if (readAll(dst) != readAll(file))
      throw std::runtime_error("merge: " + (fs::path(d) / rel).string() + " differs from the same file of an earlier shard");
    return;
  }
  fs::create_directories(dst.parent_path());
  fs::copy_file(file, dst, fs::copy_options::overwrite_existing);
  if (!perCase(rel) && rel.parent_path().filename() != "mjcf")  // an input copy: the merge wrote it
    recordInManifest(dst.parent_path().string(), rel.filename().string(), readAll(dst));
  ++st.files_copied;
}

// Stage 2: every shard's files into the staging folder, shard by shard; then the merged
// time_series.h5 files named in their manifests as tailsim wrote them, for the runner's check.
void copyShards(const std::vector<std::string>& shard_dirs, StopSignals& signals, MergeState& ms, MergeStats& st) {
  for (const std::string& d : shard_dirs) {
    const fs::path root(d);
    std::vector<fs::path> this_shard_cases;
    for (auto it = fs::recursive_directory_iterator(root); it != fs::recursive_directory_iterator(); ++it) {
      checkStop(signals);
      if (!it->is_regular_file()) continue;
      const fs::path rel = it->path().lexically_relative(root);
      if (rebuiltOrTransient(rel)) continue;
      mergeShardFile(it->path(), rel, d, ms, this_shard_cases, st);
    }
    ms.taken_cases.insert(ms.taken_cases.end(), this_shard_cases.begin(), this_shard_cases.end());
  }
  for (const fs::path& h5 : ms.merged_h5) {
    const std::optional<std::string> hash = sha256OfFile(h5.string());
    if (!hash) throw std::runtime_error("merge: cannot read back " + h5.string());
    recordHashInManifest(h5.parent_path().string(), h5.filename().string(), *hash);
  }
}

// Stage 3: the summary and results table, written by the runner itself, resuming every case and
// running none (a case in no shard is an error): the same code as a single-process run. Returns the
// suite; st.cases counts its cases.
std::vector<Experiment> rebuildSummary(const MergeState& ms, const std::string& out_dir, int threads, bool allow_other_build,
                                       StopSignals& signals, MergeStats& st) {
  std::vector<Experiment> suite = loadExperimentSuite((ms.stage / "experiment.yaml").string());
  resolveRobotModels(suite);  // the cases' keys include the derived robot
  RunOptions o;
  o.out_dir = ms.stage.string();
  o.threads = threads;
  o.progress = false;
  o.render = true;
  o.merge_only = true;
  o.allow_other_build = allow_other_build;
  o.case_origin = [&](const std::string& experiment, const std::string& name, const std::string& dir) -> std::string {
    for (const fs::path& prefix : {fs::path(experiment), fs::path()}) {
      if (const auto it = ms.journal_lines.find((prefix / name).string()); it != ms.journal_lines.end()) return it->second.second;
      if (const auto it = ms.taken_by.find(prefix / "cases" / dir); it != ms.taken_by.end()) return it->second;
    }
    return out_dir;
  };
  checkStop(signals);
  const RunStats rs = runSuite(suite, o);
  st.cases = rs.total;
  checkStop(signals);
  return suite;
}

// Stage 4: the staging folder, cleaned of its locks and marker, becomes `out` (empty or absent).
void publishStage(const fs::path& stage, const std::vector<Experiment>& suite, const fs::path& out) {
  std::error_code ec;
  fs::remove(stage / ".tailsim.lock", ec);
  for (const Experiment& e : suite) fs::remove(stage / e.name / ".tailsim.lock", ec);
  fs::remove(stage / kStageMarker);
  compactManifest(stage.string());
  if (fs::exists(out, ec)) fs::remove(out);  // empty (checked above)
  fs::rename(stage, out);
}
}  // namespace

// The stages in order: check the shards, copy them into a staging folder beside --out, let the runner
// write the summary there, and rename the staging folder to --out; a signal or an error removes it.
MergeStats mergeShards(const std::vector<std::string>& shard_dirs, const std::string& out_dir, int threads,
                       bool allow_other_build) {
  if (shard_dirs.empty()) throw std::runtime_error("merge: no shard folders given");
  MergeStats st;
  st.shards = static_cast<int>(shard_dirs.size());
  const fs::path out = fs::absolute(out_dir).lexically_normal();
  std::error_code ec;
  if (fs::exists(out, ec) && !(fs::is_directory(out, ec) && fs::is_empty(out, ec)))
    throw std::runtime_error("merge: " + out_dir + " exists and is not empty (merge into a new folder)");
  checkShards(shard_dirs, out, out_dir);
  StopSignals signals;
  removeStaleStages(out);
  MergeState ms;
  ms.stage = out.parent_path() / (out.filename().string() + ".merge.tmp." + std::to_string(::getpid()));
  fs::remove_all(ms.stage, ec);
  try {
    fs::create_directories(ms.stage);
    recordInManifest(ms.stage.string(), kStageMarker, kStageMarkerText);
    writeFileAtomic((ms.stage / kStageMarker).string(), kStageMarkerText);
    copyShards(shard_dirs, signals, ms, st);
    const std::vector<Experiment> suite = rebuildSummary(ms, out_dir, threads, allow_other_build, signals, st);
    publishStage(ms.stage, suite, out);
  } catch (const MergeStopped& m) {
    fs::remove_all(ms.stage, ec);
    st.stop_signal = m.sig;
  } catch (...) {
    fs::remove_all(ms.stage, ec);
    throw;
  }
  return st;
}

}  // namespace tailsim
