// The time series of a whole experiment in one HDF5 file, DIR/time_series.h5
// (`output.time_series_file: hdf5`, docs/experiment-format.md "Time-series output"):
//   /<case dir>/                 one group per case (caseDirName); attributes: "case" (its name),
//                                "key" (its resume key), and one per swept key (dotted name; a number
//                                as a double, anything else as a string)
//   /<case dir>/<model>/         one group per model run; attribute "time_series" (full | thin)
//   /<case dir>/<model>/<column> one 1-D float64 dataset per CSV column, named as the CSV column,
//                                attribute "units" ("s", "deg", "deg/s", "N m", ...; "1" for states)
//   /<case dir>/<model>          attribute "columns": the number of datasets (written last: a
//                                group is whole only with it)
// Written to a temporary file beside the target (<file>.tmp.<pid>.h5) and renamed over it (after
// fsync), so a killed run never leaves a torn published file. The runner writes each finished case
// to a file of its own this way (DIR/time_series.h5.d/<case dir>.h5) and joins them at the run's end. The C API's handles are wrapped
// (H5Handle); Debian's libhdf5 is built thread-safe, and each writer also serializes its own calls.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "results/time_series.h"

namespace tailsim {

// The unit of a column from its name's suffix (t_s -> "s", phidot_dps -> "deg/s", MzT_Nm -> "N m").
std::string columnUnits(const std::string& column);

// Whether libhdf5 is mapped into the process: it is loaded (dlopen) the first time a file is
// opened, never at start-up (tests/test_lazy_gl.cc).
bool hdf5Loaded();

// Reads a published file (never written through this class).
class TimeSeriesH5Reader {
 public:
  // Opens `path` read-only; ok() is false when it is absent or not an HDF5 file.
  explicit TimeSeriesH5Reader(const std::string& path);
  ~TimeSeriesH5Reader();
  TimeSeriesH5Reader(const TimeSeriesH5Reader&) = delete;
  TimeSeriesH5Reader& operator=(const TimeSeriesH5Reader&) = delete;
  bool ok() const;
  // Whether /<case_dir> exists with attribute "key" == key and a whole group per model: every
  // column it was written with, of one length, at least one row, t_s finite in every row.
  bool hasCase(const std::string& case_dir, const std::string& key, const std::vector<std::string>& models) const;
  // The columns of /<case_dir>/<model> in the order they were written; throws std::runtime_error.
  TimeSeries read(const std::string& case_dir, const std::string& model) const;
  // The case groups at the file's root.
  std::vector<std::string> caseDirs() const;
  long long handle() const;  // the file's hid_t (for TimeSeriesH5Writer::copyCase)
  const std::string& path() const { return path_; }

 private:
  long long file_ = -1;
  std::string path_;
};

// Where a writer builds its file: beside the target on disk, or in memory (the core driver) and
// written out whole by publish(), so a full disk fails in tailsim's own write(), never inside
// libhdf5 (whose H5Ocopy crashed on ENOSPC).
enum class H5Storage { kDisk, kMemory };

class TimeSeriesH5Writer {
 public:
  // Creates the temporary file beside `final_path` (kDisk) or in memory; throws std::runtime_error.
  // reserve_bytes (kDisk): disk space allocated for it first (fallocate beyond its end, given back
  // by publish), so the writes cannot meet a full disk; std::system_error(ENOSPC) when it is not
  // there.
  explicit TimeSeriesH5Writer(const std::string& final_path, H5Storage storage = H5Storage::kDisk,
                              long long reserve_bytes = 0);
  // Not published: the temporary file is closed and removed.
  ~TimeSeriesH5Writer();
  TimeSeriesH5Writer(const TimeSeriesH5Writer&) = delete;
  TimeSeriesH5Writer& operator=(const TimeSeriesH5Writer&) = delete;

  // /<case_dir>: created on first use with its attributes. A failed write throws
  // std::system_error(ENOSPC) when the disk is full, else std::runtime_error.
  void write(const std::string& case_dir, const std::string& case_name, const std::string& key,
             const std::map<std::string, std::string>& sweep, const std::string& model, const std::string& mode,
             const TimeSeries& ts);
  // Copies /<case_dir> (all its models) from a published file (H5Ocopy).
  void copyCase(const TimeSeriesH5Reader& from, const std::string& case_dir);
  // Closes the file, flushes it to disk and renames it over final_path (the rename is flushed too).
  // before_rename (if given) is called with the temporary file's path once it is whole on disk,
  // before the rename (to name it in a manifest first: a stop in between leaves no unnamed file).
  void publish(const std::function<void(const std::string& temp_path)>& before_rename = nullptr);

 private:
  void writeLocked(const std::string& case_dir, const std::string& case_name, const std::string& key,
                   const std::map<std::string, std::string>& sweep, const std::string& model, const std::string& mode,
                   const TimeSeries& ts);
  std::mutex mu_;
  long long file_ = -1;
  std::string final_path_, temp_path_;
  H5Storage storage_ = H5Storage::kDisk;
  int reserve_fd_ = -1;
  bool published_ = false;
};

// Runs f, which reads HDF5 files written elsewhere or earlier, in a child process: libhdf5 crashes
// (SIGSEGV) on some damaged files whatever their manifest line says (a shard received from another
// machine has a manifest that matches whatever it holds). A crash is then std::runtime_error
// "<what> is damaged: libhdf5 crashed reading it (...)", never tailsim's; f's exceptions come back with
// their message (a std::system_error with its error code, so a full disk is still ENOSPC). f's effects
// on memory stay in the child: it may only write files. Call it with no other thread using libhdf5.
void runHdf5Isolated(const std::string& what, const std::function<void()>& f);

// Copies every case group of `src` that `dst` lacks into `dst` (created when absent): joins the
// files of shard folders (tailsim merge). Throws std::runtime_error.
void mergeTimeSeriesH5(const std::string& src, const std::string& dst);

}  // namespace tailsim
