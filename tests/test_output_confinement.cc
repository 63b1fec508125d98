// Issue 16 finding 9: nothing is written outside --out. An experiment name becomes a folder only
// when it is one safe path component; MuJoCo's messages never become MUJOCO_LOG.TXT in the
// current directory.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "mujoco_model/mujoco_handles.h"

using namespace tailsim;
namespace fs = std::filesystem;

namespace {

fs::path tempDir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("tailsim_confine_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

// Runs f with the current directory set to dir.
template <class F>
void inDirectory(const fs::path& dir, F f) {
  const fs::path old = fs::current_path();
  fs::current_path(dir);
  try {
    f();
  } catch (...) {
    fs::current_path(old);
    throw;
  }
  fs::current_path(old);
}

const char* kBody =
    "robot: paper\ntail: {links: 1}\ntrajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25, w_ss: 0.25}\n"
    "models: [analytic]\n";

}  // namespace

TEST(OutputConfinement, Finding9_SuiteMemberNamesMustBeOneSafePathComponent) {
  const fs::path dir = tempDir("names");
  const std::vector<std::string> bad = {"..", ".", "a/b", "a\\\\b", "-rf", "\"tab\\there\"", std::string(101, 'n')};
  for (const std::string& name : bad) {
    std::ofstream(dir / "member.yaml") << "name: " << name << "\n" << kBody;
    std::ofstream(dir / "suite.yaml") << "experiments: [member.yaml]\n";
    try {
      loadExperimentSuite((dir / "suite.yaml").string());
      ADD_FAILURE() << "name " << name << " was accepted";
    } catch (const ConfigError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("member.yaml:1:7: name: must be a folder name"), std::string::npos) << m;
    }
  }
  // Nothing was written beside the result folder.
  for (const auto& f : fs::directory_iterator(dir))
    EXPECT_TRUE(f.path().filename() == "member.yaml" || f.path().filename() == "suite.yaml") << f.path();
  std::ofstream(dir / "member.yaml") << "name: fine-name_1.2\n" << kBody;
  EXPECT_EQ(loadExperimentSuite((dir / "suite.yaml").string()).at(0).name, "fine-name_1.2");
}

TEST(OutputConfinement, Finding9_MujocoWarningWritesNoLogFile) {
  const fs::path dir = tempDir("mjlog");
  std::string captured;
  inDirectory(dir, [&] {
    ModelPtr m = loadModelFromXml(
        "<mujoco><worldbody><body><freejoint/><geom size='0.1'/></body></worldbody></mujoco>");
    DataPtr d = makeData(m.get());
    const MujocoMessages messages;
    d->qpos[0] = NAN;  // MuJoCo warns: mjWARN_BADQPOS
    mj_step(m.get(), d.get());
    EXPECT_GT(warningCount(d.get()), 0);
    captured = messages.text();
  });
  EXPECT_NE(captured.find("MuJoCo warning: "), std::string::npos) << captured;
  EXPECT_FALSE(fs::exists(dir / "MUJOCO_LOG.TXT"));
}

TEST(OutputConfinement, Finding9_MujocoErrorIsAnExceptionNotAnExit) {
  const fs::path dir = tempDir("mjerr");
  inDirectory(dir, [&] {
    installMujocoMessageHandlers();
    try {
      mju_error("tailsim test error");
      ADD_FAILURE() << "mju_error returned";
    } catch (const MujocoError& e) {
      EXPECT_EQ(std::string(e.what()), "MuJoCo error: tailsim test error");
    }
  });
  EXPECT_FALSE(fs::exists(dir / "MUJOCO_LOG.TXT"));
}
