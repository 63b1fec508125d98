#include "experiments/experiment_runner.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <system_error>
#include <thread>

#include "analytic_model/analytic_simulation.h"
#include "experiments/render_case.h"
#include "mujoco_model/mujoco_simulation.h"
#include "results/atomic_file.h"
#include "results/sha256.h"
#include "tailsim_version.h"

namespace tailsim {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
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

std::string fmtSeconds(double s) {
  char b[32];
  if (s < 60) std::snprintf(b, sizeof b, "%.1f s", s);
  else std::snprintf(b, sizeof b, "%dm%02ds", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
  return b;
}

}  // namespace

// ---- Resume key -------------------------------------------------------------------------
// A canonical text of everything a case's results depend on, one "key=value" line each, numbers
// with 17 significant digits (exact for doubles). If a field is added to one of these structs,
// the static_asserts below fail: add the field to the text, then update the size.
namespace {

static_assert(sizeof(QuadrupedParams) == 48 && sizeof(FrictionParams) == 48 && sizeof(TailLink) == 32 &&
                  sizeof(RobotParams) == 128,
              "a robot parameter was added: add it to caseKeyText, then update this size");
static_assert(sizeof(SplitCycleParams) == 40, "a trajectory parameter was added: add it to caseKeyText");
static_assert(sizeof(AnalyticSettings) == 96, "an analytic setting was added: add it to caseKeyText");
static_assert(sizeof(MujocoSettings) == 288, "a MuJoCo setting was added: add it to caseKeyText");
static_assert(sizeof(Effects) == 16, "an effect was added: add it to caseKeyText");
static_assert(sizeof(OutputSettings) == 24, "an output setting was added: add it to caseKeyText");
static_assert(sizeof(RenderSettings) == 152, "a render setting was added: add it to caseKeyText");
static_assert(sizeof(PoseSpec) == 72 && sizeof(ExperimentCase) == 1032,
              "a case field was added: add it to caseKeyText if results depend on it");

struct KeyText {
  std::string s;
  void add(const std::string& k, double v) {
    char b[40];
    std::snprintf(b, sizeof b, "%.17g", v);
    s += k + "=" + b + "\n";
  }
  void add(const std::string& k, int v) { s += k + "=" + std::to_string(v) + "\n"; }
  void add(const std::string& k, bool v) { s += k + "=" + (v ? "true" : "false") + "\n"; }
  void add(const std::string& k, const std::string& v) {
    s += k + "=" + std::to_string(v.size()) + ":" + v + "\n";  // length-prefixed: no ambiguity
  }
  void add(const std::string& k, const char* v) { add(k, std::string(v)); }
  void add(const std::string& k, const std::vector<double>& v) {
    add(k + ".size", static_cast<int>(v.size()));
    for (size_t i = 0; i < v.size(); ++i) add(k + "[" + std::to_string(i) + "]", v[i]);
  }
};

}  // namespace

std::string caseKeyText(const ExperimentCase& c, bool render) {
  KeyText t;
  t.add("tailsim.version", kVersion);
  t.add("tailsim.git_commit", kGitCommit);
  t.add("experiment", c.experiment);
  t.add("case", c.name);
  t.add("sweep.size", static_cast<int>(c.sweep_values.size()));
  for (const auto& [k, v] : c.sweep_values) t.add("sweep." + k, v);
  t.add("kind", c.kind);
  t.add("pose.theta_rad", c.pose.theta_rad);
  t.add("pose.thetadot_radps", c.pose.thetadot_radps);
  t.add("pose.thetaddot_radps2", c.pose.thetaddot_radps2);
  const RobotParams& r = c.robot;  // the resolved values, not the robot file's name
  t.add("quadruped.mass_kg", r.quadruped.mass_kg);
  t.add("quadruped.izz_kgm2", r.quadruped.izz_kgm2);
  t.add("quadruped.d_Q2C_m", r.quadruped.d_Q2C_m);
  t.add("quadruped.d_Q2B_m", r.quadruped.d_Q2B_m);
  t.add("quadruped.l_F_m", r.quadruped.l_F_m);
  t.add("quadruped.w_F_m", r.quadruped.w_F_m);
  t.add("tail.links", r.numLinks());
  for (size_t i = 0; i < r.tail.size(); ++i) {
    const std::string k = "tail[" + std::to_string(i) + "].";
    t.add(k + "mass_kg", r.tail[i].mass_kg);
    t.add(k + "izz_kgm2", r.tail[i].izz_kgm2);
    t.add(k + "length_m", r.tail[i].length_m);
    t.add(k + "com_offset_m", r.tail[i].com_offset_m);
  }
  t.add("friction.mu_s", r.friction.mu_s);
  t.add("friction.mu_d", r.friction.mu_d);
  t.add("friction.phidot_s_radps", r.friction.phidot_s_radps);
  t.add("friction.phidot_d_radps", r.friction.phidot_d_radps);
  t.add("friction.v_s_mps", r.friction.v_s_mps);
  t.add("friction.v_d_mps", r.friction.v_d_mps);
  t.add("gravity_mps2", r.gravity_mps2);
  t.add("joints.size", static_cast<int>(c.joints.size()));
  for (size_t i = 0; i < c.joints.size(); ++i) {
    const std::string k = "joint[" + std::to_string(i) + "].";
    t.add(k + "theta0_rad", c.joints[i].theta0_rad);
    t.add(k + "dtheta_rad", c.joints[i].dtheta_rad);
    t.add(k + "dT_s", c.joints[i].dT_s);
    t.add(k + "w_ss", c.joints[i].w_ss);
    t.add(k + "t0_s", c.joints[i].t0_s);
  }
  std::string models;
  for (const std::string& m : c.models) models += m + ";";
  t.add("models", models);  // after a --models filter: `run X --models analytic` then `run X` computes MuJoCo
  const AnalyticSettings& a = c.analytic;
  t.add("analytic.solver", a.solver);
  t.add("analytic.rel_tol", a.rel_tol);
  t.add("analytic.abs_tol", a.abs_tol);
  t.add("analytic.fixed_dt_s", a.fixed_dt_s);
  t.add("analytic.event_tol_s", a.event_tol_s);
  t.add("analytic.max_step_s", a.max_step_s);
  t.add("analytic.v_stop_mps", a.v_stop_mps);
  t.add("analytic.coupling", static_cast<int>(a.coupling));
  t.add("analytic.max_steps", static_cast<double>(a.max_steps));
  const MujocoSettings& m = c.mujoco;
  t.add("mujoco.timestep_s", m.timestep_s);
  t.add("mujoco.integrator", m.integrator);
  t.add("mujoco.solver", m.solver);
  t.add("mujoco.iterations", m.iterations);
  t.add("mujoco.tolerance", m.tolerance);
  t.add("mujoco.cone", m.cone);
  t.add("mujoco.noslip_iterations", m.noslip_iterations);
  t.add("mujoco.condim", m.condim);
  t.add("mujoco.impratio", m.impratio);
  t.add("mujoco.solref", std::vector<double>(m.solref.begin(), m.solref.end()));
  t.add("mujoco.solimp", std::vector<double>(m.solimp.begin(), m.solimp.end()));
  t.add("mujoco.mu", m.mu);
  t.add("mujoco.kp", m.kp);
  t.add("mujoco.kv", m.kv);
  t.add("mujoco.velocity_feedforward", m.velocity_feedforward);
  t.add("mujoco.inverse_dynamics_feedforward", m.inverse_dynamics_feedforward);
  t.add("mujoco.servo_wn_dt", m.servo_wn_dt);
  t.add("mujoco.body_height_m", m.body_height_m);
  t.add("mujoco.foot_radius_m", m.foot_radius_m);
  t.add("mujoco.settle_s", m.settle_s);
  t.add("mujoco.stop_phidot_radps", m.stop_phidot_radps);
  t.add("mujoco.max_tilt_deg", m.max_tilt_deg);
  t.add("mujoco.max_all_feet_off_s", m.max_all_feet_off_s);
  t.add("mujoco.max_steps", static_cast<double>(m.max_steps));
  const Effects& e = c.effects;
  t.add("effects.friction", static_cast<int>(e.friction));
  t.add("effects.translation", e.translation);
  t.add("effects.gravity", e.gravity);
  t.add("effects.ground_contact", e.ground_contact);
  t.add("effects.foot_loads", static_cast<int>(e.foot_loads));
  t.add("effects.load_decomposition", e.load_decomposition);
  t.add("output.sample_dt_s", c.output.sample_dt_s);
  t.add("output.duration_s", c.output.duration_s);
  t.add("output.settle_s", c.output.settle_s);
  t.add("render", render);  // --no-render: a later run with rendering renders the case
  if (render) {
    const RenderSettings& v = c.render;
    t.add("render.width", v.width);
    t.add("render.height", v.height);
    t.add("render.fps", v.fps);
    t.add("render.slowmo", v.slowmo);
    t.add("render.duration_s", v.duration_s);
    t.add("render.camera", v.camera);
    t.add("render.shadows", v.shadows);
    t.add("render.reflections", v.reflections);
    t.add("render.msaa", v.msaa);
    t.add("render.ghost", v.ghost);
    t.add("render.ffmpeg", v.ffmpeg);
    t.add("render.crf", v.crf);
    t.add("render.preset", v.preset);
  }
  return t.s;
}

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

std::vector<RunResult> runCase(const ExperimentCase& c) {
  std::vector<RunResult> out;
  if (c.kind == "pose") {
    std::vector<JointState> js(c.robot.numLinks());
    for (size_t i = 0; i < js.size(); ++i)
      js[i] = {c.pose.theta_rad.at(i), c.pose.thetadot_radps.at(i), c.pose.thetaddot_radps2.at(i)};
    out.push_back(evaluatePose(c.robot, js, c.effects));
    return out;
  }
  const TailTrajectory traj = c.trajectory();
  for (const std::string& m : c.models) {
    if (m == "analytic") {
      out.push_back(simulateAnalytic(c.robot, traj, c.analytic, c.effects, c.output));
    } else if (m == "mujoco") {
      try {
        out.push_back(simulateMujoco(c.robot, traj, c.mujoco, c.effects, c.output));
      } catch (const std::exception& e) {
        RunResult r;
        r.summary.model = "mujoco";
        r.summary.ok = false;
        r.summary.error = e.what();
        out.push_back(std::move(r));
      }
    }
  }
  return out;
}

namespace {

// One experiment's share of a run: its folder, what is finished, what is left.
struct Job {
  const Experiment* e = nullptr;
  fs::path root;
  bool render = false;
  std::vector<std::string> keys;  // per case: caseKey()
  std::vector<std::string> dirs;  // per case: caseDirName()
  std::vector<json> entries;      // per case; null = not finished
  std::vector<size_t> todo;       // case indices to run now
  int total = 0, resumed = 0;
};

// DIR/.tailsim.lock, flock()ed for the whole run: a second run into the same folder fails at once
// instead of interleaving its writes. The file holds the owner's pid (for the message). The lock
// goes with the process (also on kill -9); the file stays.
class RunLock {
 public:
  explicit RunLock(const fs::path& dir) {
    fs::create_directories(dir);
    const fs::path p = dir / ".tailsim.lock";
    fd_ = ::open(p.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw std::runtime_error("cannot open " + p.string() + ": " + std::strerror(errno));
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      const int err = errno;
      char buf[32] = {};
      const ssize_t n = ::pread(fd_, buf, sizeof buf - 1, 0);
      ::close(fd_);
      if (err != EWOULDBLOCK) throw std::runtime_error("cannot lock " + p.string() + ": " + std::strerror(err));
      std::string pid = n > 0 ? std::string(buf, static_cast<size_t>(n)) : "?";
      while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
      throw std::runtime_error(dir.string() + " is in use by another tailsim run (pid " + pid + ")");
    }
    const std::string me = std::to_string(::getpid()) + "\n";
    if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, me.data(), me.size(), 0) != static_cast<ssize_t>(me.size())) {
      // the pid is only for the message of a second run; the lock itself holds
    }
  }
  ~RunLock() { ::close(fd_); }  // releases the lock
  RunLock(const RunLock&) = delete;
  RunLock& operator=(const RunLock&) = delete;

 private:
  int fd_ = -1;
};

json readJsonFile(const fs::path& p) {
  std::ifstream in(p);
  return json::parse(in, nullptr, false);  // discarded (not an exception) when unreadable
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
  return {};
}

bool holdsResults(const fs::path& root) {
  std::error_code ec;
  return fs::exists(root / "summary.json", ec) || fs::is_directory(root / "cases", ec);
}

// The entries tailsim writes into a result folder (docs/ARCHITECTURE.md); nothing else is touched.
void clearResultFolder(const fs::path& root) {
  for (const char* entry : {"summary.json", "experiment.yaml", "report.md", "cases", "renders", "plots"})
    fs::remove_all(root / entry);
}

// Result folders of experiments inside DIR (a suite's layout: DIR/<experiment>/summary.json).
std::vector<fs::path> memberFolders(const fs::path& root) {
  std::vector<fs::path> out;
  std::error_code ec;
  if (!fs::is_directory(root, ec)) return out;
  for (const auto& d : fs::directory_iterator(root, ec)) {
    const std::string n = d.path().filename().string();
    if (n == "cases" || n == "renders" || n == "plots") continue;
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
  const bool foreign = !name.empty() && (name != e.name || source != e.source_file);
  std::vector<fs::path> members = memberFolders(root);  // a suite's results where one experiment goes
  if (!foreign && members.empty()) return;
  if (!fresh) {
    const std::string what = foreign ? "the results of experiment '" + name + "' (" + source + ")"
                                     : "the results of a suite (" + members.front().string() + ", ...)";
    throw std::runtime_error(root.string() + " holds " + what + ", not of '" + e.name + "' (" + e.source_file +
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

// Temporary files of an earlier run that was killed: "<name>.tmp.<pid>[.<k>][.<ext>]" (atomic
// writes, renders), removed when their pid is no longer running (the run lock already excludes
// a concurrent run; this also spares a concurrent `tailsim plot` or `render`). Only in the
// folders tailsim writes: DIR, DIR/cases/*, DIR/renders, DIR/plots.
int removeStaleTemps(const fs::path& root) {
  // The pid of "<name>.tmp.<pid>[.<k>][.<ext>]" (1-10 digits), or -1 when n is not such a name.
  auto tempPid = [](const std::string& n) -> long {
    const size_t at = n.rfind(".tmp.");
    if (at == std::string::npos || at == 0) return -1;
    size_t i = at + 5, digits = 0;
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
      const long pid = tempPid(n);
      if (pid <= 0 || pid > std::numeric_limits<pid_t>::max()) continue;
      const bool dead = ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
      if ((dead || pid == ::getpid()) && fs::remove(f.path(), ec)) ++removed;
    }
  };
  clean(root);
  clean(root / "renders");
  clean(root / "plots");
  if (fs::is_directory(root / "cases", ec))
    for (const auto& d : fs::directory_iterator(root / "cases", ec))
      if (d.is_directory(ec)) clean(d.path());
  return removed;
}

Job prepare(const Experiment& e, const RunOptions& opt, const fs::path& root) {
  Job job;
  job.e = &e;
  job.root = root;
  std::vector<size_t> todo_all;
  for (size_t i = 0; i < e.cases.size(); ++i)
    if (opt.only_case.empty() || e.cases[i].name == opt.only_case) todo_all.push_back(i);
  job.total = static_cast<int>(todo_all.size());
  // Render prerequisites are checked before anything runs (issue 5).
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
  fs::create_directories(root / "cases");
  writeFileAtomic((root / "experiment.yaml").string(), readText(e.source_file));
  if (job.render) checkRenderPrerequisites(e.cases.front().render, (root / "renders").string());
  job.entries.resize(e.cases.size());
  for (size_t i : todo_all) {  // finished cases of an earlier, interrupted run
    const fs::path rj = root / "cases" / job.dirs[i] / "result.json";
    if (opt.resume && fs::exists(rj)) {
      json j = readJsonFile(rj);
      // A case is reused only when everything its results depend on is unchanged (caseKey).
      if (j.is_object() && j.value("key", std::string()) == job.keys[i] &&
          j.value("name", std::string()) == e.cases[i].name) {
        job.entries[i] = std::move(j);
        ++job.resumed;
        continue;
      }
    }
    job.todo.push_back(i);
  }
  return job;
}

// Runs one case and writes its folder; result.json last, as the "finished" marker.
json runAndWrite(const Job& job, size_t i, int& failed_runs) {
  const ExperimentCase& c = job.e->cases[i];
  const std::vector<RunResult> runs = runCase(c);
  const fs::path dir = job.root / "cases" / job.dirs[i];
  fs::create_directories(dir);
  json j;
  j["name"] = c.name;
  j["dir"] = job.dirs[i];
  j["experiment"] = job.e->name;
  j["source"] = job.e->source_file;
  j["key"] = job.keys[i];
  j["sweep"] = json::object();
  for (const auto& [key, v] : c.sweep_values) j["sweep"][key] = v;
  j["runs"] = json::object();
  for (const RunResult& r : runs) {
    writeCsvAtomic((dir / (r.summary.model + ".csv")).string(), r.series);
    j["runs"][r.summary.model] = summaryJson(r.summary);
    if (!r.summary.ok) ++failed_runs;
  }
  if (job.render) renderCase(c, runs, (job.root / "renders").string());
  writeFileAtomic((dir / "result.json").string(), j.dump(1));
  return j;
}

void writeSummary(const Job& job) {
  const Experiment& e = *job.e;
  json s;
  s["experiment"] = e.name;
  s["tailsim_version"] = kVersion;
  if (*kGitCommit) s["tailsim_git_commit"] = kGitCommit;
  s["description"] = e.description;
  s["source"] = e.source_file;
  s["kind"] = e.cases.empty() ? "simulate" : e.cases.front().kind;
  s["swept_keys"] = e.swept_keys;
  s["cases"] = json::array();
  for (json entry : job.entries)
    if (!entry.is_null()) {
      entry.erase("experiment");  // said once, above
      entry.erase("source");
      s["cases"].push_back(std::move(entry));
    }
  writeFileAtomic((job.root / "summary.json").string(), s.dump(1));
}

// All cases of all experiments share one pool of workers (workers share nothing mutable but
// the task counter; each writes only its own case folder and entry).
RunStats runJobs(std::vector<Job>& jobs, const RunOptions& opt, const std::string& label) {
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
      return std::find(m.begin(), m.end(), "mujoco") != m.end();
    };
    return heavy(a) && !heavy(b);
  });

  // Ctrl-C (opt.stop_on_sigint): SIGINT is blocked in this thread before the workers start (they
  // inherit the mask, and so do ffmpeg/gnuplot children), and taken here with sigtimedwait: no
  // handler, no global flag. The first stops new cases, the in-flight ones finish and are saved; a
  // second terminates the process at once (finished cases stay saved: each is written whole).
  sigset_t int_set, old_mask;
  sigemptyset(&int_set);
  sigaddset(&int_set, SIGINT);
  if (opt.stop_on_sigint) pthread_sigmask(SIG_BLOCK, &int_set, &old_mask);

  std::atomic<size_t> next{0};
  std::atomic<int> done{0}, failed{0}, running{0};
  std::atomic<bool> stop{false};
  std::mutex mu;
  std::condition_variable cv;
  std::string first_error;
  auto worker = [&]() {
    for (;;) {
      if (stop.load()) break;
      const size_t k = next.fetch_add(1);
      if (k >= tasks.size()) break;
      const Task& t = tasks[k];
      try {
        int f = 0;
        json j = runAndWrite(*t.job, t.i, f);
        failed += f;
        t.job->entries[t.i] = std::move(j);  // distinct element per task: no lock needed
      } catch (const std::exception& ex) {
        // A full disk fails every case after it: stop starting new ones (issue 16, finding 4).
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
      ++done;
      cv.notify_all();
    }
    std::lock_guard<std::mutex> lock(mu);
    --running;
    cv.notify_all();
  };
  const int n_threads = std::max(1, std::min<int>(opt.threads > 0 ? opt.threads : std::thread::hardware_concurrency(),
                                                  static_cast<int>(tasks.size())));
  std::vector<std::thread> pool;
  for (int t = 0; t < n_threads && !tasks.empty(); ++t) {
    ++running;
    pool.emplace_back(worker);
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
    {
      std::unique_lock<std::mutex> lock(mu);
      if (running.load() == 0) break;
      if (!opt.stop_on_sigint) cv.wait_for(lock, std::chrono::milliseconds(100));
    }
    if (opt.stop_on_sigint) {
      const timespec wait{0, 100 * 1000 * 1000};
      if (sigtimedwait(&int_set, nullptr, &wait) == SIGINT) {
        if (line_open) std::fprintf(stderr, "\n");
        line_open = false;
        if (!stop.exchange(true)) {
          const int in_flight = static_cast<int>(std::min(next.load(), tasks.size())) - done.load();
          std::fprintf(stderr, "interrupted: finishing %d running case%s (Ctrl-C again to abandon %s)\n", in_flight,
                       in_flight == 1 ? "" : "s", in_flight == 1 ? "it" : "them");
        } else {
          std::fprintf(stderr, "interrupted again: abandoning the running cases; %d cases saved\n",
                       done.load() + stats.resumed);
          std::signal(SIGINT, SIG_DFL);
          pthread_sigmask(SIG_SETMASK, &old_mask, nullptr);
          std::raise(SIGINT);  // terminates: the shell sees "killed by SIGINT"
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
  try {
    for (const Job& job : jobs) writeSummary(job);  // also after a failure: finished cases count
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

RunStats runExperiment(const Experiment& e, const RunOptions& opt) {
  if (opt.resume) claimFolder(e, opt.out_dir, false);  // refuse before the lock file is created
  const RunLock lock(opt.out_dir);
  std::vector<Job> jobs{prepare(e, opt, opt.out_dir)};
  if (jobs.front().total == 0) throw std::runtime_error("experiment " + e.name + " has no case named '" + opt.only_case + "'");
  return runJobs(jobs, opt, e.name);
}

RunStats runSuite(const std::vector<Experiment>& suite, const RunOptions& opt) {
  if (suite.size() == 1) return runExperiment(suite.front(), opt);
  if (opt.resume) {  // refuse before the lock file is created
    claimSuiteFolder(opt.out_dir, false);
    for (const Experiment& e : suite) claimFolder(e, fs::path(opt.out_dir) / e.name, false);
  }
  const RunLock lock(opt.out_dir);  // one lock for the suite's folder and its members
  claimSuiteFolder(opt.out_dir, !opt.resume);
  std::vector<Job> jobs;
  for (const Experiment& e : suite) jobs.push_back(prepare(e, opt, fs::path(opt.out_dir) / e.name));
  return runJobs(jobs, opt, fs::path(opt.out_dir).filename().string());
}

}  // namespace tailsim
