// Work and resources bounded before anything runs, for the run command: a whole sweep's steps and
// output (not only each case's), the worker threads, and doubtful strokes flagged in the result.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>

#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "experiments/yaml_file.h"
#include "common/work_limits.h"

namespace tailsim {
namespace {

namespace fs = std::filesystem;

class InputLimits : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string tmpl = (fs::temp_directory_path() / "tailsim_input_limits_XXXXXX").string();
    ASSERT_NE(mkdtemp(tmpl.data()), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string write(const std::string& rel, const std::string& text) {
    const fs::path p = dir_ / rel;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }
  std::string errorOf(const std::string& path) {
    try {
      loadExperiment(path);
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "(no error)";
  }
  fs::path dir_;
};

using UnboundedWorkRefusedAtLoad = InputLimits;
using CrashesInsteadOfErrors = InputLimits;
using Smaller = InputLimits;

// Every case within its own limits, the sweep over the whole-experiment limits: refused at load
// with the estimate (this file was accepted and projected to write 26 TB).
TEST_F(UnboundedWorkRefusedAtLoad, WholeSweepOutputIsBounded) {
  const std::string f = write("big.yaml",
                              "name: big\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\nmodels: [analytic]\n"
                              "output: {duration_s: 90, sample_dt_s: 0.0001}\n"
                              "quadruped: {d_Q2B_m: {range: [0.1, 0.2, 0.0002]}}\n");
  const std::string e = errorOf(f);
  EXPECT_EQ(e.rfind(f + ":1:1: the 501 cases would write about ", 0), 0u) << e;
  EXPECT_NE(e.find("bytes of time series in all"), std::string::npos) << e;
  EXPECT_NE(e.find("more than the limit 1e+11"), std::string::npos) << e;
  // The same sweep without time series writes its table only and loads.
  const std::string g = write("none.yaml",
                              "name: none\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\nmodels: [analytic]\n"
                              "output: {duration_s: 90, sample_dt_s: 0.0001, time_series: none}\n"
                              "quadruped: {d_Q2B_m: {range: [0.1, 0.2, 0.0002]}}\n");
  EXPECT_EQ(errorOf(g), "(no error)");
}

// The rendering of a whole sweep is bounded too: frames x pixels x MSAA summed over the cases (this
// 981-case file was accepted and started: about 2 x 10^7 frames of 67 Mpixel).
TEST_F(UnboundedWorkRefusedAtLoad, WholeSweepRenderingIsBounded) {
  const std::string sweep = "name: r\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25, w_ss: {range: [0.01, 0.99, 0.001]}}\n"
                            "models: [mujoco]\noutput: {time_series: none}\n";
  const std::string f = write("rend.yaml", sweep + "render: {width: 8192, height: 8192, fps: 240, slowmo: 160, msaa: 4}\n");
  const std::string e = errorOf(f);
  EXPECT_EQ(e.rfind(f + ":1:1: the 981 cases would render about ", 0), 0u) << e;
  EXPECT_NE(e.find("samples in all (frames x render.width x render.height x render.msaa"), std::string::npos) << e;
  EXPECT_NE(e.find("more than the limit 1e+12"), std::string::npos) << e;
  // The same sweep at the default frame size, rate and MSAA loads.
  EXPECT_EQ(errorOf(write("small.yaml", sweep + "render: {width: 640, height: 480}\n")), "(no error)");
}

// A video replays whichever model ran: an analytic-only sweep's rendering is bounded
// the same way (this file, models [analytic], was accepted and started 981 renders of 8192 x 8192).
TEST_F(UnboundedWorkRefusedAtLoad, WholeSweepRenderingIsBoundedForEveryModel) {
  for (const std::string models : {"[analytic]", "[analytic, perfoot]"}) {
    const std::string f =
        write("rend_a.yaml", "name: r\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25, w_ss: {range: [0.01, 0.99, "
                             "0.001]}}\nmodels: " + models + "\noutput: {time_series: none}\n"
                             "render: {width: 8192, height: 8192, fps: 240, slowmo: 160, msaa: 4}\n");
    const std::string e = errorOf(f);
    EXPECT_EQ(e.rfind(f + ":1:1: the 981 cases would render about ", 0), 0u) << models << ": " << e;
    EXPECT_NE(e.find("more than the limit 1e+12"), std::string::npos) << models << ": " << e;
  }
}

// The solver steps of a whole sweep are bounded too.
TEST_F(UnboundedWorkRefusedAtLoad, WholeSweepStepsAreBounded) {
  const std::string f = write("steps.yaml",
                              "name: steps\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\nmodels: [mujoco]\n"
                              "output: {duration_s: 100, sample_dt_s: 0.01, time_series: none}\n"
                              "mujoco: {timestep_s: 0.00002}\n"
                              "quadruped: {d_Q2B_m: {range: [0.1, 0.2, 0.00004]}}\n");
  const std::string e = errorOf(f);
  EXPECT_EQ(e.rfind(f + ":1:1: the 2501 cases would take about ", 0), 0u) << e;
  EXPECT_NE(e.find("solver steps in all"), std::string::npos) << e;
}

// A suite's members are bounded together: each below the whole-experiment limits, two of them over
// (a 60-member suite of 98,010-case experiments, 5.9 million cases, loaded for over a minute and
// 1.4 GB before anything was said).
TEST_F(UnboundedWorkRefusedAtLoad, SuiteMembersAreBoundedTogether) {
  auto member = [&](const std::string& name) {
    return write(name + ".yaml", "name: " + name + "\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\nmodels: [mujoco]\n"
                                 "output: {duration_s: 100, sample_dt_s: 0.01, time_series: none}\n"
                                 "mujoco: {timestep_s: 0.00002}\nquadruped: {d_Q2B_m: {range: [0.1, 0.148, 0.00004]}}\n");
  };
  EXPECT_EQ(errorOf(member("m1")), "(no error)");  // about 6e9 steps: within 1e10 alone
  member("m2");
  const std::string suite = write("suite.yaml", "experiments: [m1.yaml, m2.yaml]\n");
  std::string e = "(no error)";
  try {
    loadExperimentSuite(suite);
  } catch (const ConfigError& x) {
    e = x.what();
  }
  EXPECT_EQ(e.rfind(suite + ":1:24: experiments[1]: the suite's ", 0), 0u) << e;
  EXPECT_NE(e.find(" cases up to this experiment would take about "), std::string::npos) << e;
  EXPECT_NE(e.find("more than the limit 1e+10"), std::string::npos) << e;
}

// A render of a case whose models the renderer cannot draw (per-foot only) was accepted and failed
// after the run ("nothing to render (no model ran)"): refused at load, at the render section.
TEST_F(Smaller, RenderNeedsAModelItDraws) {
  const std::string f = write("pf.yaml", "name: pf\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\n"
                                         "models: [perfoot]\nrender: {width: 64, height: 48}\n");
  const std::string e = errorOf(f);
  EXPECT_EQ(e.rfind(f + ":5:", 0), 0u) << e;
  EXPECT_NE(e.find("render: a video needs the analytic or mujoco model"), std::string::npos) << e;
  EXPECT_EQ(errorOf(write("a.yaml", "name: a\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\n"
                                    "models: [perfoot, analytic]\nrender: {width: 64, height: 48}\n")),
            "(no error)");
}

// A NUL byte was reported by yaml-cpp as a bad escape or hex number somewhere else in the file: it
// is named at its own line and column, for every file kind (experiments and the files read
// through loadBoundedYaml: optimize, maneuver, robot compare).
TEST_F(Smaller, NulByteIsNamedAtItsPlace) {
  using namespace std::string_literals;  // the literals hold NUL bytes
  const std::string text = "name: o\0x\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\n"s;
  const std::string f = write("nul.yaml", text);
  EXPECT_EQ(errorOf(f), f + ":1:8: a NUL byte (0x00): the file is not text");
  std::string e = "(no error)";
  try {
    loadBoundedYaml(f);
  } catch (const ConfigError& x) {
    e = x.what();
  }
  EXPECT_EQ(e, f + ":1:8: a NUL byte (0x00): the file is not text");
  const std::string g = write("nul_end.yaml", "name: t\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\n  \0\0"s);
  EXPECT_EQ(errorOf(g), g + ":4:3: a NUL byte (0x00): the file is not text");
}

// threads is bounded before any work (the CLI's --threads and tailsim.run(threads=...) alike).
TEST_F(CrashesInsteadOfErrors, ThreadsAreBoundedBeforeAnyWork) {
  const Experiment e = loadExperimentText("name: t\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\n"
                                          "models: [analytic]\n",
                                          "t.yaml");
  RunOptions o;
  o.out_dir = (dir_ / "out").string();
  o.progress = false;
  for (const int n : {-1, limits::kMaxThreads + 1, 100000}) {
    o.threads = n;
    EXPECT_THROW(runExperiment(e, o), std::invalid_argument) << n;
    EXPECT_FALSE(fs::exists(dir_ / "out")) << n;
  }
}

// A thread the system refuses to start (address space or process limit) is an error or fewer
// workers, not std::terminate: run in a child with little address space left.
TEST_F(CrashesInsteadOfErrors, ThreadCreationFailureIsNotAnAbort) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer cannot run under the address-space limit this test sets";
#endif
  const Experiment e = loadExperiment(write("t.yaml", "name: t\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\n"
                                                     "models: [analytic]\noutput: {time_series: none}\n"
                                                     "quadruped: {d_Q2B_m: {range: [0.1, 0.2, 0.0015625]}}\n"));
  const std::string out = (dir_ / "out").string();
  std::fflush(nullptr);
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    // The address space in use now plus 40 MB: room for the run, not for 64 thread stacks of 8 MB.
    long pages = 0;
    if (FILE* f = std::fopen("/proc/self/statm", "r")) {
      if (std::fscanf(f, "%ld", &pages) != 1) pages = 0;
      std::fclose(f);
    }
    const rlim_t as = static_cast<rlim_t>(pages) * static_cast<rlim_t>(sysconf(_SC_PAGESIZE)) + (40u << 20);
    const rlimit lim{as, as};
    if (pages == 0 || setrlimit(RLIMIT_AS, &lim) != 0) _exit(2);
    int code = 0;
    try {
      RunOptions o;
      o.out_dir = out;
      o.progress = false;
      o.threads = 64;
      runExperiment(e, o);
    } catch (const std::exception& ex) {
      code = std::string(ex.what()).find("cannot start a worker thread") != std::string::npos ? 3 : 4;
      if (code == 4) std::fprintf(stderr, "%s\n", ex.what());
    }
    _exit(code);
  }
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  EXPECT_TRUE(WEXITSTATUS(status) == 0 || WEXITSTATUS(status) == 3) << WEXITSTATUS(status);
}

// (a) A stroke faster than any tail motor (-3600 deg in 1 ms: 7.2e6 deg/s) is run but flagged.
TEST_F(Smaller, ImplausibleJointSpeedWarns) {
  const Experiment fast = loadExperimentText("name: f\nrobot: paper\ntrajectory: {dtheta_deg: -3600, dT_s: 0.001}\n"
                                             "models: [analytic, perfoot]\n",
                                             "f.yaml");
  for (const RunResult& r : runCase(fast.cases.at(0))) {
    bool warned = false;
    for (const std::string& w : r.summary.warnings)
      warned = warned || w.find("tail joint 1 peaks at 7.2e+06 deg/s, above 3.6e+04 deg/s") != std::string::npos;
    EXPECT_TRUE(warned) << r.summary.model;
  }
  const Experiment paper = loadExperimentText("name: p\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\n"
                                              "models: [analytic]\n",
                                              "p.yaml");
  for (const RunResult& r : runCase(paper.cases.at(0)))
    for (const std::string& w : r.summary.warnings) EXPECT_EQ(w.find("peaks at"), std::string::npos) << w;
}

// (f) An empty --out and an empty or comment-only experiment file: errors in tailsim's words, the
// file's with its location (the loader's "the file must be a map" had none; --out "" reached the
// filesystem library).
TEST_F(Smaller, EmptyFilesAndEmptyOutAreRefusedInTailsimsWords) {
  const std::string bin = std::string(TAILSIM_BINARY_DIR) + "/tailsim";
  auto run = [](const std::string& cmd, std::string& out) {
    std::unique_ptr<FILE, int (*)(FILE*)> p(popen((cmd + " 2>&1").c_str(), "r"), pclose);
    char buf[4096];
    std::size_t k;
    while ((k = fread(buf, 1, sizeof buf, p.get())) > 0) out.append(buf, k);
    const int rc = pclose(p.release());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  };
  const std::string good = write("good.yaml", "name: g\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\n");
  std::string out;
  EXPECT_EQ(run(bin + " run " + good + " --out ''", out), 2) << out;
  EXPECT_EQ(out.rfind("--out: is empty: give a folder or file name", 0), 0u) << out;
  for (const std::string& text : {std::string(""), std::string("# nothing here\n\n")}) {
    const std::string f = write("empty.yaml", text);
    out.clear();
    EXPECT_EQ(run(bin + " run " + f + " --out " + (dir_ / "o").string(), out), 1) << out;
    EXPECT_EQ(out.rfind("error: " + f + ":1:1: the file holds no YAML value (it is empty or only comments)", 0), 0u) << out;
    EXPECT_FALSE(fs::exists(dir_ / "o"));
  }
}

// (c) A render at the documented maximum: msaa above 4 was accepted and rendered with 4 (llvmpipe's
// GL_MAX_SAMPLES) or failed late with a GL status code; refused at load with the key.
TEST_F(Smaller, RenderMsaaIsBoundedToWhatTheGlSupports) {
  const std::string f = write("r.yaml", "name: r\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\n"
                                        "models: [mujoco]\nrender: {width: 8192, height: 8192, msaa: 16}\n");
  const std::string e = errorOf(f);
  EXPECT_EQ(e.rfind(f + ":5:43: render.msaa: must be in 0..4", 0), 0u) << e;
  const std::string g = write("g.yaml", "name: g\nrobot: paper\ntrajectory: {dtheta_deg: -90, dT_s: 0.25}\n"
                                        "models: [mujoco]\nrender: {width: 8192, height: 8192, msaa: 4}\n");
  EXPECT_EQ(errorOf(g), "(no error)");
}

}  // namespace
}  // namespace tailsim
