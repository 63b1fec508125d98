// A full disk: a video that could not be written whole is never published
// under its final name, and a sweep stops at the first "No space left on device" instead of
// computing every remaining case. The disk is a 200 KiB tmpfs mounted for the test (root with
// CAP_SYS_ADMIN); where mounting is not allowed the tests are skipped with a message.
#include <gtest/gtest.h>
#include <sys/mount.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <system_error>
#include <vector>

#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "rendering/ffmpeg_writer.h"

namespace tailsim {
namespace {

namespace fs = std::filesystem;

// A temporary directory with a small tmpfs mounted on it; unmounted and removed at the end.
class SmallDisk {
 public:
  explicit SmallDisk(const std::string& size) {
    std::string tmpl = (fs::temp_directory_path() / "tailsim_diskfull_XXXXXX").string();
    if (!mkdtemp(tmpl.data())) {
      error_ = std::string("mkdtemp: ") + std::strerror(errno);
      return;
    }
    dir_ = tmpl;
    if (::mount("tmpfs", dir_.c_str(), "tmpfs", 0, ("size=" + size).c_str()) != 0) {
      error_ = "cannot mount a " + size + " tmpfs on " + dir_.string() + " (" + std::strerror(errno) +
               "): needs root with CAP_SYS_ADMIN";
      return;
    }
    mounted_ = true;
  }
  ~SmallDisk() {
    if (mounted_) ::umount2(dir_.c_str(), MNT_DETACH);
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }
  bool ok() const { return mounted_; }
  const std::string& error() const { return error_; }
  const fs::path& dir() const { return dir_; }

 private:
  fs::path dir_;
  bool mounted_ = false;
  std::string error_;
};

std::vector<std::string> filesIn(const fs::path& d) {
  std::vector<std::string> v;
  for (const auto& e : fs::recursive_directory_iterator(d)) v.push_back(e.path().filename().string());
  return v;
}

TEST(DiskFull, Finding4_TruncatedVideoIsNeverPublished) {
  const std::string exe = findExecutable("ffmpeg");
  if (exe.empty()) GTEST_SKIP() << "ffmpeg not installed";
  const std::string ffprobe = findExecutable("ffprobe");
  ASSERT_FALSE(ffprobe.empty()) << "ffprobe (Debian package ffmpeg) is needed to check the published videos";
  // Incompressible frames (noise, crf 0): 64x64 frames of ~7.7 kB each in the MP4. With 200 KiB,
  // about 20 fit; around 25 ffmpeg loses its trailer to ENOSPC yet exits 0; beyond ~33 its frame
  // writes fail too. Each count must end as a whole video or as an error with nothing published.
  std::mt19937 rng(16);
  std::vector<uint8_t> frame(64 * 64 * 3);
  int published = 0, refused = 0;
  for (int n : {10, 24, 26, 28, 30, 40}) {
    SmallDisk disk("200k");
    if (!disk.ok()) GTEST_SKIP() << disk.error();
    const std::string out = (disk.dir() / "v.mp4").string();
    try {
      FfmpegSink sink(exe, 64, 64, VideoEncoding{30, 0, "ultrafast"}, {{FfmpegOutput::Kind::kMp4, out, 0}});
      for (int k = 0; k < n; ++k) {
        for (uint8_t& b : frame) b = static_cast<uint8_t>(rng());
        sink.writeFrame(frame.data());
      }
      sink.finish();
      sink.commit();
      ++published;
      EXPECT_EQ(countVideoFrames(ffprobe, out), n) << n << " frames written; the published video is damaged";
    } catch (const std::system_error& e) {
      ++refused;
      EXPECT_EQ(e.code(), std::errc::no_space_on_device) << e.what();
      EXPECT_NE(std::string(e.what()).find("No space left on device"), std::string::npos) << e.what();
      EXPECT_FALSE(fs::exists(out)) << n << " frames: " << e.what();
    } catch (const std::exception& e) {
      ++refused;
      EXPECT_FALSE(fs::exists(out)) << n << " frames: " << e.what();
    }
    EXPECT_TRUE(filesIn(disk.dir()).empty() || fs::exists(out)) << n << " frames: temporary files left";
  }
  EXPECT_GT(published, 0);
  EXPECT_GT(refused, 0);
}

TEST(DiskFull, Finding4_SweepStopsAtTheFirstDiskFullError) {
  SmallDisk disk("200k");
  if (!disk.ok()) GTEST_SKIP() << disk.error();
  // 40 cases whose CSVs (~100 kB each) fill the disk after about one case.
  const fs::path exp = disk.dir().parent_path() / (disk.dir().filename().string() + ".yaml");
  std::ofstream(exp) << "name: full\nrobot: paper\nmodels: [analytic]\n"
                        "trajectory: {dtheta_deg: {range: [-100, -61, 1]}, dT_s: 0.25}\n";
  const Experiment e = loadExperiment(exp.string());
  ASSERT_EQ(e.cases.size(), 40u);
  RunOptions o;
  o.out_dir = (disk.dir() / "out").string();
  o.threads = 1;
  o.progress = false;
  try {
    runExperiment(e, o);
    ADD_FAILURE() << "a sweep on a full disk succeeded";
  } catch (const std::exception& ex) {
    const std::string msg = ex.what();
    EXPECT_NE(msg.find("No space left on device"), std::string::npos) << msg;
    EXPECT_NE(msg.find("the disk is full: no further case was started"), std::string::npos) << msg;
  }
  fs::remove(exp);  // after the run: it copies the experiment file into the result folder
  // Case folders: the finished ones (whole) and the one that failed; none of the 40 - n after it.
  int started = 0, finished = 0;
  for (const auto& c : fs::directory_iterator(disk.dir() / "out" / "cases")) {
    ++started;
    if (fs::exists(c.path() / "result.json")) ++finished;
  }
  EXPECT_EQ(started, finished + 1) << "cases started after the disk was full";
  EXPECT_LT(started, 40);
}

}  // namespace
}  // namespace tailsim
