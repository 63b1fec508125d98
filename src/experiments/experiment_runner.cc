#include "experiments/experiment_runner.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <condition_variable>
#include <cstdio>
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

// Identifies the configuration a finished case was computed from: a resumed case must come
// from the same experiment text (and robot file), else it is recomputed.
std::string fingerprint(const Experiment& e) {
  std::string text = readText(e.source_file);
  if (!e.cases.empty()) text += readText(e.cases.front().robot_file);
  return std::to_string(std::hash<std::string>{}(text));
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

std::string caseDirName(const std::string& name) {
  std::string d;
  for (char ch : name) d += (std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' || ch == '-' || ch == '=' ||
                             ch == ',' || ch == '_') ? ch : '_';
  return d.empty() ? "base" : d;
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
  std::string fp;
  bool render = false;
  std::vector<json> entries;  // per case; null = not finished
  std::vector<size_t> todo;   // case indices to run now
  int total = 0, resumed = 0;
};

Job prepare(const Experiment& e, const RunOptions& opt, const fs::path& root) {
  Job job;
  job.e = &e;
  job.root = root;
  std::vector<size_t> todo_all;
  for (size_t i = 0; i < e.cases.size(); ++i)
    if (opt.only_case.empty() || e.cases[i].name == opt.only_case) todo_all.push_back(i);
  job.total = static_cast<int>(todo_all.size());
  fs::create_directories(root / "cases");
  writeFileAtomic((root / "experiment.yaml").string(), readText(e.source_file));
  job.fp = fingerprint(e);
  // Render prerequisites are checked before anything runs (issue 5).
  job.render = opt.render && !e.cases.empty() && e.cases.front().render.enabled;
  if (job.render) checkRenderPrerequisites(e.cases.front().render, (root / "renders").string());
  job.entries.resize(e.cases.size());
  for (size_t i : todo_all) {  // finished cases of an earlier, interrupted run
    const fs::path rj = root / "cases" / caseDirName(e.cases[i].name) / "result.json";
    if (opt.resume && fs::exists(rj)) {
      try {
        std::ifstream in(rj);
        json j = json::parse(in);
        if (j.value("fingerprint", std::string()) == job.fp && j.value("name", std::string()) == e.cases[i].name) {
          job.entries[i] = std::move(j);
          ++job.resumed;
          continue;
        }
      } catch (const std::exception&) {
        // unreadable: recompute
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
  const fs::path dir = job.root / "cases" / caseDirName(c.name);
  fs::create_directories(dir);
  json j;
  j["name"] = c.name;
  j["dir"] = caseDirName(c.name);
  j["fingerprint"] = job.fp;
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
  for (const json& entry : job.entries)
    if (!entry.is_null()) s["cases"].push_back(entry);
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
  std::vector<Job> jobs{prepare(e, opt, opt.out_dir)};
  if (jobs.front().total == 0) throw std::runtime_error("experiment " + e.name + " has no case named '" + opt.only_case + "'");
  return runJobs(jobs, opt, e.name);
}

RunStats runSuite(const std::vector<Experiment>& suite, const RunOptions& opt) {
  if (suite.size() == 1) return runExperiment(suite.front(), opt);
  std::vector<Job> jobs;
  for (const Experiment& e : suite) jobs.push_back(prepare(e, opt, fs::path(opt.out_dir) / e.name));
  return runJobs(jobs, opt, fs::path(opt.out_dir).filename().string());
}

}  // namespace tailsim
