// The folder lock (experiments/experiment_runner.h FolderLock) after a run is killed while its
// HDF5 helper process (runHdf5Isolated) works: the helper dies with the run, so the next run into
// the folder takes the lock at once instead of "in use by another tailsim run".
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "experiments/experiment_runner.h"
#include "experiments/time_series_h5.h"

namespace tailsim {
namespace {

TEST(FolderLock, ARunKilledDuringItsHdf5HelperLeavesTheFolderFree) {
  char tmpl[] = "/tmp/tailsim_lock_XXXXXX";
  ASSERT_NE(::mkdtemp(tmpl), nullptr);
  const std::string dir = std::string(tmpl) + "/out";
  int sync[2];
  ASSERT_EQ(::pipe(sync), 0);
  const pid_t run = ::fork();
  ASSERT_GE(run, 0);
  if (run == 0) {  // the "run": holds the lock, then waits in its HDF5 helper
    ::close(sync[0]);
    try {
      FolderLock lock(dir);
      runHdf5Isolated("a test helper", [&] {
        const char started = 's';
        (void)!::write(sync[1], &started, 1);
        ::sleep(6);  // longer than the lock's wait for a dead holder (2 s)
      });
    } catch (...) {
    }
    ::_exit(0);
  }
  ::close(sync[1]);
  char c = 0;
  ASSERT_EQ(::read(sync[0], &c, 1), 1) << "the helper process did not start";
  ::close(sync[0]);
  ASSERT_EQ(::kill(run, SIGKILL), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(run, &status, 0), run);
  EXPECT_NO_THROW(FolderLock next(dir)) << "the dead run's helper process still holds " << dir;
  std::filesystem::remove_all(tmpl);
}

}  // namespace
}  // namespace tailsim
