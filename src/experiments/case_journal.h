// DIR/cases.jsonl, the resume record of the cases without a folder of their own: appending a
// finished case's line, and reading the finished cases back (docs/ARCHITECTURE.md "Result folder").
#pragma once

#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <nlohmann/json.hpp>

namespace tailsim {
namespace runner {

// DIR/cases.jsonl: the resume record of the cases that have no folder of their own (no CSV time
// series: output.time_series none, or time_series_file hdf5). One line per finished case, the JSON
// a case folder's result.json would hold, appended with one write() (O_APPEND) the moment the
// case is done; no fsync (a kill -9 loses nothing the kernel has; a power cut may lose the last
// lines, whose cases then run again). A torn last line (killed inside the write, or a full disk)
// is cut off before the next run appends (readJournal). At the end of a run the file is rewritten
// atomically with exactly the finished cases in case order, so it is the same whatever the order
// the workers finished in (and after a resume).
class CaseJournal {
 public:
  explicit CaseJournal(const std::filesystem::path& p) : path_(p) {}
  ~CaseJournal();
  CaseJournal(const CaseJournal&) = delete;
  CaseJournal& operator=(const CaseJournal&) = delete;
  void append(const std::string& line);
  void close();

 private:
  std::filesystem::path path_;
  std::mutex mu_;
  int fd_ = -1;
};

// Whether a journal line is an entry tailsim writes: an object with a string "key" and "name".
bool journalEntry(const nlohmann::json& j);

// The first line of DIR/cases.jsonl (without its newline; a file without one: all of it), read
// no further than the longest line tailsim writes; std::nullopt when absent.
std::optional<std::string> firstJournalLine(const std::filesystem::path& p);

// The finished cases of DIR/cases.jsonl by name (a later line wins), read line by line (a line
// longer than any entry tailsim writes: an error naming the file). A file whose first line is not a
// tailsim entry is not tailsim's: an error naming it, the file untouched. A last line without its
// newline (torn by a kill or a full disk: the start of an entry) is cut off the file, so the next
// append starts a line.
std::map<std::string, std::string> readJournal(const std::filesystem::path& p, bool repair);

}  // namespace runner
}  // namespace tailsim
