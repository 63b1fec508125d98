#include "experiments/time_series_h5.h"

#include <dlfcn.h>
#include <linux/falloc.h>
#include <fcntl.h>
#include <hdf5.h>  // types and constants only: libhdf5 is loaded at run time (see h5())
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <system_error>
#include <type_traits>
#include <vector>

namespace tailsim {
namespace fs = std::filesystem;
static_assert(std::is_same<hid_t, int64_t>::value || sizeof(hid_t) <= sizeof(long long), "hid_t fits in long long");

namespace {

// libhdf5 (Debian's serial build) is loaded the first time a file is opened, not at process start:
// linked, it brings curl, GnuTLS, Kerberos and LDAP (18 more shared libraries, ~5 ms of start-up
// for every process), and most runs write no HDF5 file. The functions are
// resolved by name with dlsym; hdf5.h supplies their types only (its data-type macros name global
// variables, read here through the same table). The handle is never closed.
#define TAILSIM_HDF5_FUNCTIONS(X) \
  X(H5Acreate2) \
  X(H5Aexists) \
  X(H5Aopen) \
  X(H5Aread) \
  X(H5Awrite) \
  X(H5Dcreate2) \
  X(H5Dget_space) \
  X(H5Dopen2) \
  X(H5Dread) \
  X(H5Dwrite) \
  X(H5Eset_auto2) \
  X(H5Fclose) \
  X(H5Fcreate) \
  X(H5Fflush) \
  X(H5Fget_file_image) \
  X(H5Fis_hdf5) \
  X(H5Fopen) \
  X(H5Gcreate2) \
  X(H5Gget_info) \
  X(H5Gopen2) \
  X(H5Ldelete) \
  X(H5Lexists) \
  X(H5Lget_name_by_idx) \
  X(H5Ocopy) \
  X(H5Pcreate) \
  X(H5Pset_link_creation_order) \
  X(H5Screate) \
  X(H5Screate_simple) \
  X(H5Sget_simple_extent_dims) \
  X(H5Sget_simple_extent_ndims) \
  X(H5Tcopy) \
  X(H5Tset_cset) \
  X(H5Tset_size) \
  X(H5free_memory) \
  X(H5Tclose) \
  X(H5Sclose) \
  X(H5Aclose) \
  X(H5Gclose) \
  X(H5Dclose) \
  X(H5Pclose) \
  X(H5Pset_fapl_core) \
  X(H5dont_atexit) \
  X(H5open)

struct Hdf5Api {
#define TAILSIM_HDF5_MEMBER(name) decltype(&::name) name = nullptr;
  TAILSIM_HDF5_FUNCTIONS(TAILSIM_HDF5_MEMBER)
#undef TAILSIM_HDF5_MEMBER
  const hid_t* native_double_g = nullptr;
  const hid_t* ieee_f64le_g = nullptr;
  const hid_t* c_s1_g = nullptr;
  const hid_t* group_create_g = nullptr;
  const hid_t* file_access_g = nullptr;
  // The library's predefined types and property classes (H5T_NATIVE_DOUBLE, ...): set by H5open().
  hid_t native_double() const { return *native_double_g; }
  hid_t ieee_f64le() const { return *ieee_f64le_g; }
  hid_t c_s1() const { return *c_s1_g; }
  hid_t group_create() const { return *group_create_g; }
  hid_t file_access() const { return *file_access_g; }
};

Hdf5Api loadHdf5() {
  void* lib = nullptr;
  std::string why;
  for (const char* name : {TAILSIM_HDF5_SONAME, "libhdf5_serial.so", "libhdf5.so"}) {
    lib = ::dlopen(name, RTLD_NOW | RTLD_LOCAL);
    if (lib) break;
    if (const char* e = ::dlerror()) why = e;
  }
  if (!lib)
    throw std::runtime_error("HDF5: cannot load " TAILSIM_HDF5_SONAME " (" + why +
                             "); is libhdf5-103-1 installed (scripts/setup.sh)?");
  Hdf5Api api;
  std::string missing;
  const auto symbol = [&](const char* name) {
    void* p = ::dlsym(lib, name);
    if (!p) missing += std::string(missing.empty() ? "" : ", ") + name;
    return p;
  };
#define TAILSIM_HDF5_RESOLVE(name) api.name = reinterpret_cast<decltype(api.name)>(symbol(#name));
  TAILSIM_HDF5_FUNCTIONS(TAILSIM_HDF5_RESOLVE)
#undef TAILSIM_HDF5_RESOLVE
  api.native_double_g = static_cast<const hid_t*>(symbol("H5T_NATIVE_DOUBLE_g"));
  api.ieee_f64le_g = static_cast<const hid_t*>(symbol("H5T_IEEE_F64LE_g"));
  api.c_s1_g = static_cast<const hid_t*>(symbol("H5T_C_S1_g"));
  api.group_create_g = static_cast<const hid_t*>(symbol("H5P_CLS_GROUP_CREATE_ID_g"));
  api.file_access_g = static_cast<const hid_t*>(symbol("H5P_CLS_FILE_ACCESS_ID_g"));
  if (!missing.empty()) throw std::runtime_error("HDF5: " TAILSIM_HDF5_SONAME " lacks " + missing);
  // No clean-up handler at exit: after a failed write (a full disk) the library keeps the file's
  // dirty cache, and its atexit handler flushing it again crashed the process (SIGSEGV) after the
  // error was reported. Every file is closed here explicitly, and a failed one is deleted.
  if (api.H5dont_atexit() < 0) throw std::runtime_error("HDF5: H5dont_atexit failed");
  if (api.H5open() < 0) throw std::runtime_error("HDF5: H5open failed");
  // The library's error stacks are not printed (stderr gets tailsim's one-line errors): every call
  // is checked here and a failure becomes an exception naming the file.
  api.H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  return api;
}

// H5F_ACC_* expand to H5check()/H5open() calls in hdf5.h: their values (H5Fpublic.h), used plainly.
constexpr unsigned kAccRdonly = 0x0000u, kAccRdwr = 0x0001u, kAccTrunc = 0x0002u, kAccExcl = 0x0004u;

// Loaded once per process (thread-safe static initialisation); a failed load is retried next time.
const Hdf5Api& h5() {
  static const Hdf5Api api = loadHdf5();
  return api;
}


// One HDF5 identifier, closed by its own close function when it goes out of scope.
class H5Handle {
 public:
  H5Handle() = default;
  H5Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~H5Handle() { reset(); }
  H5Handle(H5Handle&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = -1; }
  H5Handle& operator=(H5Handle&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = o.id_;
      close_ = o.close_;
      o.id_ = -1;
    }
    return *this;
  }
  H5Handle(const H5Handle&) = delete;
  H5Handle& operator=(const H5Handle&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }
  void reset() {
    if (id_ >= 0 && close_) close_(id_);
    id_ = -1;
  }

 private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error("HDF5: " + what); }

// A failed write to `file`: std::system_error(ENOSPC) when its filesystem is full (the library
// does not pass errno on; a run stops starting cases on ENOSPC), else std::runtime_error.
[[noreturn]] void failWrite(const std::string& file, const std::string& what) {
  struct statvfs st {};
  const fs::path dir = fs::path(file).parent_path();
  if (::statvfs(dir.empty() ? "." : dir.c_str(), &st) == 0 &&
      static_cast<unsigned long long>(st.f_bavail) * st.f_frsize < 64 * 1024)
    throw std::system_error(ENOSPC, std::generic_category(), what + " (writing " + file + ")");
  throw std::runtime_error(what + " (writing " + file + ")");
}

H5Handle check(H5Handle h, const std::string& what) {
  if (!h.ok()) fail(what);
  return h;
}

// A variable-length UTF-8 string type (h5py reads it as str).
H5Handle stringType() {
  H5Handle t(h5().H5Tcopy(h5().c_s1()), h5().H5Tclose);
  h5().H5Tset_size(t.get(), H5T_VARIABLE);
  h5().H5Tset_cset(t.get(), H5T_CSET_UTF8);
  return t;
}

void putString(hid_t obj, const std::string& name, const std::string& value) {
  const H5Handle t = stringType();
  const H5Handle space(h5().H5Screate(H5S_SCALAR), h5().H5Sclose);
  const H5Handle a = check(H5Handle(h5().H5Acreate2(obj, name.c_str(), t.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), h5().H5Aclose),
                           "cannot create attribute " + name);
  const char* p = value.c_str();
  if (h5().H5Awrite(a.get(), t.get(), &p) < 0) fail("cannot write attribute " + name);
}

void putNumber(hid_t obj, const std::string& name, double value) {
  const H5Handle space(h5().H5Screate(H5S_SCALAR), h5().H5Sclose);
  const H5Handle a = check(
      H5Handle(h5().H5Acreate2(obj, name.c_str(), h5().ieee_f64le(), space.get(), H5P_DEFAULT, H5P_DEFAULT), h5().H5Aclose),
      "cannot create attribute " + name);
  if (h5().H5Awrite(a.get(), h5().native_double(), &value) < 0) fail("cannot write attribute " + name);
}

std::string getString(hid_t obj, const std::string& name) {
  if (h5().H5Aexists(obj, name.c_str()) <= 0) return {};
  const H5Handle a(h5().H5Aopen(obj, name.c_str(), H5P_DEFAULT), h5().H5Aclose);
  if (!a.ok()) return {};
  const H5Handle t = stringType();
  char* p = nullptr;
  if (h5().H5Aread(a.get(), t.get(), &p) < 0 || !p) return {};
  std::string s(p);
  h5().H5free_memory(p);
  return s;
}

bool linkExists(hid_t loc, const std::string& name) { return h5().H5Lexists(loc, name.c_str(), H5P_DEFAULT) > 0; }

// A number as written ("0.25", "-90"): its value, or false when it is not one.
bool asNumber(const std::string& s, double& out) {
  if (s.empty()) return false;
  char* end = nullptr;
  out = std::strtod(s.c_str(), &end);
  return end && *end == '\0';
}

// Names of a group's links in creation order when tracked, else by name.
std::vector<std::string> linkNames(hid_t group, bool creation_order) {
  std::vector<std::string> out;
  H5G_info_t info{};
  if (h5().H5Gget_info(group, &info) < 0) return out;
  const H5_index_t idx = creation_order ? H5_INDEX_CRT_ORDER : H5_INDEX_NAME;
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    const ssize_t n = h5().H5Lget_name_by_idx(group, ".", idx, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    if (n < 0) continue;
    std::string name(static_cast<size_t>(n) + 1, '\0');
    h5().H5Lget_name_by_idx(group, ".", idx, H5_ITER_INC, i, name.data(), name.size(), H5P_DEFAULT);
    name.resize(static_cast<size_t>(n));
    out.push_back(name);
  }
  return out;
}

// Group creation property list that tracks creation order (so columns read back in CSV order).
H5Handle orderedGroupProps() {
  H5Handle p(h5().H5Pcreate(h5().group_create()), h5().H5Pclose);
  h5().H5Pset_link_creation_order(p.get(), H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED);
  return p;
}

// Whether /<case>/<model> is whole: as many 1-D datasets of one length as its "columns" attribute
// says (written last, so a group torn by a crash or edited lacks it or disagrees), at least one
// row, and a first column (t_s) that is not NaN: finite in every row when it is t_s, finite
// somewhere otherwise (a group of NaN is not a result).
bool modelComplete(hid_t case_group, const std::string& model) {
  if (!linkExists(case_group, model)) return false;
  const H5Handle g(h5().H5Gopen2(case_group, model.c_str(), H5P_DEFAULT), h5().H5Gclose);
  if (!g.ok() || h5().H5Aexists(g.get(), "columns") <= 0) return false;
  double want = -1;
  {
    const H5Handle a(h5().H5Aopen(g.get(), "columns", H5P_DEFAULT), h5().H5Aclose);
    if (!a.ok() || h5().H5Aread(a.get(), h5().native_double(), &want) < 0) return false;
  }
  const std::vector<std::string> names = linkNames(g.get(), true);
  if (names.empty() || static_cast<double>(names.size()) != want) return false;
  hsize_t rows = 0;
  for (size_t k = 0; k < names.size(); ++k) {
    const H5Handle d(h5().H5Dopen2(g.get(), names[k].c_str(), H5P_DEFAULT), h5().H5Dclose);
    if (!d.ok()) return false;
    const H5Handle sp(h5().H5Dget_space(d.get()), h5().H5Sclose);
    hsize_t n = 0;
    if (!sp.ok() || h5().H5Sget_simple_extent_ndims(sp.get()) != 1 || h5().H5Sget_simple_extent_dims(sp.get(), &n, nullptr) < 0)
      return false;
    if (k == 0) rows = n;
    if (n != rows || n == 0) return false;
    if (k != 0) continue;
    std::vector<double> v(n);
    if (h5().H5Dread(d.get(), h5().native_double(), H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) < 0) return false;
    const auto finite = [](double x) { return std::isfinite(x); };
    if (names[k] == "t_s" ? !std::all_of(v.begin(), v.end(), finite) : std::none_of(v.begin(), v.end(), finite))
      return false;
  }
  return true;
}

// fsync of a directory, so a rename in it survives a power cut.
void syncDirectory(const fs::path& dir) {
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

bool hdf5Loaded() {
  void* lib = ::dlopen(TAILSIM_HDF5_SONAME, RTLD_NOW | RTLD_NOLOAD);  // takes a reference when mapped
  if (lib) ::dlclose(lib);
  return lib != nullptr;
}

std::string columnUnits(const std::string& column) {
  const size_t u = column.rfind('_');
  const std::string s = u == std::string::npos ? std::string() : column.substr(u + 1);
  if (s == "s") return "s";
  if (s == "deg") return "deg";
  if (s == "dps") return "deg/s";
  if (s == "dps2") return "deg/s^2";
  if (s == "m") return "m";
  if (s == "mps") return "m/s";
  if (s == "Nm") return "N m";
  if (s == "N") return "N";
  if (s == "kgm2") return "kg m^2";
  return "1";  // rot_state, trans_state: 0 stuck, 1 slipping
}

// ---- reader ----------------------------------------------------------------------------------

TimeSeriesH5Reader::TimeSeriesH5Reader(const std::string& path) : path_(path) {
  std::error_code ec;
  // A regular file only: not a symlink (never read through to outside the folder), FIFO or device.
  if (!fs::is_regular_file(fs::symlink_status(path, ec)) || h5().H5Fis_hdf5(path.c_str()) <= 0) return;
  file_ = h5().H5Fopen(path.c_str(), kAccRdonly, H5P_DEFAULT);
}

TimeSeriesH5Reader::~TimeSeriesH5Reader() {
  if (file_ >= 0) h5().H5Fclose(file_);
}

bool TimeSeriesH5Reader::ok() const { return file_ >= 0; }
long long TimeSeriesH5Reader::handle() const { return file_; }

bool TimeSeriesH5Reader::hasCase(const std::string& case_dir, const std::string& key,
                                 const std::vector<std::string>& models) const {
  if (file_ < 0 || !linkExists(file_, case_dir)) return false;
  const H5Handle g(h5().H5Gopen2(file_, case_dir.c_str(), H5P_DEFAULT), h5().H5Gclose);
  if (!g.ok() || getString(g.get(), "key") != key) return false;
  for (const std::string& m : models)
    if (!modelComplete(g.get(), m)) return false;
  return true;
}

std::vector<std::string> TimeSeriesH5Reader::caseDirs() const {
  if (file_ < 0) return {};
  const H5Handle root(h5().H5Gopen2(file_, "/", H5P_DEFAULT), h5().H5Gclose);
  return root.ok() ? linkNames(root.get(), false) : std::vector<std::string>{};
}

TimeSeries TimeSeriesH5Reader::read(const std::string& case_dir, const std::string& model) const {
  const std::string where = path_ + ":/" + case_dir + "/" + model;
  if (file_ < 0) throw std::runtime_error("cannot read " + path_ + " (absent or not an HDF5 file)");
  if (!linkExists(file_, case_dir) || !linkExists(file_, case_dir + "/" + model))
    throw std::runtime_error(where + " does not exist");
  const H5Handle g(h5().H5Gopen2(file_, (case_dir + "/" + model).c_str(), H5P_DEFAULT), h5().H5Gclose);
  if (!g.ok()) throw std::runtime_error("cannot open " + where);
  TimeSeries ts;
  std::vector<std::vector<double>> cols;
  for (const std::string& name : linkNames(g.get(), true)) {
    const H5Handle d(h5().H5Dopen2(g.get(), name.c_str(), H5P_DEFAULT), h5().H5Dclose);
    const H5Handle sp(d.ok() ? h5().H5Dget_space(d.get()) : -1, h5().H5Sclose);
    hsize_t n = 0;
    if (!sp.ok() || h5().H5Sget_simple_extent_ndims(sp.get()) != 1 || h5().H5Sget_simple_extent_dims(sp.get(), &n, nullptr) < 0)
      throw std::runtime_error(where + "/" + name + " is not a 1-D dataset");
    std::vector<double> v(n);
    if (n && h5().H5Dread(d.get(), h5().native_double(), H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) < 0)
      throw std::runtime_error("cannot read " + where + "/" + name);
    if (!cols.empty() && v.size() != cols.front().size())
      throw std::runtime_error(where + ": columns of different lengths");
    ts.addColumn(name);
    cols.push_back(std::move(v));
  }
  const size_t rows = cols.empty() ? 0 : cols.front().size();
  ts.reserveRows(rows);
  std::vector<double> row(cols.size());
  for (size_t k = 0; k < rows; ++k) {
    for (size_t c = 0; c < cols.size(); ++c) row[c] = cols[c][k];
    ts.appendRow(row);
  }
  return ts;
}

// ---- writer ----------------------------------------------------------------------------------

TimeSeriesH5Writer::TimeSeriesH5Writer(const std::string& final_path, H5Storage storage, long long reserve_bytes)
    : final_path_(final_path), storage_(storage) {
  temp_path_ = final_path + ".tailsim-tmp." + std::to_string(::getpid()) + ".h5";
  if (storage == H5Storage::kMemory) {
    // The core driver: the file is built in memory and written out by publish() (writeImage).
    const H5Handle fapl(h5().H5Pcreate(h5().file_access()), h5().H5Pclose);
    if (!fapl.ok() || h5().H5Pset_fapl_core(fapl.get(), 64 * 1024, 0) < 0) fail("cannot set up an in-memory file");
    file_ = h5().H5Fcreate(temp_path_.c_str(), kAccTrunc, H5P_DEFAULT, fapl.get());
    if (file_ < 0) fail("cannot create an in-memory file for " + final_path);
    return;
  }
  file_ = h5().H5Fcreate(temp_path_.c_str(), kAccTrunc, H5P_DEFAULT, H5P_DEFAULT);
  if (file_ < 0) failWrite(temp_path_, "HDF5: cannot create");
  if (reserve_bytes > 0) {
    reserve_fd_ = ::open(temp_path_.c_str(), O_WRONLY | O_CLOEXEC);
    if (reserve_fd_ >= 0 && ::fallocate(reserve_fd_, FALLOC_FL_KEEP_SIZE, 0, reserve_bytes) != 0) {
      const int err = errno;
      ::close(reserve_fd_);
      reserve_fd_ = -1;
      if (err != EOPNOTSUPP && err != ENOSYS) {  // (no reservation where the filesystem cannot make one)
        h5().H5Fclose(file_);
        file_ = -1;
        std::error_code ec;
        fs::remove(temp_path_, ec);
        throw std::system_error(err, std::generic_category(),
                                "HDF5: cannot reserve " + std::to_string(reserve_bytes) + " bytes for " + final_path);
      }
    }
  }
}

TimeSeriesH5Writer::~TimeSeriesH5Writer() {
  if (reserve_fd_ >= 0) ::close(reserve_fd_);
  if (published_) return;
  if (file_ >= 0) h5().H5Fclose(file_);
  std::error_code ec;
  if (storage_ == H5Storage::kDisk) fs::remove(temp_path_, ec);
}

void TimeSeriesH5Writer::write(const std::string& case_dir, const std::string& case_name, const std::string& key,
                               const std::map<std::string, std::string>& sweep, const std::string& model,
                               const std::string& mode, const TimeSeries& ts) {
  std::lock_guard<std::mutex> lock(mu_);
  try {
    writeLocked(case_dir, case_name, key, sweep, model, mode, ts);
  } catch (const std::runtime_error& ex) {
    failWrite(temp_path_, ex.what());
  }
}

void TimeSeriesH5Writer::writeLocked(const std::string& case_dir, const std::string& case_name, const std::string& key,
                                     const std::map<std::string, std::string>& sweep, const std::string& model,
                                     const std::string& mode, const TimeSeries& ts) {
  if (file_ < 0) fail("cannot write to " + temp_path_ + ": it is closed");
  H5Handle cg;
  if (linkExists(file_, case_dir)) {
    cg = H5Handle(h5().H5Gopen2(file_, case_dir.c_str(), H5P_DEFAULT), h5().H5Gclose);
  } else {
    cg = check(H5Handle(h5().H5Gcreate2(file_, case_dir.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), h5().H5Gclose),
               "cannot create group /" + case_dir + " in " + temp_path_);
    putString(cg.get(), "case", case_name);
    putString(cg.get(), "key", key);
    for (const auto& [k, v] : sweep) {
      double x = 0;
      if (asNumber(v, x)) putNumber(cg.get(), k, x);
      else putString(cg.get(), k, v);
    }
  }
  if (linkExists(cg.get(), model)) h5().H5Ldelete(cg.get(), model.c_str(), H5P_DEFAULT);  // a re-run case
  const H5Handle gp = orderedGroupProps();
  const H5Handle mg = check(H5Handle(h5().H5Gcreate2(cg.get(), model.c_str(), H5P_DEFAULT, gp.get(), H5P_DEFAULT), h5().H5Gclose),
                            "cannot create group /" + case_dir + "/" + model);
  putString(mg.get(), "time_series", mode);
  const hsize_t n = ts.numRows();
  const H5Handle space(h5().H5Screate_simple(1, &n, nullptr), h5().H5Sclose);
  for (size_t c = 0; c < ts.numColumns(); ++c) {
    const std::string& name = ts.names()[c];
    const H5Handle d = check(H5Handle(h5().H5Dcreate2(mg.get(), name.c_str(), h5().ieee_f64le(), space.get(), H5P_DEFAULT,
                                                 H5P_DEFAULT, H5P_DEFAULT),
                                      h5().H5Dclose),
                             "cannot create dataset " + name);
    if (n && h5().H5Dwrite(d.get(), h5().native_double(), H5S_ALL, H5S_ALL, H5P_DEFAULT, ts.values(static_cast<int>(c)).data()) < 0)
      fail("cannot write dataset /" + case_dir + "/" + model + "/" + name);
    putString(d.get(), "units", columnUnits(name));
  }
  putNumber(mg.get(), "columns", static_cast<double>(ts.numColumns()));  // last: the group is whole
}

void TimeSeriesH5Writer::copyCase(const TimeSeriesH5Reader& from, const std::string& case_dir) {
  std::lock_guard<std::mutex> lock(mu_);
  if (linkExists(file_, case_dir)) h5().H5Ldelete(file_, case_dir.c_str(), H5P_DEFAULT);
  if (h5().H5Ocopy(static_cast<hid_t>(from.handle()), case_dir.c_str(), file_, case_dir.c_str(), H5P_DEFAULT, H5P_DEFAULT) < 0)
    failWrite(temp_path_, "HDF5: cannot copy /" + case_dir + " from " + from.path());
}

namespace {
// Writes bytes to `temp`, flushes them to disk, calls before_rename (if any) and renames it over
// `path`; std::system_error.
void writeDurably(const std::string& temp, const std::string& path, const std::vector<char>& bytes,
                  const std::function<void(const std::string&)>& before_rename) {
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd < 0) throw std::system_error(errno, std::generic_category(), "cannot write " + temp);
  size_t done = 0;
  int err = 0;
  while (done < bytes.size() && err == 0) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno != EINTR) err = errno;
    if (n > 0) done += static_cast<size_t>(n);
  }
  if (err == 0 && ::fsync(fd) != 0) err = errno;
  if (::close(fd) != 0 && err == 0) err = errno;
  if (err == 0 && before_rename) {
    try {
      before_rename(temp);
    } catch (...) {
      ::unlink(temp.c_str());
      throw;
    }
  }
  if (err == 0 && ::rename(temp.c_str(), path.c_str()) != 0) err = errno;
  if (err != 0) {
    ::unlink(temp.c_str());
    throw std::system_error(err, std::generic_category(), "cannot write " + path);
  }
  // The directory is not flushed (a case's file per fsync of its folder doubled the cost): after a
  // power cut the rename may be lost with the journal line after it (no fsync either), and the
  // case runs again; a file that is there is whole (fsync before the rename), and a resume checks
  // every group it takes (hasCase).
}
}  // namespace

void TimeSeriesH5Writer::publish(const std::function<void(const std::string&)>& before_rename) {
  std::lock_guard<std::mutex> lock(mu_);
  if (published_) return;
  if (file_ < 0) fail("cannot publish " + temp_path_ + ": an earlier write to it failed");
  if (storage_ == H5Storage::kMemory) {
    const bool flushed = h5().H5Fflush(file_, H5F_SCOPE_GLOBAL) >= 0;  // (the image's superblock is current)
    const ssize_t n = flushed ? h5().H5Fget_file_image(file_, nullptr, 0) : -1;
    std::vector<char> image(n > 0 ? static_cast<size_t>(n) : 0);
    const bool got = n > 0 && h5().H5Fget_file_image(file_, image.data(), image.size()) == n;
    h5().H5Fclose(file_);
    file_ = -1;
    if (!got) fail("cannot take the in-memory image of " + final_path_);
    writeDurably(temp_path_, final_path_, image, before_rename);
    published_ = true;
    return;
  }
  const herr_t closed = h5().H5Fclose(file_);
  file_ = -1;
  if (closed < 0) failWrite(temp_path_, "HDF5: cannot close");
  // HDF5 wrote through its own descriptor; flush it to disk before the rename publishes it.
  const int fd = reserve_fd_ >= 0 ? reserve_fd_ : ::open(temp_path_.c_str(), O_RDONLY | O_CLOEXEC);
  reserve_fd_ = -1;
  if (fd >= 0) {
    struct stat st {};
    if (::fstat(fd, &st) == 0)  // the reserved space beyond the end is given back
      (void)::fallocate(fd, FALLOC_FL_PUNCH_HOLE | FALLOC_FL_KEEP_SIZE, st.st_size, 1LL << 40);
    ::fsync(fd);
    ::close(fd);
  }
  if (before_rename) before_rename(temp_path_);  // (the destructor removes the temporary on a throw)
  std::error_code ec;
  fs::rename(temp_path_, final_path_, ec);
  if (ec) fail("cannot rename " + temp_path_ + " to " + final_path_ + ": " + ec.message());
  syncDirectory(fs::path(final_path_).parent_path());
  published_ = true;
}

void runHdf5Isolated(const std::string& what, const std::function<void()>& f) {
  int pipe_fd[2];
  if (::pipe2(pipe_fd, O_CLOEXEC) != 0) throw std::system_error(errno, std::generic_category(), "cannot make a pipe");
  std::fflush(nullptr);  // (nothing buffered is written twice)
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int err = errno;
    ::close(pipe_fd[0]);
    ::close(pipe_fd[1]);
    throw std::system_error(err, std::generic_category(), "cannot start a process to read " + what);
  }
  if (pid == 0) {  // the child: f, then its outcome down the pipe ("<errno>\n<message>"), and _exit (no
                   // exit handlers: libhdf5's crashed on a full disk)
    // The child dies with tailsim (kill -9 included): it shares the folder lock's open file, so an
    // orphan would hold the lock, and write into the folder, after the run that started it is gone.
    if (::prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || ::getppid() != parent) ::_exit(1);
    ::close(pipe_fd[0]);
    std::string out = "0\n";
    int code = 0;
    try {
      f();
    } catch (const std::system_error& e) {
      out = std::to_string(e.code().value()) + "\n" + e.what();
      code = 1;
    } catch (const std::exception& e) {
      out += e.what();
      code = 1;
    } catch (...) {
      out += "unknown error";
      code = 1;
    }
    for (size_t done = 0; done < out.size();) {
      const ssize_t n = ::write(pipe_fd[1], out.data() + done, out.size() - done);
      if (n <= 0 && errno != EINTR) break;
      if (n > 0) done += static_cast<size_t>(n);
    }
    ::_exit(code);
  }
  ::close(pipe_fd[1]);
  std::string msg;
  char buf[4096];
  for (ssize_t n; (n = ::read(pipe_fd[0], buf, sizeof buf)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    msg.append(buf, static_cast<size_t>(n));
  }
  ::close(pipe_fd[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFSIGNALED(status))
    throw std::runtime_error(what + " is damaged: libhdf5 crashed reading it (signal " + std::to_string(WTERMSIG(status)) +
                             ", " + strsignal(WTERMSIG(status)) +
                             ") although its manifest line matches it (copied from elsewhere?): move it away and run "
                             "its cases again");
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
  const size_t nl = msg.find('\n');
  const int err = nl == std::string::npos ? 0 : std::atoi(msg.substr(0, nl).c_str());
  std::string text = nl == std::string::npos ? std::string("reading " + what + " failed") : msg.substr(nl + 1);
  if (err != 0) {  // std::system_error's what() ends in ": <strerror>", which its constructor adds again
    const std::string tail = std::string(": ") + std::strerror(err);
    if (text.size() >= tail.size() && text.compare(text.size() - tail.size(), tail.size(), tail) == 0)
      text.erase(text.size() - tail.size());
    throw std::system_error(err, std::generic_category(), text);
  }
  throw std::runtime_error(text);
}

void mergeTimeSeriesH5(const std::string& src, const std::string& dst) {
  const TimeSeriesH5Reader in(src);
  if (!in.ok()) throw std::runtime_error("merge: " + src + " is not a readable HDF5 file (truncated or corrupt?)");
  std::error_code ec;
  const bool exists = fs::exists(dst, ec);
  hid_t out = exists ? h5().H5Fopen(dst.c_str(), kAccRdwr, H5P_DEFAULT)
                     : h5().H5Fcreate(dst.c_str(), kAccExcl, H5P_DEFAULT, H5P_DEFAULT);
  if (out < 0) failWrite(dst, "merge: cannot open " + dst);
  {  // space for the copy, reserved before libhdf5 writes (H5Ocopy crashed on a full disk)
    const long long bytes = static_cast<long long>(fs::file_size(src, ec));
    const int fd = ::open(dst.c_str(), O_WRONLY | O_CLOEXEC);
    struct stat st {};
    const int err = fd < 0 || ::fstat(fd, &st) != 0 ? errno
                    : ::fallocate(fd, FALLOC_FL_KEEP_SIZE, st.st_size, bytes + bytes / 2 + (64 << 10)) != 0 ? errno : 0;
    if (fd >= 0) ::close(fd);
    if (err != 0 && err != EOPNOTSUPP && err != ENOSYS) {
      h5().H5Fclose(out);
      throw std::system_error(err, std::generic_category(), "merge: cannot reserve space for " + src + " in " + dst);
    }
  }
  std::string error;
  {
    const H5Handle root(h5().H5Gopen2(static_cast<hid_t>(in.handle()), "/", H5P_DEFAULT), h5().H5Gclose);
    if (!root.ok()) error = "merge: cannot read " + src + " (truncated or corrupt?)";
    for (const std::string& name : root.ok() ? linkNames(root.get(), false) : std::vector<std::string>{}) {
      if (linkExists(out, name)) continue;  // an earlier shard's (the runner has checked they agree)
      if (h5().H5Ocopy(static_cast<hid_t>(in.handle()), name.c_str(), out, name.c_str(), H5P_DEFAULT, H5P_DEFAULT) < 0) {
        error = "merge: cannot copy /" + name + " from " + src + " into " + dst;
        break;
      }
    }
  }
  const bool closed = h5().H5Fclose(out) >= 0;
  if (error.empty() && !closed) error = "merge: cannot write " + dst;
  if (const int fd = ::open(dst.c_str(), O_WRONLY | O_CLOEXEC); fd >= 0) {  // the reserved space beyond the end back
    struct stat st {};
    if (::fstat(fd, &st) == 0) (void)::fallocate(fd, FALLOC_FL_PUNCH_HOLE | FALLOC_FL_KEEP_SIZE, st.st_size, 1LL << 40);
    ::close(fd);
  }
  if (!error.empty()) failWrite(dst, error);
}

}  // namespace tailsim
