#include "experiments/experiment_runner.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/eventfd.h>
#include <sys/file.h>
#include <sys/signalfd.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <new>
#include <optional>
#include <set>
#include <nlohmann/json.hpp>
#include <sstream>
#include <system_error>
#include <thread>

#include "models/analytic/analytic_simulation.h"
#include "experiments/folder_inputs.h"
#include "experiments/model_registry.h"
#include "experiments/render_case.h"
#include "experiments/sharding.h"
#include "experiments/results_table.h"
#include "experiments/verdict.h"
#include "experiments/time_series_h5.h"
#include "experiments/work_estimate.h"
#include "experiments/robot_model_cases.h"
#include "models/mujoco/mjcf_generator.h"
#include "models/mujoco/mujoco_simulation.h"
#include "results/atomic_file.h"
#include "results/columns.h"
#include "results/sha256.h"
#include "results/thin_series.h"
#include "results/work_limits.h"
#include "tailsim_version.h"

namespace tailsim {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// A file descriptor closed when it goes out of scope (the run's signalfd and eventfd).
struct PollFd {
  explicit PollFd(int f) : fd(f) {}
  ~PollFd() {
    if (fd >= 0) ::close(fd);
  }
  PollFd(const PollFd&) = delete;
  PollFd& operator=(const PollFd&) = delete;
  int fd;
};


std::string fmtSeconds(double s) {
  char b[32];
  if (s < 60) std::snprintf(b, sizeof b, "%.1f s", s);
  else std::snprintf(b, sizeof b, "%dm%02ds", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
  return b;
}

}  // namespace

// ---- Resume key ----------------------------------------------------------------------------
// The SHA-256 of the canonical resolved case (settings_json.h: every declared setting, so a new
// setting is in the key by being declared), the models run, the render switch and settings, and
// the tailsim version and git commit.
std::string caseKey(const ExperimentCase& c, bool render) { return sha256Hex(caseKeyText(c, render)); }

// A name made only of [A-Za-z0-9.=,_-], not starting with '.' or '-', at most kMaxPlainDirName
// characters, is its own folder name. Any other name maps to its sanitized, shortened form plus
// "~" and 16 hex digits of its SHA-256: '~' never occurs in a plain name, so a plain and a mapped
// name never meet, and two mapped names meet only if their hashes do (checked in prepare()).
std::string caseDirName(const std::string& name) {
  constexpr size_t kMaxPlainDirName = 100, kMaxReadable = 80;
  auto allowed = [](char ch) {
    return std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' || ch == '-' || ch == '=' || ch == ',' ||
           ch == '_';
  };
  bool plain = !name.empty() && name.size() <= kMaxPlainDirName && name[0] != '.' && name[0] != '-';
  for (char ch : name) plain = plain && allowed(ch);
  if (plain) return name;
  std::string d;
  for (char ch : name.substr(0, kMaxReadable)) d += allowed(ch) ? ch : '_';
  if (!d.empty() && (d[0] == '.' || d[0] == '-')) d[0] = '_';
  if (d.empty()) d = "case";
  return d + "~" + sha256Hex(name).substr(0, 16);
}

json summaryJson(const RunSummary& s) {
  json j;
  j["ok"] = s.ok;
  // A failed run has no phi_net (null, never a number a reader could take for a result).
  j["phi_net_deg"] = s.ok && std::isfinite(s.phi_net_deg) ? json(s.phi_net_deg) : json(nullptr);
  j["t_stop_s"] = s.t_stop_s;
  j["stick_slip_events"] = s.stick_slip_events;
  j["wall_time_s"] = s.wall_time_s;
  j["solver_steps"] = s.solver_steps;
  if (!s.error.empty()) j["error"] = s.error;
  // A finished run: was the body at rest at the end, and what makes the result doubtful.
  j["at_rest"] = s.ok ? json(s.at_rest) : json(nullptr);
  j["warnings"] = s.warnings;
  for (const auto& [k, v] : s.extra) j["extra"][k] = std::isfinite(v) ? json(v) : json(nullptr);
  return j;
}

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

std::vector<RunResult> runCase(const ExperimentCase& c, RunContext* ctx) {
  std::vector<RunResult> out;
  if (c.robot_model && !c.robot_derived)  // the caller derives it first (resolveRobotModels)
    throw std::invalid_argument("case " + c.name + ": its robot's model file " + c.robot_model->file +
                                " was not stood and measured before the run (resolveRobotModels)");
  if (c.kind == CaseKind::kPose) {
    std::vector<JointState> js(c.robot.numLinks());
    for (size_t i = 0; i < js.size(); ++i)
      js[i] = {c.pose.theta_rad.at(i), c.pose.thetadot_radps.at(i), c.pose.thetaddot_radps2.at(i)};
    out.push_back(evaluatePose(c.robot, js, c.effects));
    return out;
  }
  for (const std::string& m : c.models) {
    const ModelEntry* model = findModel(m);
    if (!model) throw std::invalid_argument("unknown model '" + m + "'");  // the loader refuses it first
    out.push_back(model->run(c, ctx));
    if (const std::string w = jointSpeedWarning(c); !w.empty()) out.back().summary.warnings.push_back(w);
  }
  return out;
}

namespace {

// DIR/cases.jsonl: the resume record of the cases that have no folder of their own (no CSV time
// series: output.time_series none, or time_series_file hdf5). One line per finished case, the JSON
// a case folder's result.json would hold, appended with one write() (O_APPEND) the moment the
// case is done; no fsync (a kill -9 loses nothing the kernel has; a power cut may lose the last
// lines, whose cases then run again). A torn last line (killed inside the write, or a full disk)
// is cut off before the next run appends (readJournal). At the end of a run the file is rewritten
// atomically with exactly the finished cases in case order, so it is the same whatever the order
// the workers finished in (and after a resume).
class CaseJournal {
 public:
  explicit CaseJournal(const fs::path& p) : path_(p) {}
  ~CaseJournal() {
    if (fd_ >= 0) ::close(fd_);
  }
  CaseJournal(const CaseJournal&) = delete;
  CaseJournal& operator=(const CaseJournal&) = delete;
  void append(const std::string& line) {
    std::lock_guard<std::mutex> lock(mu_);
    if (fd_ < 0) {
      // A regular file of the folder only: never through a symlink, never a FIFO or device.
      fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK, 0644);
      if (fd_ < 0) throw std::system_error(errno, std::generic_category(), "cannot open " + path_.string());
      struct stat st {};
      if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode) || st.st_nlink > 1) {
        const bool linked = S_ISREG(st.st_mode) && st.st_nlink > 1;
        ::close(fd_);
        fd_ = -1;
        throw std::runtime_error(path_.string() + (linked ? " has other hard links (the same file elsewhere): not written"
                                                          : " is not a regular file: not written"));
      }
    }
    size_t done = 0;
    while (done < line.size()) {
      const ssize_t n = ::write(fd_, line.data() + done, line.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) throw std::system_error(errno, std::generic_category(), "cannot append to " + path_.string());
      done += static_cast<size_t>(n);
    }
  }
  void close() {
    std::lock_guard<std::mutex> lock(mu_);
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  fs::path path_;
  std::mutex mu_;
  int fd_ = -1;
};

// The longest line tailsim writes into cases.jsonl (a case's entry: a few kB) with a wide margin.
constexpr size_t kMaxJournalLine = size_t(1) << 22;

// Whether a journal line is an entry tailsim writes: an object with a string "key" and "name".
bool journalEntry(const json& j) {
  return j.is_object() && j.contains("key") && j["key"].is_string() && j.contains("name") && j["name"].is_string();
}

// The first line of DIR/cases.jsonl (without its newline; a file without one: all of it), read
// no further than kMaxJournalLine; std::nullopt when absent.
std::optional<std::string> firstJournalLine(const fs::path& p) {
  std::string first;
  const std::optional<LinesRead> r = readResultFileLines(p.string(), kMaxJournalLine, [&](const std::string& line, long long) {
    first = line;
    return false;
  });
  if (!r) return std::nullopt;
  return r->lines > 0 ? first : r->tail;
}

// The finished cases of DIR/cases.jsonl by name (a later line wins), read line by line (a line
// longer than any entry tailsim writes: an error naming the file). A file whose first line is not a
// tailsim entry is not tailsim's: an error naming it, the file untouched. A last line without its
// newline (torn by a kill or a full disk: the start of an entry) is cut off the file, so the next
// append starts a line.
std::map<std::string, std::string> readJournal(const fs::path& p, bool repair) {
  std::map<std::string, std::string> out;
  const auto notOurs = [&](const std::string& why) {
    return std::runtime_error(p.string() + " " + why + ": not a journal tailsim wrote, not changed (move it out of " +
                              p.parent_path().string() + " or choose another --out)");
  };
  std::optional<LinesRead> read;
  try {
    read = readResultFileLines(p.string(), kMaxJournalLine, [&](const std::string& line, long long number) {
      const json j = json::parse(line, nullptr, false);
      if (number == 1 && !journalEntry(j)) throw notOurs("line 1 is not a case entry of tailsim");
      if (journalEntry(j)) out[j["name"].get<std::string>()] = line;  // as text: see Job::entries
      return true;
    });
  } catch (const std::bad_alloc&) {
    throw std::runtime_error(p.string() + " holds more than this process can read into memory: not tailsim's journal (move it away)");
  }
  if (!read) return out;
  if (!read->tail.empty()) {
    if (read->lines == 0 && read->tail.compare(0, 2, "{\"") != 0) throw notOurs("does not start with a case entry of tailsim");
    if (repair) {
      struct stat st {};
      if (::lstat(p.c_str(), &st) == 0 && st.st_nlink > 1)
        throw notOurs("has other hard links (the same file elsewhere)");
      std::error_code ec;
      fs::resize_file(p, static_cast<uintmax_t>(read->whole), ec);
    }
  }
  return out;
}

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

constexpr char kH5None = 0, kH5Published = 1, kH5Part = 2;
const char* const kH5Parts = "time_series.h5.d";

fs::path h5PartPath(const Job& job, size_t i) { return job.root / kH5Parts / (job.dirs[i] + ".h5"); }

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

bool keepsSeries(const ExperimentCase& c) { return c.output.time_series != TimeSeriesOutput::kNone; }
bool inH5(const ExperimentCase& c) { return keepsSeries(c) && c.output.time_series_file == TimeSeriesFile::kHdf5; }

// The run lock goes with the process (also on kill -9); the file stays.
}  // namespace

FolderLock::FolderLock(const std::string& dir_text) {
  const fs::path dir(dir_text);
  fs::create_directories(dir);
  const fs::path p = dir / ".tailsim.lock";
  fd_ = ::open(p.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK, 0644);
  if (fd_ < 0) throw std::runtime_error("cannot open " + p.string() + ": " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode) || st.st_nlink > 1) {
    ::close(fd_);
    throw std::runtime_error(p.string() + (S_ISREG(st.st_mode) ? " has other hard links (the same file elsewhere)"
                                                                 : " is not a regular file") +
                             ": tailsim writes its lock only into a file of its own (remove it)");
  }
  // A busy lock whose recorded run is dead is held for a moment more by that run's dying helper
  // process (runHdf5Isolated's child, killed with it): waited for up to kDeadHolderWait.
  constexpr auto kDeadHolderWait = std::chrono::seconds(2);
  const auto t0 = std::chrono::steady_clock::now();
  while (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    char buf[32] = {};
    const ssize_t n = ::pread(fd_, buf, sizeof buf - 1, 0);
    std::string pid = n > 0 ? std::string(buf, static_cast<size_t>(n)) : "?";
    while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
    const bool holder_dead = !pid.empty() && pid.size() <= 9 &&
                             std::all_of(pid.begin(), pid.end(), [](char c) { return c >= '0' && c <= '9'; }) &&
                             processGone(std::atol(pid.c_str()));
    if (err == EWOULDBLOCK && holder_dead && std::chrono::steady_clock::now() - t0 < kDeadHolderWait) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      continue;
    }
    ::close(fd_);
    if (err != EWOULDBLOCK) throw std::runtime_error("cannot lock " + p.string() + ": " + std::strerror(err));
    throw std::runtime_error(dir.string() + " is in use by another tailsim run (pid " + pid + ")");
  }
  const std::string me = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, me.data(), me.size(), 0) != static_cast<ssize_t>(me.size())) {
    // the pid is only for the message of a second run; the lock itself holds
  }
}

FolderLock::~FolderLock() { ::close(fd_); }  // releases the lock

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

namespace {
using RunLock = FolderLock;

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
  if (!ownFile(root, name))
    throw std::runtime_error((root / name).string() + " was not written by tailsim (or was changed since): not "
                             "replaced; move it out of " + root.string() + " or choose another --out");
  recordInManifest(root.string(), name, text);
  writeFileAtomic((root / name).string(), text);
}

// The entries tailsim writes into a result folder (docs/ARCHITECTURE.md) are deleted, and in them
// only what tailsim writes: its top-level files when they are its own (ownFile), a case folder's
// result.json and <model>.csv, mjcf/<hash>.xml, renders/<case dir>.{mp4,png}, time_series.h5(.d),
// its temporary files, and the files of `tailsim plot` / `report` (plots/, page/, report.md,
// figures.html, index.html) that their folder's manifest names unchanged. Anything else stays
// (named on stderr).
void clearResultFolder(const fs::path& root) {
  std::error_code ec;
  std::vector<std::string> kept;
  const auto removeIf = [&](const fs::path& p, bool own) {
    if (!fs::exists(fs::symlink_status(p, ec))) return;
    if (own) fs::remove(p, ec);
    else kept.push_back(p.string());
  };
  const auto isTemp = [](const std::string& n) { return n.find(".tailsim-tmp.") != std::string::npos; };
  // Folders: delete tailsim's files in them, then the folder if it is empty.
  const auto clearDir = [&](const fs::path& dir, const std::function<bool(const std::string&)>& own) {
    if (!fs::is_directory(fs::symlink_status(dir, ec))) {
      if (fs::exists(fs::symlink_status(dir, ec))) kept.push_back(dir.string());
      return;
    }
    for (const auto& f : fs::directory_iterator(dir, ec)) {
      const std::string n = f.path().filename().string();
      removeIf(f.path(), f.is_regular_file(ec) && !f.is_symlink(ec) && (isTemp(n) || own(n)));
    }
    fs::remove(dir, ec);  // only if now empty
  };
  std::set<std::string> case_dirs;
  const std::vector<std::string> models = modelNames();
  if (fs::is_directory(fs::symlink_status(root / "cases", ec))) {
    for (const auto& d : fs::directory_iterator(root / "cases", ec)) {
      if (!d.is_directory(ec) || d.is_symlink(ec)) {
        kept.push_back(d.path().string());
        continue;
      }
      if (isRegularFile(d.path() / "result.json")) case_dirs.insert(d.path().filename().string());
      clearDir(d.path(), [&](const std::string& n) {
        if (n == "result.json") return true;
        return std::any_of(models.begin(), models.end(), [&](const std::string& m) { return n == m + ".csv"; });
      });
    }
    fs::remove(root / "cases", ec);
  }
  if (const json s = readJsonFile(root / "summary.json"); s.is_object() && s.contains("cases") && s["cases"].is_array())
    for (const json& c : s["cases"])
      if (c.is_object() && c.contains("dir") && c["dir"].is_string()) case_dirs.insert(c["dir"].get<std::string>());
  clearDir(root / "renders", [&](const std::string& n) {
    const size_t dot = n.rfind('.');
    return dot != std::string::npos && (n.substr(dot) == ".mp4" || n.substr(dot) == ".png") &&
           case_dirs.count(n.substr(0, dot));
  });
  clearDir(root / "mjcf", [](const std::string& n) {
    return n.size() == 20 && n.compare(16, 4, ".xml") == 0 &&
           std::all_of(n.begin(), n.begin() + 16, [](char ch) { return std::isxdigit(static_cast<unsigned char>(ch)); });
  });
  clearDir(root / kH5Parts, [](const std::string& n) { return n.size() > 3 && n.compare(n.size() - 3, 3, ".h5") == 0; });
  // Folders of `tailsim plot` (figures, the result page): the files their manifest names unchanged.
  const auto clearManifested = [&](const fs::path& dir) {
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
  };
  clearManifested(root / "page" / "cases");
  clearManifested(root / "page");
  clearManifested(root / "plots");
  {
    const fs::path h5 = root / "time_series.h5";
    removeIf(h5, fs::is_regular_file(fs::symlink_status(h5, ec)) && TimeSeriesH5Reader(h5.string()).ok());
  }
  for (const char* name : {"report.md", "figures.html", "index.html"}) {
    bool own = false;
    try {
      const std::optional<std::string> t = readResultFile((root / name).string());
      own = t && manifestNames(root.string(), name, *t);
    } catch (const std::exception&) {  // not a regular file: not tailsim's
    }
    removeIf(root / name, own);
  }
  std::vector<std::string> top = {"cases.jsonl", "results.csv", "experiment.yaml", "robot.yaml", "robot.xml"};
  for (const auto& f : fs::directory_iterator(root, ec))
    if (isRobotCopy(f.path().filename().string())) top.push_back(f.path().filename().string());
  top.push_back("summary.json");  // last: ownFile of the others may read it
  for (const std::string& name : top) {
    bool own = false;
    try {
      own = ownFile(root, name);
    } catch (const std::exception&) {  // not a regular file: not tailsim's
    }
    removeIf(root / name, own);
  }
  compactManifest(root.string());
  for (const std::string& k : kept) std::fprintf(stderr, "note: --fresh kept %s (not written by tailsim)\n", k.c_str());
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

// in_shard: per case, whether it belongs to this process's shard (--shard K/N; empty = all).
Job prepare(const Experiment& e, const RunOptions& opt, const fs::path& root, const std::vector<char>& in_shard = {}) {
  Job job;
  job.e = &e;
  job.root = root;
  job.source = recordedSource(e);
  std::vector<size_t> todo_all;
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
  for (const auto& [name, text] : folderInputs(e)) writeOwnFile(root, name, text);
  if (job.render) checkRenderPrerequisites(e.cases.front().render, (root / "renders").string());
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
  // HDF5 files are opened only when they are as tailsim wrote them (their SHA-256 named in their
  // folder's manifest): libhdf5 crashes on some damaged files, and copies others silently. A
  // damaged time_series.h5 or part is not read: its cases run again (and the file is replaced).
  if (job.any_h5) {
    const fs::path h5 = root / "time_series.h5";
    bool intact = false;
    if (isRegularFile(h5)) {
      const std::optional<std::string> hash = sha256OfFile(h5.string());
      intact = hash && manifestNamesHash(root.string(), "time_series.h5", *hash);
      if (!intact)
        std::fprintf(stderr, "note: %s is not as tailsim wrote it (damaged or changed): not read, its cases run again\n",
                     h5.c_str());
    }
    job.published = std::make_unique<TimeSeriesH5Reader>(intact ? h5.string() : std::string());
  }
  // Where case i's whole group is: its own file (when intact), else the published file, else nowhere.
  const auto findH5 = [&](size_t i, const std::vector<std::string>& models, const std::string& key) -> char {
    const fs::path part = h5PartPath(job, i);
    if (h5PartIntact(job, i) && TimeSeriesH5Reader(part.string()).hasCase(job.dirs[i], key, models))
      return kH5Part;
    return job.published->hasCase(job.dirs[i], key, models) ? kH5Published : kH5None;
  };
  {  // the lines of cases not run now (--case, another shard's) are kept when the journal is rewritten
    std::vector<char> now(e.cases.size(), 0);
    for (size_t i : todo_all) now[i] = 1;
    job.other_lines.resize(e.cases.size());
    for (size_t i = 0; i < e.cases.size(); ++i)
      if (!now[i])
        if (auto it = journal.find(e.cases[i].name); it != journal.end()) {
          job.other_lines[i] = it->second;
          if (inH5(e.cases[i])) job.h5_from[i] = findH5(i, {}, job.keys[i]);  // its group stays too
        }
  }
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
      job.h5_from[i] = findH5(i, models, j.value("key", std::string()));
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
  if (!job.other_builds.empty()) {
    std::string list;
    int n = 0;
    for (const auto& [build, count] : job.other_builds) {
      list += (list.empty() ? "" : ", ") + std::to_string(count) + " by " + build;
      n += count;
    }
    // Where those cases are: DIR, or for a merge the shard folders they come from.
    std::string where = root.string();
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
  if (opt.merge_only && !job.todo.empty())
    throw std::runtime_error("merge: case '" + e.cases[job.todo.front()].name + "' of experiment " + e.name +
                             " is finished in none of the shard folders (run its shard, or the shard again)");
  if (had_journal) {  // compacted: one line per finished case, whatever earlier runs appended
    std::string lines;
    for (size_t i = 0; i < e.cases.size(); ++i)
      if (!job.entries[i].empty() && !e.cases[i].output.caseFolder()) lines += job.entries[i] + "\n";
      else if (!job.other_lines[i].empty()) lines += job.other_lines[i] + "\n";
    writeFileAtomic((root / "cases.jsonl").string(), lines);
  }
  if (any_journal || had_journal) job.journal = std::make_unique<CaseJournal>(root / "cases.jsonl");
  return job;
}

// Runs one case and writes its folder; result.json last, as the "finished" marker.
std::string runAndWrite(const Job& job, size_t i, int& failed_runs, RunContext& ctx) {
  const ExperimentCase& c = job.e->cases[i];
  const std::vector<RunResult> runs = runCase(c, &ctx);
  const fs::path dir = job.root / "cases" / job.dirs[i];
  const bool folder = c.output.caseFolder();
  if (folder) makeResultDir(dir.string());
  json j;
  j["name"] = c.name;
  j["dir"] = job.dirs[i];
  j["experiment"] = job.e->name;
  j["source"] = job.source;
  j["key"] = job.keys[i];
  j["tailsim_version"] = kVersion;
  if (*kGitCommit) j["tailsim_git_commit"] = kGitCommit;
  // Every parameter the run used, defaults included, in a case folder's result.json. A case
  // without a folder (a line of DIR/cases.jsonl, one of up to 10^5) leaves it out: it is 80 % of
  // the line, and the folder's experiment.yaml resolves every case the same (ExperimentResults).
  if (c.output.caseFolder()) {
    j["resolved"] = resolvedJson(c);
    // ... but not where they were read from: a folder re-run from its own copies (robot.yaml,
    // experiment.yaml) must write the same result.json; "source" above names the original input.
    j["resolved"].erase("source_file");
    j["resolved"].erase("robot_file");
  }
  j["sweep"] = json::object();
  for (const auto& [key, v] : c.sweep_values) j["sweep"][key] = v;
  j["runs"] = json::object();
  const bool thin = c.output.time_series == TimeSeriesOutput::kThin;
  const std::vector<double> marks = thin && c.kind == CaseKind::kSimulate ? c.trajectory().breakpoints() : std::vector<double>{};
  std::unique_ptr<TimeSeriesH5Writer> part;  // this case's DIR/time_series.h5.d/<dir>.h5
  if (inH5(c)) {
    makeResultDir((job.root / kH5Parts).string());
    part = std::make_unique<TimeSeriesH5Writer>(h5PartPath(job, i).string(), H5Storage::kMemory);
  }
  for (const RunResult& r : runs) {
    // Every model's CSV in the one column order (docs/ARCHITECTURE.md "Time-series columns").
    if (keepsSeries(c)) {
      TimeSeries ordered = col::inColumnOrder(r.series, modelColumnOrder(col::links(r.series)));
      if (thin && !r.series_thinned) ordered = thinRows(ordered, marks);
      if (folder) writeCsvAtomic((dir / (r.summary.model + ".csv")).string(), ordered);
      else part->write(job.dirs[i], c.name, job.keys[i], c.sweep_values, r.summary.model,
                       settings::nameOf(timeSeriesOutputNames(), c.output.time_series), ordered);
    }
    j["runs"][r.summary.model] = summaryJson(r.summary);
    if (!r.summary.ok) ++failed_runs;
  }
  {
    std::vector<RunSummary> sums;
    for (const RunResult& r : runs) sums.push_back(r.summary);
    if (std::string v = caseVerdict(sums); !v.empty()) j["verdict"] = std::move(v);
  }
  // The MJCF a model's run simulated, once per distinct model (mjcf/<hash>.xml); none when the
  // model could not be built (the run's error says why).
  const bool simulates_mjcf = std::any_of(c.models.begin(), c.models.end(), [](const std::string& m) {
    const ModelEntry* e = findModel(m);
    return e && e->simulates_mjcf;
  });
  if (c.kind != CaseKind::kPose && simulates_mjcf) {
    std::string xml;
    try {
      xml = c.robot_model ? articulatedMjcf(c) : generateMjcf(c.robot, c.mujoco, c.effects);
    } catch (const std::exception&) {
    }
    if (!xml.empty()) {
      const std::string name = mjcfFileName(xml);
      makeResultDir((job.root / "mjcf").string());
      if (!fs::exists(job.root / name)) writeFileAtomic((job.root / name).string(), xml);
      j["mjcf"] = name;
    }
  }
  if (job.render) renderCase(c, runs, (job.root / "renders").string());
  if (part) {  // on disk, and named with its content before it takes its name, before the journal line
    part->publish([&](const std::string& temp) {
      const std::optional<std::string> hash = sha256OfFile(temp);
      if (!hash) throw std::runtime_error("cannot read back " + temp);
      recordHashInManifest((job.root / kH5Parts).string(), job.dirs[i] + ".h5", *hash);
    });
  }
  std::string line = j.dump();
  if (folder) writeFileAtomic((dir / "result.json").string(), j.dump(1));
  else job.journal->append(line + "\n");  // one line, one write(): the case is finished
  return line;
}

// The finished entries of a job, in case order, each parsed on its own (Job::entries).
template <class F>
void forEachEntry(const Job& job, const F& f) {
  for (const std::string& text : job.entries)
    if (!text.empty()) f(json::parse(text));
}

// One experiment's rows of a results table, read from its job's entries (after writeSummary: the
// part a table reads, {name, sweep, runs, verdict}, and the extras' names collected).
ResultsCsvInput tableInput(const Job& job) {
  return {job.e->name, job.e->swept_keys, [&job](const std::function<void(const json&)>& f) { forEachEntry(job, f); },
          &job.extra_names};
}

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

// All cases of all experiments share one pool of workers (workers share nothing mutable but
// the task counter; each writes only its own case folder and entry).
// suite_root: a suite's folder, which gets the results.csv of all members.
RunStats runJobs(std::vector<Job>& jobs, const RunOptions& opt, const std::string& label,
                 const fs::path& suite_root = {}) {
  const auto wall0 = std::chrono::steady_clock::now();
  RunStats stats;
  struct Task {
    Job* job;
    size_t i;
  };
  std::vector<Task> tasks;
  for (Job& job : jobs) {
    stats.total += job.total;
    stats.resumed += job.resumed;
    for (size_t i : job.todo) tasks.push_back({&job, i});
  }
  if (opt.max_new_cases >= 0 && static_cast<long>(tasks.size()) > opt.max_new_cases) tasks.resize(opt.max_new_cases);
  // MuJoCo cases first: the long tasks start early, the short ones fill the gaps at the end.
  std::stable_sort(tasks.begin(), tasks.end(), [](const Task& a, const Task& b) {
    auto heavy = [](const Task& t) {
      const auto& m = t.job->e->cases[t.i].models;
      return std::any_of(m.begin(), m.end(), [](const std::string& name) {
        const ModelEntry* e = findModel(name);
        return e && e->long_running;
      });
    };
    return heavy(a) && !heavy(b);
  });

  // Ctrl-C, SIGTERM (a batch system's time limit) and SIGHUP (a closed terminal), with
  // opt.stop_on_sigint: blocked in this thread before the workers start (they inherit the mask,
  // and so do ffmpeg/gnuplot children), and read here from a signalfd: no handler, no global flag.
  // The first stops new cases, the in-flight ones finish and are saved; a second terminates the
  // process at once by that signal (finished cases stay saved: each is on disk whole, its HDF5
  // groups in a file of its own, before its journal line).
  // The main thread sleeps in poll() on that signalfd and on an eventfd each worker writes when it
  // exits, so it wakes the moment the last case is done (a fixed sleep cost every run up to 100 ms),
  // and otherwise once per progress period (a wake-up after every case doubled the system time of
  // a sweep of short cases: docs/scale.md "Work no result needed").
  sigset_t int_set, old_mask;
  sigemptyset(&int_set);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&int_set, sig);
  if (opt.stop_on_sigint) pthread_sigmask(SIG_BLOCK, &int_set, &old_mask);
  const PollFd sig_fd(opt.stop_on_sigint ? ::signalfd(-1, &int_set, SFD_CLOEXEC | SFD_NONBLOCK) : -1);
  const PollFd wake_fd(::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK));
  if ((opt.stop_on_sigint && sig_fd.fd < 0) || wake_fd.fd < 0) {
    if (opt.stop_on_sigint) pthread_sigmask(SIG_SETMASK, &old_mask, nullptr);
    throw std::system_error(errno, std::generic_category(), "cannot create the run's signalfd/eventfd");
  }
  auto wakeMain = [&wake_fd]() {
    const uint64_t one = 1;
    while (::write(wake_fd.fd, &one, sizeof one) < 0 && errno == EINTR) {
    }
  };

  std::atomic<size_t> next{0};
  std::atomic<int> done{0}, failed{0}, running{0};
  std::atomic<bool> stop{false};
  int stop_signal = 0;  // the signal that stopped the run (main thread only)
  std::mutex mu;
  std::string first_error;
  RunContext ctx;  // shared by the workers: the MuJoCo pre-roll once per distinct model
  auto worker = [&]() {
    for (;;) {
      if (stop.load()) break;
      const size_t k = next.fetch_add(1);
      if (k >= tasks.size()) break;
      const Task& t = tasks[k];
      try {
        int f = 0;
        std::string entry = runAndWrite(*t.job, t.i, f, ctx);
        failed += f;
        t.job->entries[t.i] = std::move(entry);  // distinct element per task: no lock needed
        if (inH5(t.job->e->cases[t.i])) t.job->h5_from[t.i] = kH5Part;
      } catch (const std::bad_alloc&) {
        // Out of memory: every case holds its series in memory while it runs; start no more.
        stop = true;
        std::lock_guard<std::mutex> lock(mu);
        if (first_error.empty()) {
          // Its series as held while it runs: rows x columns x 8 B a value, per model (a lower bound).
          const ExperimentCase& c = t.job->e->cases[t.i];
          char mb[32];
          std::snprintf(mb, sizeof mb, "%.0f",
                        estimateWork(c).csv_bytes / limits::kCsvBytesPerValue * 8.0 * static_cast<double>(c.models.size()) / 1e6);
          first_error = "case " + c.name + ": out of memory while running it (each running case holds its time series in "
                        "memory, at least about " + mb + " MB for this one, one case per thread): use fewer --threads, "
                        "raise output.sample_dt_s or set output.time_series: thin or none; no further case was started, "
                        "the finished ones are saved (run the same command again to resume)";
        }
      } catch (const std::exception& ex) {
        // A full disk fails every case after it: stop starting new ones.
        const auto* sys = dynamic_cast<const std::system_error*>(&ex);
        const bool disk_full = sys && sys->code() == std::errc::no_space_on_device;
        if (disk_full) stop = true;
        std::lock_guard<std::mutex> lock(mu);
        if (first_error.empty())
          first_error = "case " + t.job->e->cases[t.i].name + ": " + ex.what() +
                        (disk_full ? " (the disk is full: no further case was started; free space and run the "
                                     "same command again to resume)"
                                   : "");
      }
      ++done;  // (no wake-up per case: a syscall and a context switch each)
    }
    {
      std::lock_guard<std::mutex> lock(mu);
      --running;
    }
    wakeMain();
  };
  const int n_threads = std::max(1, std::min<int>(opt.threads > 0 ? opt.threads : std::thread::hardware_concurrency(),
                                                  static_cast<int>(tasks.size())));
  std::vector<std::thread> pool;
  for (int t = 0; t < n_threads && !tasks.empty(); ++t) {
    ++running;
    try {
      pool.emplace_back(worker);
    } catch (const std::system_error& ex) {  // out of threads or memory (ulimit -u, -v; cgroup pids.max)
      --running;
      if (pool.empty()) {
        if (opt.stop_on_sigint) pthread_sigmask(SIG_SETMASK, &old_mask, nullptr);
        throw std::runtime_error(std::string("cannot start a worker thread (") + ex.what() +
                                 "): the process limits (ulimit -u, ulimit -v) leave no room for one; no case was run");
      }
      std::fprintf(stderr, "note: started %zu of %d worker threads (%s); running on %zu\n", pool.size(), n_threads,
                   ex.what(), pool.size());
      break;
    }
  }

  // Progress: on a terminal one line redrawn with \r; in a log (not a TTY) a plain line every
  // few seconds, so the log is readable and not flooded.
  const bool tty = ::isatty(STDERR_FILENO) == 1;
  const bool show = opt.progress && !tasks.empty();
  const auto period = tty ? std::chrono::milliseconds(500) : std::chrono::milliseconds(5000);
  bool line_open = false;  // a \r line is on screen
  int shown = -1;
  auto last_print = wall0;
  auto printProgress = [&](bool final_line) {
    const int d = done.load();
    const auto now = std::chrono::steady_clock::now();
    if (!final_line && (d == shown || now - last_print < period)) return;
    shown = d;
    last_print = now;
    const double el = std::chrono::duration<double>(now - wall0).count();
    const double eta = d > 0 ? el / d * (tasks.size() - d) : 0.0;
    char line[256];
    std::snprintf(line, sizeof line, "[%s] %d/%d cases (%d resumed), %s elapsed", label.c_str(), d + stats.resumed,
                  stats.total, stats.resumed, fmtSeconds(el).c_str());
    const std::string eta_s = final_line ? std::string() : ", ETA " + fmtSeconds(eta);
    if (tty) {
      std::fprintf(stderr, "\r%s%s   ", line, eta_s.c_str());
      line_open = true;
      if (final_line) {
        std::fprintf(stderr, "\n");
        line_open = false;
      }
    } else {
      std::fprintf(stderr, "%s%s\n", line, eta_s.c_str());
    }
    std::fflush(stderr);
  };
  for (;;) {
    if (running.load() == 0) break;
    pollfd fds[2] = {{wake_fd.fd, POLLIN, 0}, {sig_fd.fd, POLLIN, 0}};
    const int n_fds = opt.stop_on_sigint ? 2 : 1;
    int timeout_ms = show ? static_cast<int>(period.count()) : -1;
    if (opt.should_stop) timeout_ms = timeout_ms < 0 ? 200 : std::min(timeout_ms, 200);
    if (::poll(fds, n_fds, timeout_ms) > 0) {
      uint64_t count = 0;
      if (fds[0].revents & POLLIN) (void)!::read(wake_fd.fd, &count, sizeof count);
    }
    if (opt.should_stop && !stop.load() && opt.should_stop()) stop = true;
    if (opt.stop_on_sigint && (fds[1].revents & POLLIN)) {
      signalfd_siginfo info{};
      if (::read(sig_fd.fd, &info, sizeof info) == static_cast<ssize_t>(sizeof info)) {
        const int sig = static_cast<int>(info.ssi_signo);
        const std::string sig_name = sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP" : "Ctrl-C";
        const std::string by = sig == SIGINT ? "" : " by " + sig_name;
        if (line_open) std::fprintf(stderr, "\n");
        line_open = false;
        if (!stop.exchange(true)) {
          stop_signal = sig;
          const int in_flight = static_cast<int>(std::min(next.load(), tasks.size())) - done.load();
          std::fprintf(stderr, "interrupted%s: finishing %d running case%s (%s again to abandon %s)\n", by.c_str(),
                       in_flight, in_flight == 1 ? "" : "s", sig_name.c_str(), in_flight == 1 ? "it" : "them");
        } else {
          // Finished cases stay resumable: their result.json / cases.jsonl line is on disk, their
          // HDF5 groups in DIR/time_series.h5.d; a case still being written runs again.
          std::fprintf(stderr, "interrupted again: abandoning the running cases; %d cases saved\n", done.load() + stats.resumed);
          std::signal(sig, SIG_DFL);
          pthread_sigmask(SIG_SETMASK, &old_mask, nullptr);
          std::raise(sig);  // terminates: the shell sees "killed by <signal>"
        }
      }
    }
    if (show) printProgress(false);
  }
  for (auto& th : pool) th.join();
  if (opt.stop_on_sigint) pthread_sigmask(SIG_SETMASK, &old_mask, nullptr);
  if (show) printProgress(true);
  else if (line_open) std::fprintf(stderr, "\n");
  stats.interrupted = stop.load();
  stats.stop_signal = stop_signal;
  try {
    std::vector<ResultsCsvInput> tables;
    for (Job& job : jobs) {
      writeSummary(job);  // also after a failure: finished cases count
      tables.push_back(tableInput(job));
    }
    if (!suite_root.empty()) writeOwnFile(suite_root, "results.csv", resultsCsv(tables));
    for (Job& job : jobs) compactManifest(job.root.string());  // one line per file, as it is now
    if (!suite_root.empty()) compactManifest(suite_root.string());
  } catch (const std::exception&) {
    if (first_error.empty()) throw;  // else report the first error (a full disk fails the summary too)
  }
  if (!first_error.empty()) throw std::runtime_error(first_error);
  stats.ran = done.load();
  stats.failed = failed.load();
  stats.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return stats;
}

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
