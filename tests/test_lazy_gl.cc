// Libhdf5 (with curl, GnuTLS, Kerberos, LDAP: 18 shared libraries) is loaded only when an
// HDF5 file is opened. OSMesa (Mesa's llvmpipe with LLVM, z3 and ICU; ~14 ms of dynamic loading) is loaded
// only when something is rendered. This binary links the whole program's libraries like the CLI does.
#include <gtest/gtest.h>

#include "analytic_test_util.h"
#include "experiments/time_series_h5.h"
#include "rendering/gl_context.h"
#include "results/time_series.h"

#include <filesystem>
#include <unistd.h>

namespace tailsim {
namespace {

// One test only, so the order is fixed: a fresh process has no OSMesa, an analytic run does not
// load it, the first GL context does (and it then works: MuJoCo finds its GL entry points).
TEST(LazyOsMesa, LoadedByTheFirstContextNotAtStartOrBySimulation) {
  EXPECT_FALSE(osMesaLoaded()) << "libOSMesa is mapped at start-up: something links it again";
  const RunResult r = testing::runFig7();
  EXPECT_TRUE(r.summary.ok) << r.summary.error;
  EXPECT_FALSE(osMesaLoaded()) << "an analytic run loaded libOSMesa";
  {
    OsMesaContext gl(16, 16);
    EXPECT_TRUE(osMesaLoaded());
  }
  EXPECT_TRUE(osMesaLoaded());  // never unloaded: MuJoCo keeps GL function pointers
}

// Each TEST is its own process (gtest_discover_tests): this one starts fresh too.
TEST(LazyHdf5, LoadedByTheFirstFileNotAtStartOrBySimulation) {
  EXPECT_FALSE(hdf5Loaded()) << "libhdf5 is mapped at start-up: something links it again";
  const RunResult r = testing::runFig7();
  EXPECT_TRUE(r.summary.ok) << r.summary.error;
  const std::string absent = (std::filesystem::temp_directory_path() / "tailsim_no_such.h5").string();
  EXPECT_FALSE(TimeSeriesH5Reader(absent).ok());  // resume check of a CSV run: no file, no library
  EXPECT_FALSE(hdf5Loaded()) << "an analytic run or an absent file loaded libhdf5";
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("tailsim_lazy_h5_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "time_series.h5").string();
  {
    TimeSeriesH5Writer w(path);
    w.write("case0", "case0", "key0", {}, "analytic", "full", r.series);
    w.publish();
  }
  EXPECT_TRUE(hdf5Loaded());
  const TimeSeriesH5Reader in(path);
  ASSERT_TRUE(in.ok());
  const TimeSeries back = in.read("case0", "analytic");
  EXPECT_EQ(back.numRows(), r.series.numRows());
  EXPECT_EQ(back.names(), r.series.names());
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace tailsim
