#include "experiments/run_job.h"

#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <sys/eventfd.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <csignal>
#include <thread>
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

#include "experiments/work_estimate.h"
#include "common/atomic_file.h"
#include "common/work_limits.h"

namespace tailsim {
namespace fs = std::filesystem;
using json = nlohmann::json;
namespace runner {
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

// A task: case i of a job.
struct Task {
  Job* job;
  size_t i;
};

// Stage 1: the cases to run now (at most opt.max_new_cases), MuJoCo cases first; the jobs' totals
// and resumed cases counted into stats.
std::vector<Task> collectTasks(std::vector<Job>& jobs, const RunOptions& opt, RunStats& stats) {
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
  return tasks;
}

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
struct RunWakeups {
  // Stage 2: the stop signals blocked (with stop_on_sigint) and the signalfd and eventfd created;
  // on failure the signal mask is restored and std::system_error thrown.
  explicit RunWakeups(bool block_signals) : stop_on_sigint(block_signals) {
    sigemptyset(&int_set);
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&int_set, sig);
    if (stop_on_sigint) pthread_sigmask(SIG_BLOCK, &int_set, &old_mask);
    sig_fd.fd = stop_on_sigint ? ::signalfd(-1, &int_set, SFD_CLOEXEC | SFD_NONBLOCK) : -1;
    wake_fd.fd = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if ((stop_on_sigint && sig_fd.fd < 0) || wake_fd.fd < 0) {
      if (stop_on_sigint) pthread_sigmask(SIG_SETMASK, &old_mask, nullptr);
      throw std::system_error(errno, std::generic_category(), "cannot create the run's signalfd/eventfd");
    }
  }
  // The signal mask as it was before the run.
  void restoreMask() const { pthread_sigmask(SIG_SETMASK, &old_mask, nullptr); }
  // A worker's exit, told to the main thread.
  void wakeMain() const {
    const uint64_t one = 1;
    while (::write(wake_fd.fd, &one, sizeof one) < 0 && errno == EINTR) {
    }
  }

  bool stop_on_sigint;
  sigset_t int_set, old_mask;
  PollFd sig_fd{-1};
  PollFd wake_fd{-1};
};

// What the workers share: the task counter, the counts, the stop flag, the first error and the
// caches of the run (workers share nothing else mutable; each writes only its own case folder and
// entry).
struct WorkerPool {
  WorkerPool(const std::vector<Task>& t, const RunWakeups& w) : tasks(t), wake(w) {}
  const std::vector<Task>& tasks;
  const RunWakeups& wake;
  std::atomic<size_t> next{0};
  std::atomic<int> done{0}, failed{0}, running{0};
  std::atomic<bool> stop{false};
  std::mutex mu;
  std::string first_error;
  RunContext ctx;  // shared by the workers: the MuJoCo pre-roll once per distinct model
};

// The message for a case that ran out of memory: its series as held while it runs, rows x columns
// x 8 B a value, per model (a lower bound).
std::string outOfMemoryError(const ExperimentCase& c) {
  char mb[32];
  std::snprintf(mb, sizeof mb, "%.0f",
                estimateWork(c).csv_bytes / limits::kCsvBytesPerValue * 8.0 * static_cast<double>(c.models.size()) / 1e6);
  return "case " + c.name + ": out of memory while running it (each running case holds its time series in "
         "memory, at least about " + mb + " MB for this one, one case per thread): use fewer --threads, "
         "raise output.sample_dt_s or set output.time_series: thin or none; no further case was started, "
         "the finished ones are saved (run the same command again to resume)";
}

// One case on a worker thread (runAndWrite): its entry kept; out of memory or a full disk stops
// the run; the first error is kept for the end of the run.
void runTask(WorkerPool& p, const Task& t) {
  try {
    int f = 0;
    std::string entry = runAndWrite(*t.job, t.i, f, p.ctx);
    p.failed += f;
    t.job->entries[t.i] = std::move(entry);  // distinct element per task: no lock needed
    if (inH5(t.job->e->cases[t.i])) t.job->h5_from[t.i] = kH5Part;
  } catch (const std::bad_alloc&) {
    // Out of memory: every case holds its series in memory while it runs; start no more.
    p.stop = true;
    std::lock_guard<std::mutex> lock(p.mu);
    if (p.first_error.empty()) p.first_error = outOfMemoryError(t.job->e->cases[t.i]);
  } catch (const std::exception& ex) {
    // A full disk fails every case after it: stop starting new ones.
    const auto* sys = dynamic_cast<const std::system_error*>(&ex);
    const bool disk_full = sys && sys->code() == std::errc::no_space_on_device;
    if (disk_full) p.stop = true;
    std::lock_guard<std::mutex> lock(p.mu);
    if (p.first_error.empty())
      p.first_error = "case " + t.job->e->cases[t.i].name + ": " + ex.what() +
                      (disk_full ? " (the disk is full: no further case was started; free space and run the "
                                   "same command again to resume)"
                                 : "");
  }
}

// A worker thread: the next task until none is left or the run stops; then it tells the main thread.
void workerLoop(WorkerPool& p) {
  for (;;) {
    if (p.stop.load()) break;
    const size_t k = p.next.fetch_add(1);
    if (k >= p.tasks.size()) break;
    runTask(p, p.tasks[k]);
    ++p.done;  // (no wake-up per case: a syscall and a context switch each)
  }
  {
    std::lock_guard<std::mutex> lock(p.mu);
    --p.running;
  }
  p.wake.wakeMain();
}

// Stage 3: the worker threads, as many as asked (at most one per task); fewer when the system
// refuses more, and none: an error (the signal mask restored).
std::vector<std::thread> startWorkers(WorkerPool& p, const RunOptions& opt) {
  const int n_threads = std::max(1, std::min<int>(opt.threads > 0 ? opt.threads : std::thread::hardware_concurrency(),
                                                  static_cast<int>(p.tasks.size())));
  std::vector<std::thread> pool;
  for (int t = 0; t < n_threads && !p.tasks.empty(); ++t) {
    ++p.running;
    try {
      pool.emplace_back(workerLoop, std::ref(p));
    } catch (const std::system_error& ex) {  // out of threads or memory (ulimit -u, -v; cgroup pids.max)
      --p.running;
      if (pool.empty()) {
        if (opt.stop_on_sigint) p.wake.restoreMask();
        throw std::runtime_error(std::string("cannot start a worker thread (") + ex.what() +
                                 "): the process limits (ulimit -u, ulimit -v) leave no room for one; no case was run");
      }
      std::fprintf(stderr, "note: started %zu of %d worker threads (%s); running on %zu\n", pool.size(), n_threads,
                   ex.what(), pool.size());
      break;
    }
  }
  return pool;
}

// Progress: on a terminal one line redrawn with \r; in a log (not a TTY) a plain line every
// few seconds, so the log is readable and not flooded.
class ProgressLine {
 public:
  ProgressLine(const RunOptions& opt, const std::string& label, size_t n_tasks, const RunStats& stats,
               std::chrono::steady_clock::time_point wall0)
      : show(opt.progress && n_tasks > 0), period(tty_ ? std::chrono::milliseconds(500) : std::chrono::milliseconds(5000)),
        label_(label), n_tasks_(n_tasks), stats_(stats), wall0_(wall0), last_print_(wall0) {}

  // The line for `done` cases run now: at most once per period and only when it changed, unless final.
  void print(int d, bool final_line) {
    const auto now = std::chrono::steady_clock::now();
    if (!final_line && (d == shown_ || now - last_print_ < period)) return;
    shown_ = d;
    last_print_ = now;
    const double el = std::chrono::duration<double>(now - wall0_).count();
    const double eta = d > 0 ? el / d * (n_tasks_ - d) : 0.0;
    char line[256];
    std::snprintf(line, sizeof line, "[%s] %d/%d cases (%d resumed), %s elapsed", label_.c_str(), d + stats_.resumed,
                  stats_.total, stats_.resumed, fmtSeconds(el).c_str());
    const std::string eta_s = final_line ? std::string() : ", ETA " + fmtSeconds(eta);
    if (tty_) {
      std::fprintf(stderr, "\r%s%s   ", line, eta_s.c_str());
      line_open_ = true;
      if (final_line) {
        std::fprintf(stderr, "\n");
        line_open_ = false;
      }
    } else {
      std::fprintf(stderr, "%s%s\n", line, eta_s.c_str());
    }
    std::fflush(stderr);
  }
  // Ends a \r line on screen, if any, before another message.
  void endLine() {
    if (line_open_) std::fprintf(stderr, "\n");
    line_open_ = false;
  }

 private:
  const bool tty_ = ::isatty(STDERR_FILENO) == 1;

 public:
  const bool show;
  const std::chrono::milliseconds period;

 private:
  std::string label_;
  size_t n_tasks_;
  const RunStats& stats_;
  std::chrono::steady_clock::time_point wall0_;
  bool line_open_ = false;  // a \r line is on screen
  int shown_ = -1;
  std::chrono::steady_clock::time_point last_print_;
};

// A stop signal read from the signalfd: the first stops new cases (stop_signal set), a second
// terminates the process at once by that signal.
void onStopSignal(WorkerPool& p, const RunWakeups& w, ProgressLine& progress, int resumed, int& stop_signal) {
  signalfd_siginfo info{};
  if (::read(w.sig_fd.fd, &info, sizeof info) != static_cast<ssize_t>(sizeof info)) return;
  const int sig = static_cast<int>(info.ssi_signo);
  const std::string sig_name = sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP" : "Ctrl-C";
  const std::string by = sig == SIGINT ? "" : " by " + sig_name;
  progress.endLine();
  if (!p.stop.exchange(true)) {
    stop_signal = sig;
    const int in_flight = static_cast<int>(std::min(p.next.load(), p.tasks.size())) - p.done.load();
    std::fprintf(stderr, "interrupted%s: finishing %d running case%s (%s again to abandon %s)\n", by.c_str(),
                 in_flight, in_flight == 1 ? "" : "s", sig_name.c_str(), in_flight == 1 ? "it" : "them");
  } else {
    // Finished cases stay resumable: their result.json / cases.jsonl line is on disk, their
    // HDF5 groups in DIR/time_series.h5.d; a case still being written runs again.
    std::fprintf(stderr, "interrupted again: abandoning the running cases; %d cases saved\n", p.done.load() + resumed);
    std::signal(sig, SIG_DFL);
    w.restoreMask();
    std::raise(sig);  // terminates: the shell sees "killed by <signal>"
  }
}

// Stage 4: the main thread waits until every worker has exited, woken by a worker's exit, a stop
// signal, the progress period or should_stop's 200 ms; returns the signal that stopped the run (0: none).
int superviseWorkers(WorkerPool& p, const RunOptions& opt, const RunWakeups& w, ProgressLine& progress, int resumed) {
  int stop_signal = 0;
  for (;;) {
    if (p.running.load() == 0) break;
    pollfd fds[2] = {{w.wake_fd.fd, POLLIN, 0}, {w.sig_fd.fd, POLLIN, 0}};
    const int n_fds = opt.stop_on_sigint ? 2 : 1;
    int timeout_ms = progress.show ? static_cast<int>(progress.period.count()) : -1;
    if (opt.should_stop) timeout_ms = timeout_ms < 0 ? 200 : std::min(timeout_ms, 200);
    if (::poll(fds, n_fds, timeout_ms) > 0) {
      uint64_t count = 0;
      if (fds[0].revents & POLLIN) (void)!::read(w.wake_fd.fd, &count, sizeof count);
    }
    if (opt.should_stop && !p.stop.load() && opt.should_stop()) p.stop = true;
    if (opt.stop_on_sigint && (fds[1].revents & POLLIN)) onStopSignal(p, w, progress, resumed, stop_signal);
    if (progress.show) progress.print(p.done.load(), false);
  }
  return stop_signal;
}

// Stage 5: every job's summary.json and results.csv (also after a failure: finished cases count),
// the suite's results.csv, the manifests compacted; a case's error wins over the summary's (a full
// disk fails the summary too).
void writeSummaries(std::vector<Job>& jobs, const fs::path& suite_root, const std::string& first_error) {
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
}

}  // namespace

// All cases of all experiments share one pool of workers (workers share nothing mutable but
// the task counter; each writes only its own case folder and entry).
// suite_root: a suite's folder, which gets the results.csv of all members.
RunStats runJobs(std::vector<Job>& jobs, const RunOptions& opt, const std::string& label,
                 const fs::path& suite_root) {
  const auto wall0 = std::chrono::steady_clock::now();
  RunStats stats;
  const std::vector<Task> tasks = collectTasks(jobs, opt, stats);
  const RunWakeups wake(opt.stop_on_sigint);
  WorkerPool workers(tasks, wake);
  std::vector<std::thread> pool = startWorkers(workers, opt);
  ProgressLine progress(opt, label, tasks.size(), stats, wall0);
  const int stop_signal = superviseWorkers(workers, opt, wake, progress, stats.resumed);
  for (auto& th : pool) th.join();
  if (opt.stop_on_sigint) wake.restoreMask();
  if (progress.show) progress.print(workers.done.load(), true);
  else progress.endLine();
  stats.interrupted = workers.stop.load();
  stats.stop_signal = stop_signal;
  writeSummaries(jobs, suite_root, workers.first_error);  // Stage 5
  if (!workers.first_error.empty()) throw std::runtime_error(workers.first_error);
  stats.ran = workers.done.load();
  stats.failed = workers.failed.load();
  stats.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return stats;
}

}  // namespace runner
}  // namespace tailsim
