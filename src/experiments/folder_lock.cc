#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <thread>

#include "experiments/experiment_runner.h"
#include "common/atomic_file.h"

namespace tailsim {
namespace fs = std::filesystem;

// The run lock goes with the process (also on kill -9); the file stays.
FolderLock::FolderLock(const std::string& dir_text) {
  const fs::path dir(dir_text);
  fs::create_directories(dir);
  const fs::path p = dir / ".tailsim.lock";
  fd_ = ::open(p.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK, 0644);
  if (fd_ < 0) throw std::runtime_error("cannot open " + p.string() + ": " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode) || st.st_nlink > 1) {
    ::close(fd_);
    throw std::runtime_error(p.string() + (S_ISREG(st.st_mode) ? " has other hard links (the same file elsewhere)"
                                                                 : " is not a regular file") +
                             ": tailsim writes its lock only into a file of its own (remove it)");
  }
  // A busy lock whose recorded run is dead is held for a moment more by that run's dying helper
  // process (runHdf5Isolated's child, killed with it): waited for up to kDeadHolderWait.
  constexpr auto kDeadHolderWait = std::chrono::seconds(2);
  const auto t0 = std::chrono::steady_clock::now();
  while (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    char buf[32] = {};
    const ssize_t n = ::pread(fd_, buf, sizeof buf - 1, 0);
    std::string pid = n > 0 ? std::string(buf, static_cast<size_t>(n)) : "?";
    while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
    const bool holder_dead = !pid.empty() && pid.size() <= 9 &&
                             std::all_of(pid.begin(), pid.end(), [](char c) { return c >= '0' && c <= '9'; }) &&
                             processGone(std::atol(pid.c_str()));
    if (err == EWOULDBLOCK && holder_dead && std::chrono::steady_clock::now() - t0 < kDeadHolderWait) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      continue;
    }
    ::close(fd_);
    if (err != EWOULDBLOCK) throw std::runtime_error("cannot lock " + p.string() + ": " + std::strerror(err));
    throw std::runtime_error(dir.string() + " is in use by another tailsim run (pid " + pid + ")");
  }
  const std::string me = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, me.data(), me.size(), 0) != static_cast<ssize_t>(me.size())) {
    // the pid is only for the message of a second run; the lock itself holds
  }
}

FolderLock::~FolderLock() { ::close(fd_); }  // releases the lock

}  // namespace tailsim
