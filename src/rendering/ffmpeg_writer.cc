#include "rendering/ffmpeg_writer.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>

extern char** environ;

namespace tailsim {

namespace {

bool isExecutableFile(const std::string& p) {
  struct stat st;
  return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(p.c_str(), X_OK) == 0;
}

// Temporary name beside the target, keeping the extension: dir/name.tailsim-tmp.<pid>.<k>.ext
std::string tempNameFor(const std::string& final_path) {
  static std::atomic<int> counter{0};  // unique within the process (several sinks at once)
  const size_t slash = final_path.find_last_of('/');
  const size_t dot = final_path.find_last_of('.');
  const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash);
  const std::string stem = has_ext ? final_path.substr(0, dot) : final_path;
  const std::string ext = has_ext ? final_path.substr(dot) : "";
  return stem + ".tailsim-tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++) + ext;
}

// write() with SIGPIPE blocked in this thread, so a dead reader gives EPIPE instead of killing
// the process; a SIGPIPE raised meanwhile is consumed before the mask is restored.
// Returns 0 or the errno of the failed write.
int writeAll(int fd, const uint8_t* p, size_t n) {
  sigset_t pipe_set, old_set;
  sigemptyset(&pipe_set);
  sigaddset(&pipe_set, SIGPIPE);
  pthread_sigmask(SIG_BLOCK, &pipe_set, &old_set);
  int err = 0;
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      err = errno;
      break;
    }
    p += w;
    n -= static_cast<size_t>(w);
  }
  if (err != 0) {
    const timespec zero{0, 0};
    while (sigtimedwait(&pipe_set, nullptr, &zero) > 0) {
    }
  }
  pthread_sigmask(SIG_SETMASK, &old_set, nullptr);
  return err;
}

}  // namespace

std::string findExecutable(const std::string& name) {
  if (name.empty()) return "";
  if (name.find('/') != std::string::npos) return isExecutableFile(name) ? name : "";
  const char* path = std::getenv("PATH");
  if (!path) return "";
  std::stringstream ss(path);
  std::string dir;
  while (std::getline(ss, dir, ':')) {
    if (dir.empty()) dir = ".";
    const std::string cand = dir + "/" + name;
    if (isExecutableFile(cand)) return cand;
  }
  return "";
}

namespace {
// ffmpeg's stderr: a file created in $TMPDIR (or /tmp) and unlinked at once, so nothing is left
// behind whatever happens to this process (kill -9 included); read back through the descriptor.
int makeLogFile() {
  const char* tmpdir = std::getenv("TMPDIR");
  std::string tmpl_s = std::string(tmpdir && *tmpdir ? tmpdir : "/tmp") + "/tailsim-ffmpeg-XXXXXX";
  std::vector<char> tmpl(tmpl_s.begin(), tmpl_s.end());
  tmpl.push_back('\0');
  const int fd = ::mkostemp(tmpl.data(), O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(std::string("cannot create an ffmpeg log file: ") + std::strerror(errno));
  ::unlink(tmpl.data());
  return fd;
}

// A path as ffmpeg's file: protocol URL: a path is never read as an option (a leading '-') or as
// another protocol ("http:", "concat:", "pipe:"), whatever the folder or case names hold.
std::string fileUrl(const std::string& path) { return "file:" + path; }

std::string rawLog(int fd) {
  std::string s;
  char buf[4096];
  off_t off = 0;
  for (;;) {
    const ssize_t n = ::pread(fd, buf, sizeof buf, off);
    if (n <= 0) break;
    s.append(buf, static_cast<size_t>(n));
    off += n;
  }
  return s;
}

std::string readLog(int fd) {
  std::string s = rawLog(fd);
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
  if (s.size() > 2000) s = "..." + s.substr(s.size() - 2000);
  return s.empty() ? "(no message)" : s;
}

// Runs argv[0] (a full path) with stdin and stderr on /dev/null; returns its exit status (-1 when
// it cannot start or is killed) and sets `out` to what it printed on stdout.
int runCapture(std::vector<std::string> args, std::string& out) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) return -1;
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&fa, fds[1], 1);
  posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, args[0].c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  ::close(fds[1]);
  out.clear();
  if (rc == 0) {
    char buf[4096];
    for (;;) {
      const ssize_t n = ::read(fds[0], buf, sizeof buf);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      if (out.size() < 65536) out.append(buf, static_cast<size_t>(n));
    }
  }
  ::close(fds[0]);
  if (rc != 0) return -1;
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// ffprobe beside the ffmpeg executable (the same Debian package), else on PATH; "" if none.
std::string ffprobeFor(const std::string& ffmpeg_exe) {
  const size_t slash = ffmpeg_exe.find_last_of('/');
  if (slash != std::string::npos) {
    const std::string beside = ffmpeg_exe.substr(0, slash + 1) + "ffprobe";
    if (isExecutableFile(beside)) return beside;
  }
  return findExecutable("ffprobe");
}

}  // namespace

// Frames (video packets) in the container at `path`, read by ffprobe; -1 when ffprobe cannot
// read it (a truncated MP4 has no moov atom).
long countVideoFrames(const std::string& ffprobe_exe, const std::string& path) {
  std::string out;
  const int rc = runCapture({ffprobe_exe, "-v", "error", "-select_streams", "v:0", "-count_packets", "-show_entries",
                             "stream=nb_read_packets", "-of", "csv=p=0", fileUrl(path)},
                            out);
  if (rc != 0) return -1;
  char* end = nullptr;
  const long n = std::strtol(out.c_str(), &end, 10);
  return end == out.c_str() ? -1 : n;
}

std::string probeFfmpeg(const std::string& ffmpeg_exe) {
  const int log_fd = makeLogFile();
  std::vector<std::string> args = {ffmpeg_exe, "-hide_banner", "-loglevel", "error", "-nostdin",
                                   "-f", "lavfi", "-i", "testsrc=size=64x48:rate=1:duration=1",
                                   "-frames:v", "1", "-c:v", "libx264", "-pix_fmt", "yuv420p", "-f", "null", "-"};
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_adddup2(&fa, log_fd, 2);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, ffmpeg_exe.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  std::string result;
  if (rc != 0) {
    result = std::string("cannot start it: ") + std::strerror(rc);
  } else {
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
      result = "a test encode with libx264 failed: " + readLog(log_fd);
  }
  ::close(log_fd);
  return result;
}

FfmpegSink::FfmpegSink(const std::string& ffmpeg_exe, int width, int height, const VideoEncoding& enc,
                       const std::vector<FfmpegOutput>& outputs)
    : outputs_(outputs), ffprobe_(ffprobeFor(ffmpeg_exe)), frame_bytes_(static_cast<size_t>(width) * height * 3) {
  if (outputs.empty()) throw std::invalid_argument("FfmpegSink needs at least one output");
  for (const FfmpegOutput& o : outputs) tmp_paths_.push_back(tempNameFor(o.path));
  log_fd_ = makeLogFile();
  const int log_fd = log_fd_;

  const std::string size = std::to_string(width) + "x" + std::to_string(height);
  std::vector<std::string> args = {ffmpeg_exe, "-hide_banner", "-loglevel", "error", "-y",
                                   "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", size,
                                   "-r", std::to_string(enc.fps), "-i", "-"};
  auto add = [&](std::initializer_list<std::string> a) { args.insert(args.end(), a); };
  for (size_t i = 0; i < outputs.size(); ++i) {
    add({"-map", "0:v", "-an"});
    if (outputs[i].kind == FfmpegOutput::Kind::kMp4) {
      // zerolatency: no lookahead or frame threads, so little is left to encode at the end.
      add({"-c:v", "libx264", "-preset", enc.preset, "-tune", "zerolatency", "-crf", std::to_string(enc.crf),
           "-pix_fmt", "yuv420p", "-movflags", "+faststart", "-f", "mp4"});
    } else {
      add({"-vf", "select=eq(n\\," + std::to_string(outputs[i].png_frame) + ")", "-fps_mode", "passthrough",
           "-frames:v", "1", "-update", "1", "-c:v", "png", "-f", "image2"});
    }
    args.push_back(fileUrl(tmp_paths_[i]));
  }

  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) {
    ::close(log_fd_);
    log_fd_ = -1;
    throw std::runtime_error(std::string("cannot create a pipe to ffmpeg: ") + std::strerror(errno));
  }
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_adddup2(&fa, fds[0], 0);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_adddup2(&fa, log_fd, 2);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const int rc = posix_spawn(&pid_, ffmpeg_exe.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  ::close(fds[0]);
  if (rc != 0) {
    ::close(fds[1]);
    ::close(log_fd_);
    log_fd_ = -1;
    pid_ = -1;
    throw std::runtime_error("cannot start ffmpeg (" + ffmpeg_exe + "): " + std::strerror(rc));
  }
  stdin_fd_ = fds[1];
  ::fcntl(stdin_fd_, F_SETPIPE_SZ, 1 << 20);  // best effort: fewer blocking writes
}

FfmpegSink::~FfmpegSink() { abort(); }

std::string FfmpegSink::errorLog() const { return log_fd_ >= 0 ? readLog(log_fd_) : "(no message)"; }

void FfmpegSink::writeFrame(const uint8_t* rgb) {
  if (stdin_fd_ < 0) throw std::logic_error("FfmpegSink::writeFrame after finish");
  if (const int err = writeAll(stdin_fd_, rgb, frame_bytes_)) {
    ::close(stdin_fd_);
    stdin_fd_ = -1;
    int status = 0;
    if (pid_ > 0) ::waitpid(pid_, &status, 0);
    pid_ = -1;
    fail("ffmpeg stopped reading frames for " + outputs_[0].path + " (" + std::strerror(err) + "): " + errorLog());
  }
  ++frames_;
}

void FfmpegSink::finish() {
  if (pid_ < 0) throw std::logic_error("FfmpegSink::finish called twice");
  ::close(stdin_fd_);
  stdin_fd_ = -1;
  int status = 0;
  while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
  }
  pid_ = -1;
  std::string msg;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    msg = "ffmpeg failed writing " + outputs_[0].path +
          (WIFEXITED(status) ? " (exit " + std::to_string(WEXITSTATUS(status)) + ")"
                             : std::string(" (killed by a signal)")) +
          ": " + errorLog();
  } else if (rawLog(log_fd_).find("rror") != std::string::npos) {
    // ffmpeg exits 0 when writing the MP4's trailer fails (e.g. the disk is full): with
    // -loglevel error, any "Error ..." line means an output is damaged.
    msg = "ffmpeg failed writing " + outputs_[0].path + ": " + errorLog();
  } else {
    for (size_t i = 0; i < tmp_paths_.size() && msg.empty(); ++i) {
      struct stat st;
      if (::stat(tmp_paths_[i].c_str(), &st) != 0 || st.st_size == 0)
        msg = "ffmpeg exited cleanly but wrote nothing for " + outputs_[i].path +
              (outputs_[i].kind == FfmpegOutput::Kind::kPng
                   ? " (frame " + std::to_string(outputs_[i].png_frame) + " of " + std::to_string(frames_) + ")"
                   : std::string()) +
              ": " + errorLog();
    }
    // The container must hold every frame written (a truncated MP4 must never be published).
    for (size_t i = 0; i < tmp_paths_.size() && msg.empty() && !ffprobe_.empty(); ++i) {
      if (outputs_[i].kind != FfmpegOutput::Kind::kMp4) continue;
      const long n = countVideoFrames(ffprobe_, tmp_paths_[i]);
      if (n != frames_)
        msg = "ffmpeg exited cleanly but " + outputs_[i].path + " is damaged: " +
              (n < 0 ? std::string("ffprobe cannot read it") : "it holds " + std::to_string(n) + " frames") +
              " (" + std::to_string(frames_) + " written)";
    }
  }
  if (!msg.empty()) fail(msg);
  finished_ = true;
}

void FfmpegSink::fail(const std::string& msg) {
  // A full disk (ffmpeg's own writes failed with ENOSPC) is a std::system_error, so that a sweep
  // stops instead of failing every remaining video the same way.
  const bool disk_full = rawLog(log_fd_).find("No space left on device") != std::string::npos;
  abort();
  if (disk_full) throw std::system_error(ENOSPC, std::generic_category(), msg);
  throw std::runtime_error(msg);
}

void FfmpegSink::commit() {
  if (!finished_) throw std::logic_error("FfmpegSink::commit before finish");
  for (size_t i = 0; i < tmp_paths_.size(); ++i) {
    if (tmp_paths_[i].empty()) continue;
    if (std::rename(tmp_paths_[i].c_str(), outputs_[i].path.c_str()) != 0) {
      const std::string msg =
          "cannot move " + tmp_paths_[i] + " to " + outputs_[i].path + ": " + std::strerror(errno);
      abort();
      throw std::runtime_error(msg);
    }
    tmp_paths_[i].clear();
  }
  ::close(log_fd_);
  log_fd_ = -1;
}

void FfmpegSink::abort() noexcept {
  if (stdin_fd_ >= 0) {
    ::close(stdin_fd_);
    stdin_fd_ = -1;
  }
  if (pid_ > 0) {
    ::kill(pid_, SIGKILL);
    int status;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    pid_ = -1;
  }
  for (std::string& t : tmp_paths_) {
    if (!t.empty()) std::remove(t.c_str());
    t.clear();
  }
  if (log_fd_ >= 0) {
    ::close(log_fd_);
    log_fd_ = -1;
  }
}

}  // namespace tailsim
