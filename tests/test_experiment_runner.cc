// Running experiments: resume after interruption, thread-count independence, nothing run or
// written for a bad file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <thread>

#include "experiments/accuracy_study.h"
#include "experiments/experiment_runner.h"
#include "common/atomic_file.h"
#include "results/csv.h"
#include "tailsim_version.h"
#include "scratch_dir.h"

using namespace tailsim;
using tailsim::testing::ScratchDir;
namespace fs = std::filesystem;

namespace {

// Fig. 11's sweep (9 cases), analytic only.
fs::path writeSweep(const fs::path& dir, const std::string& wss = "{range: [0.1, 0.9, 0.1]}") {
  const fs::path f = dir / "sweep.yaml";
  std::ofstream(f) << "name: wss_sweep\nrobot: " << TAILSIM_SOURCE_DIR << "/configs/robots/paper_quadruped.yaml\n"
                   << "tail: {links: 1}\ntrajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25, w_ss: " << wss
                   << "}\nmodels: [analytic]\n";
  return f;
}

nlohmann::json readJson(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

}  // namespace

TEST(ExperimentRunner, InterruptedSweepResumesWithEveryCaseOnce) {
  const ScratchDir dir("runner_resume");
  const Experiment e = loadExperiment(writeSweep(dir).string());
  ASSERT_EQ(e.cases.size(), 9u);
  RunOptions o;
  o.out_dir = (dir / "out").string();
  o.progress = false;
  o.max_new_cases = 4;  // "interrupted" after 4 cases
  RunStats s1 = runExperiment(e, o);
  EXPECT_EQ(s1.ran, 4);
  std::map<std::string, fs::file_time_type> first;
  for (const auto& c : fs::directory_iterator(dir / "out" / "cases"))
    first[c.path().filename().string()] = fs::last_write_time(c.path() / "result.json");
  EXPECT_EQ(first.size(), 4u);

  o.max_new_cases = -1;
  RunStats s2 = runExperiment(e, o);
  EXPECT_EQ(s2.resumed, 4);
  EXPECT_EQ(s2.ran, 5);
  // The finished cases were not redone.
  for (const auto& [name, t] : first) EXPECT_EQ(fs::last_write_time(dir / "out" / "cases" / name / "result.json"), t);
  const nlohmann::json sum = readJson(dir / "out" / "summary.json");
  std::set<std::string> names;
  for (const auto& c : sum["cases"]) names.insert(c["name"].get<std::string>());
  EXPECT_EQ(names.size(), 9u);
  EXPECT_EQ(sum["cases"].size(), 9u);
  // No temporary files left behind.
  for (const auto& f : fs::recursive_directory_iterator(dir / "out"))
    EXPECT_EQ(f.path().string().find(".tailsim-tmp."), std::string::npos) << f.path();
}

TEST(ExperimentRunner, ResultsDoNotDependOnThreadCount) {
  const ScratchDir dir("runner_threads");
  const Experiment e = loadExperiment(writeSweep(dir).string());
  std::vector<double> phi[2];
  for (int k = 0; k < 2; ++k) {
    RunOptions o;
    o.out_dir = (dir / ("out" + std::to_string(k))).string();
    o.progress = false;
    o.threads = k + 1;
    runExperiment(e, o);
    const nlohmann::json sum = readJson(fs::path(o.out_dir) / "summary.json");
    for (const auto& c : sum["cases"])
      phi[k].push_back(c["runs"]["analytic"]["phi_net_deg"].get<double>());
  }
  ASSERT_EQ(phi[0].size(), 9u);
  EXPECT_EQ(phi[0], phi[1]);  // bit for bit
  for (const auto& f : fs::directory_iterator(dir / "out0" / "cases"))
    EXPECT_TRUE(fs::exists(dir / "out1" / "cases" / f.path().filename() / "analytic.csv"));
}

TEST(ExperimentRunner, ChangedExperimentIsRecomputedNotResumed) {
  const ScratchDir dir("runner_changed");
  RunOptions o;
  o.out_dir = (dir / "out").string();
  o.progress = false;
  runExperiment(loadExperiment(writeSweep(dir, "{sweep: [0.2, 0.3]}").string()), o);
  // Same case names, different physics: a stale result must not be reused.
  std::ofstream(dir / "sweep.yaml", std::ios::app) << "output: {settle_s: 0.6}\n";
  const RunStats s = runExperiment(loadExperiment((dir / "sweep.yaml").string()), o);
  EXPECT_EQ(s.resumed, 0);
  EXPECT_EQ(s.ran, 2);
}

TEST(ExperimentRunner, InvalidSweepValueFailsBeforeAnythingRuns) {
  const ScratchDir dir("runner_invalid");
  const fs::path f = writeSweep(dir, "{sweep: [0.2, 1.5, 0.3]}");
  try {
    loadExperiment(f.string());
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("sweep.yaml:"), std::string::npos) << m;
    EXPECT_NE(m.find("sweep.yaml:4:"), std::string::npos) << m;  // the trajectory line
    EXPECT_NE(m.find("w_ss"), std::string::npos) << m;
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
}

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

// A copy of the paper robot with its quadruped mass set.
void writeRobot(const fs::path& f, double mass_kg) {
  std::string t = slurp(fs::path(TAILSIM_SOURCE_DIR) / "configs/robots/paper_quadruped.yaml");
  const size_t at = t.find("mass_kg: 8.458");
  t.replace(at, std::string("mass_kg: 8.458").size(), "mass_kg: " + std::to_string(mass_kg));
  std::ofstream(f) << t;
}

fs::path writeExperiment(const fs::path& dir, const std::string& file, const std::string& body) {
  const fs::path f = dir / file;
  std::ofstream(f) << body;
  return f;
}

const char* kShortTrajectory = "tail: {links: 1}\ntrajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25, w_ss: 0.25}\n";

double phiNet(const fs::path& out, const std::string& case_name, const std::string& model) {
  const nlohmann::json sum = readJson(out / "summary.json");
  for (const auto& c : sum["cases"])
    if (c["name"] == case_name) return c["runs"][model]["phi_net_deg"].get<double>();
  ADD_FAILURE() << "no case " << case_name;
  return NAN;
}

// Keeps only these models, as `tailsim run --models` does.
Experiment onlyModels(Experiment e, const std::vector<std::string>& models) {
  for (ExperimentCase& c : e.cases) c.models = models;
  return e;
}

}  // namespace

// Editing the second robot file of a robot sweep must recompute its cases.
TEST(ExperimentRunner, Finding1_EditedSweptRobotFileInvalidatesItsCases) {
  const ScratchDir dir("runner_f1robot");
  writeRobot(dir / "robotA.yaml", 8.458);
  writeRobot(dir / "robotB.yaml", 8.458);
  const fs::path f = writeExperiment(dir, "robots.yaml",
                                     std::string("name: robots\nrobot: {sweep: [robotA.yaml, robotB.yaml]}\n") +
                                         kShortTrajectory + "models: [analytic]\n");
  RunOptions o;
  o.out_dir = (dir / "out").string();
  o.progress = false;
  EXPECT_EQ(runExperiment(loadExperiment(f.string()), o).ran, 2);
  writeRobot(dir / "robotB.yaml", 4.0);  // a lighter body turns further
  const RunStats s = runExperiment(loadExperiment(f.string()), o);
  EXPECT_EQ(s.resumed, 1);  // robotA's case is unchanged
  EXPECT_EQ(s.ran, 1);
  RunOptions fresh = o;
  fresh.out_dir = (dir / "fresh").string();
  runExperiment(loadExperiment(f.string()), fresh);
  const Experiment e = loadExperiment(f.string());
  for (const ExperimentCase& c : e.cases)
    EXPECT_EQ(phiNet(dir / "out", c.name, "analytic"), phiNet(dir / "fresh", c.name, "analytic")) << c.name;
}

// `run X --models analytic` then `run X` must compute MuJoCo.
TEST(ExperimentRunner, Finding1_ModelsFilterIsPartOfTheResumeKey) {
  const ScratchDir dir("runner_f1models");
  const fs::path f = writeExperiment(dir, "both.yaml",
                                     std::string("name: both\nrobot: paper\n") + kShortTrajectory +
                                         "models: [analytic, mujoco]\noutput: {settle_s: 0.05, sample_dt_s: 0.01}\n");
  RunOptions o;
  o.out_dir = (dir / "out").string();
  o.progress = false;
  const Experiment e = loadExperiment(f.string());
  runExperiment(onlyModels(e, {"analytic"}), o);
  EXPECT_FALSE(readJson(dir / "out" / "summary.json")["cases"][0]["runs"].contains("mujoco"));
  const RunStats s = runExperiment(e, o);
  EXPECT_EQ(s.resumed, 0);
  EXPECT_EQ(s.ran, 1);
  EXPECT_TRUE(readJson(dir / "out" / "summary.json")["cases"][0]["runs"].contains("mujoco"));
  EXPECT_TRUE(fs::exists(dir / "out" / "cases" / "base" / "mujoco.csv"));
  EXPECT_EQ(runExperiment(e, o).resumed, 1);  // and now it is finished
}

// Rendering on/off, the version and every resolved setting are in the key.
TEST(ExperimentRunner, Finding1_ResumeKeyCoversRenderVersionAndSettings) {
  const ScratchDir dir("runner_f1key");
  const Experiment e = loadExperiment(
      writeExperiment(dir, "k.yaml", std::string("name: k\nrobot: paper\n") + kShortTrajectory + "models: [analytic]\n")
          .string());
  const ExperimentCase& c = e.cases.at(0);
  EXPECT_NE(caseKey(c, true), caseKey(c, false));
  EXPECT_EQ(caseKey(c, false), caseKey(e.cases.at(0), false));  // stable
  EXPECT_EQ(caseKey(c, false).size(), 64u);
  EXPECT_NE(caseKeyText(c, false).find(std::string("\"tailsim_version\":\"") + kVersion + "\""), std::string::npos);
  auto changed = [&](auto edit) {
    ExperimentCase d = c;
    edit(d);
    return caseKey(d, false) != caseKey(c, false);
  };
  EXPECT_TRUE(changed([](ExperimentCase& d) { d.robot.tail[0].izz_kgm2 *= 1.01; }));
  EXPECT_TRUE(changed([](ExperimentCase& d) { d.robot.friction.mu_d += 0.01; }));
  EXPECT_TRUE(changed([](ExperimentCase& d) { d.joints[0].w_ss = 0.3; }));
  EXPECT_TRUE(changed([](ExperimentCase& d) { d.analytic.rel_tol = 1e-6; }));
  EXPECT_TRUE(changed([](ExperimentCase& d) { d.mujoco.solimp[4] = 3.0; }));
  EXPECT_TRUE(changed([](ExperimentCase& d) { d.effects.gravity = false; }));
  EXPECT_TRUE(changed([](ExperimentCase& d) { d.output.sample_dt_s = 2e-3; }));
  EXPECT_TRUE(changed([](ExperimentCase& d) { d.models.push_back("mujoco"); }));
  EXPECT_FALSE(changed([](ExperimentCase& d) { d.robot_file = "/elsewhere/same_robot.yaml"; }));  // values count
}

// Names that sanitize alike get distinct folders, and the printed/recorded
// results belong to the right case.
TEST(ExperimentRunner, Finding2_CaseFoldersAreUniqueByConstruction) {
  EXPECT_EQ(caseDirName("w_ss=0.25"), "w_ss=0.25");  // plain names stay readable
  EXPECT_NE(caseDirName("r a.yaml"), caseDirName("r_a.yaml"));
  EXPECT_NE(caseDirName("a b"), caseDirName("a?b"));
  for (const std::string& n : {std::string(".."), std::string("."), std::string(""), std::string("-x"),
                              std::string("a/../../b"), std::string(300, 'x')}) {
    const std::string d = caseDirName(n);
    EXPECT_NE(d, n.empty() ? "x" : n);
    EXPECT_NE(d, ".");
    EXPECT_NE(d, "..");
    EXPECT_EQ(d.find('/'), std::string::npos) << d;
    EXPECT_LE(d.size(), 100u) << d;
    EXPECT_NE(d[0], '.');
  }
  const ScratchDir dir("runner_f2dirs");
  writeRobot(dir / "r a.yaml", 4.0);
  writeRobot(dir / "r_a.yaml", 8.458);
  const fs::path f = writeExperiment(dir, "names.yaml",
                                     std::string("name: names\nrobot: {sweep: [\"r a.yaml\", \"r_a.yaml\"]}\n") +
                                         kShortTrajectory + "models: [analytic]\n");
  for (int threads : {1, 2}) {
    RunOptions o;
    o.out_dir = (dir / ("out" + std::to_string(threads))).string();
    o.progress = false;
    o.threads = threads;
    const Experiment e = loadExperiment(f.string());
    runExperiment(e, o);
    std::set<std::string> dirs;
    const nlohmann::json sum = readJson(fs::path(o.out_dir) / "summary.json");
    for (const auto& c : sum["cases"]) {
      const std::string d = c["dir"];
      dirs.insert(d);
      // Each folder holds its own case's result.
      EXPECT_EQ(readJson(fs::path(o.out_dir) / "cases" / d / "result.json")["name"], c["name"]);
      const TimeSeries ts = readCsv((fs::path(o.out_dir) / "cases" / d / "analytic.csv").string());
      const double phi_end = ts.at(ts.numRows() - 1, ts.column("phi_deg"));
      EXPECT_NEAR(phi_end, c["runs"]["analytic"]["phi_net_deg"].get<double>(), 1e-2) << d;
    }
    EXPECT_EQ(dirs.size(), 2u);
    EXPECT_NE(phiNet(o.out_dir, e.cases[0].name, "analytic"), phiNet(o.out_dir, e.cases[1].name, "analytic"));
  }
}

// Two threads writing one path atomically never share a temporary file.
TEST(ExperimentRunner, Finding2_ConcurrentAtomicWritesNeverTear) {
  const ScratchDir dir("runner_f2atomic");
  const std::string path = (dir / "same.csv").string();
  const std::string a(300000, 'a'), b(300000, 'b');
  std::atomic<int> errors{0};
  auto writer = [&](const std::string& text) {
    for (int k = 0; k < 100; ++k) {
      try {
        writeFileAtomic(path, text);
      } catch (const std::exception&) {
        ++errors;
      }
      const std::string now = slurp(path);
      if (now != a && now != b) ++errors;  // torn: a mix of both
    }
  };
  std::thread t1(writer, a), t2(writer, b);
  t1.join();
  t2.join();
  EXPECT_EQ(errors.load(), 0);
  for (const auto& f : fs::directory_iterator(dir)) EXPECT_EQ(f.path().filename(), "same.csv");
}

// A second experiment into the same --out is refused, nothing written.
TEST(ExperimentRunner, Finding3_OtherExperimentInSameOutIsRefused) {
  const ScratchDir dir("runner_f3other");
  RunOptions o;
  o.out_dir = (dir / "out").string();
  o.progress = false;
  const Experiment x = loadExperiment(writeSweep(dir, "{sweep: [0.2, 0.3]}").string());
  runExperiment(x, o);
  const std::string summary = slurp(dir / "out" / "summary.json");
  const Experiment y = loadExperiment(
      writeExperiment(dir, "other.yaml", std::string("name: other\nrobot: paper\n") + kShortTrajectory +
                                             "models: [analytic]\n")
          .string());
  try {
    runExperiment(y, o);
    FAIL() << "expected a refusal";
  } catch (const std::runtime_error& err) {
    const std::string m = err.what();
    EXPECT_NE(m.find("holds the results of experiment 'wss_sweep'"), std::string::npos) << m;
    EXPECT_NE(m.find("--fresh"), std::string::npos) << m;
  }
  EXPECT_EQ(slurp(dir / "out" / "summary.json"), summary);
  EXPECT_FALSE(fs::exists(dir / "out" / "cases" / "base"));
  // --fresh replaces the old results entirely: no orphaned case folders.
  o.resume = false;
  runExperiment(y, o);
  std::set<std::string> dirs;
  for (const auto& d : fs::directory_iterator(dir / "out" / "cases")) dirs.insert(d.path().filename().string());
  EXPECT_EQ(dirs, std::set<std::string>{"base"});
  EXPECT_EQ(readJson(dir / "out" / "summary.json")["experiment"], "other");
}

// A run into a folder another run holds fails at once, naming its pid.
TEST(ExperimentRunner, Finding3_ConcurrentRunIntoSameOutFails) {
  const ScratchDir dir("runner_f3lock");
  fs::create_directories(dir / "out");
  const int fd = ::open((dir / "out" / ".tailsim.lock").c_str(), O_RDWR | O_CREAT, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  ASSERT_EQ(::write(fd, "4242\n", 5), 5);
  RunOptions o;
  o.out_dir = (dir / "out").string();
  o.progress = false;
  try {
    runExperiment(loadExperiment(writeSweep(dir, "{sweep: [0.2, 0.3]}").string()), o);
    FAIL() << "expected the lock to be refused";
  } catch (const std::runtime_error& err) {
    EXPECT_EQ(std::string(err.what()), o.out_dir + " is in use by another tailsim run (pid 4242)");
  }
  EXPECT_FALSE(fs::exists(dir / "out" / "cases"));
  ::close(fd);  // released: now it runs
  EXPECT_EQ(runExperiment(loadExperiment((dir / "sweep.yaml").string()), o).ran, 2);
}

// Temporaries a killed run left are removed by the next run of the folder;
// those of a live process and files not named like tailsim's temporaries stay.
TEST(ExperimentRunner, Finding11_KilledRunTemporariesAreCleaned) {
  const ScratchDir dir("runner_f11");
  RunOptions o;
  o.out_dir = (dir / "out").string();
  o.progress = false;
  const Experiment e = loadExperiment(writeSweep(dir, "{sweep: [0.2, 0.3]}").string());
  runExperiment(e, o);
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ::waitpid(child, nullptr, 0);  // a pid that is no longer running
  const std::string dead = std::to_string(child), live = std::to_string(::getppid());
  const fs::path out = dir / "out", c = out / "cases" / "w_ss=0.2";
  fs::create_directories(out / "renders");
  const std::vector<fs::path> stale = {c / ("analytic.csv.tailsim-tmp." + dead), c / ("result.json.tailsim-tmp." + dead + ".7"),
                                       out / ("summary.json.tailsim-tmp." + dead + ".0"),
                                       out / "renders" / ("w_ss=0.2.tailsim-tmp." + dead + ".3.mp4")};
  const std::vector<fs::path> kept = {c / ("analytic.csv.tailsim-tmp." + live), out / "notes.tmp.txt", out / "mine.tmp"};
  for (const auto& p : stale) std::ofstream(p) << "partial";
  for (const auto& p : kept) std::ofstream(p) << "keep";
  EXPECT_EQ(runExperiment(e, o).resumed, 2);
  for (const auto& p : stale) EXPECT_FALSE(fs::exists(p)) << p;
  for (const auto& p : kept) EXPECT_TRUE(fs::exists(p)) << p;
}

// A user's file at the path of a case's HDF5 part (time_series.h5.d/<case dir>.h5) was overwritten by the
// case's part and then deleted by the join, without a word: it is refused before any work, unchanged,
// whatever it is (a regular file, a symlink, a FIFO). tailsim's own parts still resume.
TEST(UserFiles, AFileAtAPartsPathIsRefused) {
  const ScratchDir dir("runner_a1");
  std::ofstream(dir / "h5.yaml") << "name: h5\nrobot: paper\ntail: {links: 1}\n"
                                 << "trajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25, w_ss: {sweep: [0.2, 0.3]}}\n"
                                 << "models: [analytic]\noutput: {time_series: thin, time_series_file: hdf5}\n";
  const Experiment e = loadExperiment((dir / "h5.yaml").string());
  RunOptions o;
  o.out_dir = (dir / "out").string();
  o.progress = false;
  const fs::path parts = dir / "out" / "time_series.h5.d", mine = parts / "w_ss=0.3.h5";
  for (const std::string kind : {"file", "symlink", "fifo"}) {
    fs::remove_all(dir / "out");
    fs::create_directories(parts);
    std::ofstream(dir / "target") << "mine";
    if (kind == "file") std::ofstream(mine) << "mine";
    if (kind == "symlink") fs::create_symlink(dir / "target", mine);
    if (kind == "fifo") {
      ASSERT_EQ(::mkfifo(mine.c_str(), 0644), 0);
    }
    try {
      runExperiment(e, o);
      ADD_FAILURE() << kind << ": a user's file at a part's path was not refused";
    } catch (const std::runtime_error& err) {
      EXPECT_NE(std::string(err.what()).find(mine.string() + " was not written by tailsim"), std::string::npos)
          << kind << ": " << err.what();
    }
    EXPECT_TRUE(fs::exists(fs::symlink_status(mine))) << kind;
    EXPECT_FALSE(fs::exists(dir / "out" / "summary.json")) << kind << ": work done before the refusal";
    std::ifstream t(kind == "file" ? mine : dir / "target");
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(t), {}), "mine") << kind;
  }
  // Without the user's file the same folder runs, and resumes.
  fs::remove_all(dir / "out");
  EXPECT_EQ(runExperiment(e, o).ran, 2);
  EXPECT_EQ(runExperiment(e, o).resumed, 2);
}

// `tailsim accuracy --out DIR` wrote accuracy.md and accuracy.csv over the user's files: refused
// (checkAccuracyTables, before the study; writeAccuracyTables itself), unchanged; its own replaced.
TEST(UserFiles, AccuracyTablesReplaceOnlyTailsimsOwn) {
  const ScratchDir dir("runner_a4");
  for (const std::string name : {"accuracy.md", "accuracy.csv"}) {
    std::ofstream(dir / name) << "mine";
    EXPECT_THROW(checkAccuracyTables(dir.string()), std::runtime_error) << name;
    try {
      writeAccuracyTables({}, dir.string());
      ADD_FAILURE() << "the user's " << name << " was replaced";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find((dir / name).string() + " was not written by tailsim"), std::string::npos)
          << e.what();
    }
    std::ifstream in(dir / name);
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "mine") << name;
    fs::remove(dir / name);
  }
  writeAccuracyTables({}, dir.string());
  checkAccuracyTables(dir.string());
  writeAccuracyTables({}, dir.string());  // over its own
}

// A user's file named like a temporary of a dead process but without tailsim's infix
// ("<name>.tmp.<pid>...") is not tailsim's: a run keeps it.
TEST(UserFiles, TempLookalikesOfDeadPidsAreKept) {
  const ScratchDir dir("runner_f19");
  RunOptions o;
  o.out_dir = (dir / "out").string();
  o.progress = false;
  const Experiment e = loadExperiment(writeSweep(dir, "{sweep: [0.2, 0.3]}").string());
  runExperiment(e, o);
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ::waitpid(child, nullptr, 0);  // a pid that is no longer running
  const std::string dead = std::to_string(child);
  const fs::path out = dir / "out";
  fs::create_directories(out / "plots");
  const std::vector<fs::path> mine = {out / ("notes.tmp." + dead + ".txt"), out / "plots" / ("fig.tmp." + dead + ".png"),
                                      out / "cases" / "w_ss=0.2" / ("draft.tmp." + dead)};
  for (const auto& p : mine) std::ofstream(p) << "mine";
  EXPECT_EQ(runExperiment(e, o).resumed, 2);
  for (const auto& p : mine) EXPECT_TRUE(fs::exists(p)) << p;
}
