#include "common/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <limits>
#include <vector>

#include "common/number_text.h"
#include "common/sha256.h"

namespace tailsim {

void writeFileAtomic(const std::string& path, const std::string& contents) {
  // Errors are std::system_error carrying errno (a full disk is ENOSPC, which a sweep stops at);
  // what() reads "cannot write PATH: <OS error>".
  // "<path>.tailsim-tmp.<pid>.<k>": unique per writer (process and call), so two threads writing the same
  // path never share a temporary; `tailsim run` removes those of dead processes.
  static std::atomic<unsigned long> counter{0};
  const std::string tmp = path + ".tailsim-tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw std::system_error(errno, std::generic_category(), "cannot write " + path);
  // No fsync: rename makes the file appear whole or not at all if the process dies (the
  // guarantee we give); fsync per file would only add power-loss durability, at ~10 ms a file.
  int err = 0;
  if (std::fwrite(contents.data(), 1, contents.size(), f) != contents.size() || std::fflush(f) != 0) err = errno;
  if (std::fclose(f) != 0 && err == 0) err = errno;
  if (err != 0) {
    std::remove(tmp.c_str());
    throw std::system_error(err, std::generic_category(), "cannot write " + path);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    err = errno;
    std::remove(tmp.c_str());
    throw std::system_error(err, std::generic_category(), "cannot move " + tmp + " to " + path);
  }
}

bool processGone(long pid) {
  if (pid <= 0 || pid > std::numeric_limits<pid_t>::max()) return false;
  if (::kill(static_cast<pid_t>(pid), 0) != 0) return errno == ESRCH;
  // /proc/PID/stat: "PID (comm) S ...": the state follows the last ')'.
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text;
  std::getline(stat, text);
  const size_t close = text.rfind(')');
  return close != std::string::npos && close + 2 < text.size() && text[close + 2] == 'Z';
}

namespace {
// Opens a result-folder file for reading when it is a regular file of at most max_bytes (-1: absent;
// std::runtime_error naming it otherwise); its size in *size.
int openResultFile(const std::string& path, long long max_bytes, long long* size) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    if (err == ENOENT) return -1;
    if (err == ELOOP) throw std::runtime_error(path + " is a symbolic link: tailsim reads and writes only regular files in a result folder (remove it)");
    throw std::runtime_error("cannot open " + path + ": " + std::strerror(err));
  }
  struct stat st {};
  std::string problem;
  if (::fstat(fd, &st) != 0)
    problem = "cannot stat " + path + ": " + std::strerror(errno);
  else if (!S_ISREG(st.st_mode))
    problem = path + " is not a regular file: tailsim reads and writes only regular files in a result folder (remove it)";
  else if (st.st_size > max_bytes)
    problem = path + " is " + std::to_string(st.st_size) + " bytes, more than tailsim ever writes there (" +
              std::to_string(max_bytes) + "): not read";
  if (!problem.empty()) {
    ::close(fd);
    throw std::runtime_error(problem);
  }
  *size = st.st_size;
  return fd;
}
struct FdCloser {
  int fd;
  ~FdCloser() { ::close(fd); }
};
}  // namespace

void makeResultDir(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);  // through a link too: refused below, nothing written
  struct stat st {};
  if (::lstat(dir.c_str(), &st) != 0)
    throw std::runtime_error("cannot create the folder " + dir + ": " + (ec ? ec.message() : std::strerror(errno)));
  if (S_ISLNK(st.st_mode))
    throw std::runtime_error(dir + " is a symbolic link: tailsim writes only into real folders of a result folder, "
                                   "never through a link (remove it)");
  if (!S_ISDIR(st.st_mode)) throw std::runtime_error(dir + " is not a folder: not written (remove it)");
}

std::optional<LinesRead> readResultFileLines(const std::string& path, size_t max_line,
                                             const std::function<bool(const std::string& line, long long number)>& fn) {
  long long size = 0;
  const int fd = openResultFile(path, kMaxResultFileBytes, &size);
  if (fd < 0) return std::nullopt;
  const FdCloser closer{fd};
  LinesRead r;
  std::string line;
  std::vector<char> buf(1 << 16);
  for (;;) {
    const ssize_t n = ::read(fd, buf.data(), buf.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw std::runtime_error("cannot read " + path + ": " + std::strerror(errno));
    if (n == 0) break;
    for (ssize_t i = 0; i < n;) {
      const char* start = buf.data() + i;
      const char* nl = static_cast<const char*>(std::memchr(start, '\n', static_cast<size_t>(n - i)));
      const size_t len = nl ? static_cast<size_t>(nl - start) : static_cast<size_t>(n - i);
      if (line.size() + len > max_line)
        throw std::runtime_error(path + ": line " + std::to_string(r.lines + 1) + " is longer than tailsim ever writes (" +
                                 std::to_string(max_line) + " bytes): not tailsim's file, not read (move it away)");
      line.append(start, len);
      i += static_cast<ssize_t>(len);
      r.size += static_cast<long long>(len);
      if (nl) {
        ++i;
        ++r.size;
        ++r.lines;
        const bool more = fn(line, r.lines);
        line.clear();
        r.whole = r.size;
        if (!more) return r;
      }
    }
  }
  r.tail = std::move(line);
  return r;
}

std::optional<std::string> readResultFile(const std::string& path, long long max_bytes) {
  long long size = 0;
  const int fd = openResultFile(path, max_bytes, &size);
  if (fd < 0) return std::nullopt;
  const FdCloser closer{fd};
  std::string out(static_cast<size_t>(size), '\0');
  size_t got = 0;
  while (got < out.size()) {
    const ssize_t n = ::read(fd, out.data() + got, out.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw std::runtime_error("cannot read " + path + ": " + std::strerror(errno));
    if (n == 0) break;  // shrunk meanwhile
    got += static_cast<size_t>(n);
  }
  out.resize(got);
  return out;
}

namespace {
const char* const kManifestName = ".tailsim-manifest";
std::string manifestPath(const std::string& dir) { return (std::filesystem::path(dir) / kManifestName).string(); }
bool hasLine(const std::string& text, const std::string& line) {  // line with its '\n'
  return text.compare(0, line.size(), line) == 0 || text.find("\n" + line) != std::string::npos;
}
}  // namespace

bool hasManifest(const std::string& dir) { return readResultFile(manifestPath(dir)).has_value(); }

bool manifestNames(const std::string& dir, const std::string& name, const std::string& content) {
  return manifestNamesHash(dir, name, sha256Hex(content));
}

bool manifestNamesHash(const std::string& dir, const std::string& name, const std::string& sha256_hex) {
  const std::optional<std::string> m = readResultFile(manifestPath(dir));
  return m && hasLine(*m, sha256_hex + "  " + name + "\n");
}

void recordInManifest(const std::string& dir, const std::string& name, const std::string& content) {
  recordHashInManifest(dir, name, sha256Hex(content));
}

void recordHashInManifest(const std::string& dir, const std::string& name, const std::string& sha256_hex) {
  const std::string line = sha256_hex + "  " + name + "\n";
  const std::string path = manifestPath(dir);
  if (const std::optional<std::string> m = readResultFile(path); m && hasLine(*m, line)) return;
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK, 0644);
  struct stat st {};
  if (fd < 0 || ::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || st.st_nlink > 1) {
    if (fd >= 0) ::close(fd);
    throw std::runtime_error("cannot append to " + path + " (a regular file tailsim keeps there, with no other hard link)");
  }
  const ssize_t n = ::write(fd, line.data(), line.size());
  const int err = errno;
  ::close(fd);
  if (n != static_cast<ssize_t>(line.size())) throw std::system_error(err, std::generic_category(), "cannot append to " + path);
}

void compactManifest(const std::string& dir) {
  const std::optional<std::string> m = readResultFile(manifestPath(dir));
  if (!m) return;
  std::string keep;
  std::set<std::string> done;
  std::istringstream in(*m);
  for (std::string l; std::getline(in, l);) {
    if (l.size() < 67 || l.compare(64, 2, "  ") != 0) continue;
    const std::string name = l.substr(66);
    if (done.count(name)) continue;
    // read in blocks (time_series.h5 may be larger than memory); not a regular file: not named any more
    const std::optional<std::string> hash = sha256OfFile((std::filesystem::path(dir) / name).string());
    if (hash && *hash == l.substr(0, 64)) {
      keep += l + "\n";
      done.insert(name);
    }
  }
  if (keep != *m) writeFileAtomic(manifestPath(dir), keep);
}

bool ownedFile(const std::string& dir, const std::string& name, const std::optional<std::string>& content,
               const EarlierOwnFile& earlier) {
  const std::string path = (std::filesystem::path(dir) / name).string();
  std::optional<std::string> there;
  try {
    there = readResultFile(path);
  } catch (const std::exception& e) {
    throw std::runtime_error(path + " is not a regular file tailsim wrote: not replaced; move it out of " + dir);
  }
  if (!there || (content && *there == *content) || manifestNames(dir, name, *there)) return true;
  if (!earlier) return false;
  const std::optional<std::string> m = readResultFile(manifestPath(dir));
  const bool named = m && m->find("  " + name + "\n") != std::string::npos;
  return !named && earlier(*there);
}

void checkOwnedFile(const std::string& dir, const std::string& name, const std::optional<std::string>& content,
                    const EarlierOwnFile& earlier) {
  if (!ownedFile(dir, name, content, earlier))
    throw std::runtime_error((std::filesystem::path(dir) / name).string() +
                             " was not written by tailsim (or was changed since): not replaced; move it out of " + dir +
                             " or choose another --out");
}

void writeOwnedFile(const std::string& dir, const std::string& name, const std::string& content,
                    const EarlierOwnFile& earlier) {
  checkOwnedFile(dir, name, content, earlier);
  recordInManifest(dir, name, content);
  writeFileAtomic((std::filesystem::path(dir) / name).string(), content);
}

void recordWrittenFile(const std::string& dir, const std::string& name) {
  if (const std::optional<std::string> text = readResultFile((std::filesystem::path(dir) / name).string()))
    recordInManifest(dir, name, *text);
}

namespace {

// The descriptor a path names directly ("-", /dev/stdout, /dev/fd/N, ...), or -1.
int ownDescriptor(const std::string& path) {
  if (path == "-" || path == "/dev/stdout") return STDOUT_FILENO;
  if (path == "/dev/stderr") return STDERR_FILENO;
  for (const char* prefix : {"/dev/fd/", "/proc/self/fd/"}) {
    const std::string pre(prefix);
    if (path.size() > pre.size() && path.compare(0, pre.size(), pre) == 0 &&
        path.find_first_not_of("0123456789", pre.size()) == std::string::npos)
      return std::stoi(path.substr(pre.size()));
  }
  return -1;
}

void writeAllTo(int fd, const std::string& path, const std::string& contents) {
  const char* p = contents.data();
  size_t n = contents.size();
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
    }
    p += w;
    n -= static_cast<size_t>(w);
  }
}

}  // namespace

// Refuses to replace a non-empty regular file at path (or a symlink's) that does not hold `marker`
// near its start.
static void refuseForeignFile(const std::string& path, const std::string& marker) {
  struct stat st;
  if (marker.empty() || ::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || st.st_size == 0) return;
  std::ifstream in(path, std::ios::binary);
  std::string head(4096, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  if (head.find(marker) == std::string::npos)
    throw std::runtime_error(path + " exists and was not written by tailsim: not replaced (remove it, or choose "
                                    "another name)");
}

bool writeUserFile(const std::string& path, const std::string& contents, const std::string& own_marker) {
  if (path.empty()) throw std::runtime_error("empty output path");
  if (ownDescriptor(path) < 0) refuseForeignFile(path, own_marker);
  if (const int fd = ownDescriptor(path); fd >= 0) {
    writeAllTo(fd, path, contents);
    return true;
  }
  struct stat lst;
  if (::lstat(path.c_str(), &lst) != 0 || S_ISREG(lst.st_mode)) {
    writeFileAtomic(path, contents);  // a new name or a regular file: whole or not at all
    return false;
  }
  if (S_ISDIR(lst.st_mode)) throw std::runtime_error("cannot write " + path + ": it is a directory");
  // A symlink (to anything), a device, a FIFO or a socket: write through it, replace nothing.
  struct stat st;
  const bool exists = ::stat(path.c_str(), &st) == 0;
  if (exists && S_ISDIR(st.st_mode)) throw std::runtime_error("cannot write " + path + ": it is a directory");
  const bool stream = exists && !S_ISREG(st.st_mode);
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  try {
    writeAllTo(fd, path, contents);
  } catch (...) {
    ::close(fd);
    throw;
  }
  if (::close(fd) != 0) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  return stream;
}

}  // namespace tailsim
