#include "experiments/time_series_h5.h"

#include <dlfcn.h>
#include <fcntl.h>
#include <hdf5.h>  // types and constants only: libhdf5 is loaded at run time (see h5())
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <type_traits>
#include <vector>

namespace tailsim {
namespace fs = std::filesystem;
static_assert(std::is_same<hid_t, int64_t>::value || sizeof(hid_t) <= sizeof(long long), "hid_t fits in long long");

namespace {

// libhdf5 (Debian's serial build) is loaded the first time a file is opened, not at process start:
// linked, it brings curl, GnuTLS, Kerberos and LDAP (18 more shared libraries, ~5 ms of start-up
// for every process; issue 13 item 2), and most runs write no HDF5 file. The functions are
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
  X(H5Fclose) \
  X(H5Fcreate) \
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
  X(H5open)

struct Hdf5Api {
#define TAILSIM_HDF5_MEMBER(name) decltype(&::name) name = nullptr;
  TAILSIM_HDF5_FUNCTIONS(TAILSIM_HDF5_MEMBER)
#undef TAILSIM_HDF5_MEMBER
  const hid_t* native_double_g = nullptr;
  const hid_t* ieee_f64le_g = nullptr;
  const hid_t* c_s1_g = nullptr;
  const hid_t* group_create_g = nullptr;
  // The library's predefined types and property classes (H5T_NATIVE_DOUBLE, ...): set by H5open().
  hid_t native_double() const { return *native_double_g; }
  hid_t ieee_f64le() const { return *ieee_f64le_g; }
  hid_t c_s1() const { return *c_s1_g; }
  hid_t group_create() const { return *group_create_g; }
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
  if (!missing.empty()) throw std::runtime_error("HDF5: " TAILSIM_HDF5_SONAME " lacks " + missing);
  if (api.H5open() < 0) throw std::runtime_error("HDF5: H5open failed");
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
  if (!fs::is_regular_file(path, ec) || h5().H5Fis_hdf5(path.c_str()) <= 0) return;
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
    if (!linkExists(g.get(), m)) return false;
  return true;
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

TimeSeriesH5Writer::TimeSeriesH5Writer(const std::string& final_path) : final_path_(final_path) {
  temp_path_ = final_path + ".tmp." + std::to_string(::getpid()) + ".h5";
  file_ = h5().H5Fcreate(temp_path_.c_str(), kAccTrunc, H5P_DEFAULT, H5P_DEFAULT);
  if (file_ < 0) throw std::runtime_error("HDF5: cannot create " + temp_path_);
}

TimeSeriesH5Writer::~TimeSeriesH5Writer() {
  if (published_) return;
  if (file_ >= 0) h5().H5Fclose(file_);
  std::error_code ec;
  fs::remove(temp_path_, ec);
}

void TimeSeriesH5Writer::write(const std::string& case_dir, const std::string& case_name, const std::string& key,
                               const std::map<std::string, std::string>& sweep, const std::string& model,
                               const std::string& mode, const TimeSeries& ts) {
  std::lock_guard<std::mutex> lock(mu_);
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
}

void TimeSeriesH5Writer::copyCase(const TimeSeriesH5Reader& from, const std::string& case_dir) {
  std::lock_guard<std::mutex> lock(mu_);
  if (linkExists(file_, case_dir)) h5().H5Ldelete(file_, case_dir.c_str(), H5P_DEFAULT);
  if (h5().H5Ocopy(static_cast<hid_t>(from.handle()), case_dir.c_str(), file_, case_dir.c_str(), H5P_DEFAULT, H5P_DEFAULT) < 0)
    fail("cannot copy /" + case_dir + " into " + temp_path_);
}

void TimeSeriesH5Writer::publish() {
  std::lock_guard<std::mutex> lock(mu_);
  if (published_) return;
  const herr_t closed = h5().H5Fclose(file_);
  file_ = -1;
  if (closed < 0) fail("cannot close " + temp_path_);
  // HDF5 wrote through its own descriptor; flush it to disk before the rename publishes it.
  const int fd = ::open(temp_path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
  std::error_code ec;
  fs::rename(temp_path_, final_path_, ec);
  if (ec) fail("cannot rename " + temp_path_ + " to " + final_path_ + ": " + ec.message());
  published_ = true;
}

void mergeTimeSeriesH5(const std::string& src, const std::string& dst) {
  const TimeSeriesH5Reader in(src);
  if (!in.ok()) throw std::runtime_error("merge: " + src + " is not an HDF5 file");
  std::error_code ec;
  const bool exists = fs::exists(dst, ec);
  const H5Handle out(exists ? h5().H5Fopen(dst.c_str(), kAccRdwr, H5P_DEFAULT)
                            : h5().H5Fcreate(dst.c_str(), kAccExcl, H5P_DEFAULT, H5P_DEFAULT),
                     h5().H5Fclose);
  if (!out.ok()) throw std::runtime_error("merge: cannot open " + dst);
  const H5Handle root(h5().H5Gopen2(static_cast<hid_t>(in.handle()), "/", H5P_DEFAULT), h5().H5Gclose);
  for (const std::string& name : linkNames(root.get(), false)) {
    if (linkExists(out.get(), name)) continue;  // an earlier shard's
    if (h5().H5Ocopy(static_cast<hid_t>(in.handle()), name.c_str(), out.get(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT) < 0)
      throw std::runtime_error("merge: cannot copy /" + name + " from " + src);
  }
}

}  // namespace tailsim
