// Running experiments: resume after interruption, thread-count independence, nothing run or
// written for a bad file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "experiments/experiment_runner.h"

using namespace tailsim;
namespace fs = std::filesystem;

namespace {

fs::path tempDir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("tailsim_runner_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

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
  const fs::path dir = tempDir("resume");
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
    EXPECT_EQ(f.path().string().find(".tmp."), std::string::npos) << f.path();
}

TEST(ExperimentRunner, ResultsDoNotDependOnThreadCount) {
  const fs::path dir = tempDir("threads");
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
  const fs::path dir = tempDir("changed");
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
  const fs::path dir = tempDir("invalid");
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
