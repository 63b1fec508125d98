// Nothing is written outside --out. An experiment name becomes a folder only
// when it is one safe path component; MuJoCo's messages never become MUJOCO_LOG.TXT in the
// current directory.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "models/mujoco/mujoco_handles.h"
#include "rendering/ffmpeg_writer.h"
#include "scratch_dir.h"

using namespace tailsim;
using tailsim::testing::ScratchDir;
namespace fs = std::filesystem;

namespace {

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
  const ScratchDir dir("confine_names");
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
  const ScratchDir dir("confine_mjlog");
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
  const ScratchDir dir("confine_mjerr");
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

// Ffmpeg's log file never outlives its creation (unlinked at once), so a
// run killed while rendering leaves no /tmp/tailsim-ffmpeg-* behind; its messages still arrive.
TEST(OutputConfinement, Finding11_FfmpegLogLeavesNoFileInTmp) {
  const std::string exe = findExecutable("ffmpeg");
  if (exe.empty()) GTEST_SKIP() << "ffmpeg not installed";
  const ScratchDir tmp("confine_ffmpeglog"), out("confine_ffmpegout");
  const char* old = std::getenv("TMPDIR");
  const std::string old_value = old ? old : "";
  ::setenv("TMPDIR", tmp.string().c_str(), 1);
  {
    FfmpegSink sink(exe, 64, 48, VideoEncoding{}, {{FfmpegOutput::Kind::kMp4, (out / "v.mp4").string(), 0}});
    EXPECT_TRUE(fs::is_empty(tmp));  // while ffmpeg runs: this is what a kill -9 would leave
    const std::vector<uint8_t> frame(64 * 48 * 3, 128);
    sink.writeFrame(frame.data());
    sink.finish();
    sink.commit();
  }
  // A failing ffmpeg still reports its own message.
  try {
    FfmpegSink bad(exe, 64, 48, VideoEncoding{}, {{FfmpegOutput::Kind::kMp4, (out / "no/such/dir/v.mp4").string(), 0}});
    bad.finish();
    ADD_FAILURE() << "ffmpeg wrote into a missing folder";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("No such file or directory"), std::string::npos) << e.what();
  }
  if (old) ::setenv("TMPDIR", old_value.c_str(), 1);
  else ::unsetenv("TMPDIR");
  EXPECT_TRUE(fs::is_empty(tmp));
  EXPECT_TRUE(fs::exists(out / "v.mp4"));
}
