#include "experiments/case_journal.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <new>
#include <stdexcept>
#include <system_error>

#include "common/atomic_file.h"

namespace tailsim {
namespace fs = std::filesystem;
using json = nlohmann::json;
namespace runner {

CaseJournal::~CaseJournal() {
  if (fd_ >= 0) ::close(fd_);
}

void CaseJournal::append(const std::string& line) {
  std::lock_guard<std::mutex> lock(mu_);
  if (fd_ < 0) {
    // A regular file of the folder only: never through a symlink, never a FIFO or device.
    fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK, 0644);
    if (fd_ < 0) throw std::system_error(errno, std::generic_category(), "cannot open " + path_.string());
    struct stat st {};
    if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode) || st.st_nlink > 1) {
      const bool linked = S_ISREG(st.st_mode) && st.st_nlink > 1;
      ::close(fd_);
      fd_ = -1;
      throw std::runtime_error(path_.string() + (linked ? " has other hard links (the same file elsewhere): not written"
                                                        : " is not a regular file: not written"));
    }
  }
  size_t done = 0;
  while (done < line.size()) {
    const ssize_t n = ::write(fd_, line.data() + done, line.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw std::system_error(errno, std::generic_category(), "cannot append to " + path_.string());
    done += static_cast<size_t>(n);
  }
}

void CaseJournal::close() {
  std::lock_guard<std::mutex> lock(mu_);
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

// The longest line tailsim writes into cases.jsonl (a case's entry: a few kB) with a wide margin.
constexpr size_t kMaxJournalLine = size_t(1) << 22;

// Whether a journal line is an entry tailsim writes: an object with a string "key" and "name".
bool journalEntry(const json& j) {
  return j.is_object() && j.contains("key") && j["key"].is_string() && j.contains("name") && j["name"].is_string();
}

// The first line of DIR/cases.jsonl (without its newline; a file without one: all of it), read
// no further than kMaxJournalLine; std::nullopt when absent.
std::optional<std::string> firstJournalLine(const fs::path& p) {
  std::string first;
  const std::optional<LinesRead> r = readResultFileLines(p.string(), kMaxJournalLine, [&](const std::string& line, long long) {
    first = line;
    return false;
  });
  if (!r) return std::nullopt;
  return r->lines > 0 ? first : r->tail;
}

// The finished cases of DIR/cases.jsonl by name (a later line wins), read line by line (a line
// longer than any entry tailsim writes: an error naming the file). A file whose first line is not a
// tailsim entry is not tailsim's: an error naming it, the file untouched. A last line without its
// newline (torn by a kill or a full disk: the start of an entry) is cut off the file, so the next
// append starts a line.
std::map<std::string, std::string> readJournal(const fs::path& p, bool repair) {
  std::map<std::string, std::string> out;
  const auto notOurs = [&](const std::string& why) {
    return std::runtime_error(p.string() + " " + why + ": not a journal tailsim wrote, not changed (move it out of " +
                              p.parent_path().string() + " or choose another --out)");
  };
  std::optional<LinesRead> read;
  try {
    read = readResultFileLines(p.string(), kMaxJournalLine, [&](const std::string& line, long long number) {
      const json j = json::parse(line, nullptr, false);
      if (number == 1 && !journalEntry(j)) throw notOurs("line 1 is not a case entry of tailsim");
      if (journalEntry(j)) out[j["name"].get<std::string>()] = line;  // as text: see Job::entries
      return true;
    });
  } catch (const std::bad_alloc&) {
    throw std::runtime_error(p.string() + " holds more than this process can read into memory: not tailsim's journal (move it away)");
  }
  if (!read) return out;
  if (!read->tail.empty()) {
    if (read->lines == 0 && read->tail.compare(0, 2, "{\"") != 0) throw notOurs("does not start with a case entry of tailsim");
    if (repair) {
      struct stat st {};
      if (::lstat(p.c_str(), &st) == 0 && st.st_nlink > 1)
        throw notOurs("has other hard links (the same file elsewhere)");
      std::error_code ec;
      fs::resize_file(p, static_cast<uintmax_t>(read->whole), ec);
    }
  }
  return out;
}

}  // namespace runner
}  // namespace tailsim
