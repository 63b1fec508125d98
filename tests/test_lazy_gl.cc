// Issue 13: OSMesa (Mesa's llvmpipe with LLVM, z3 and ICU; ~14 ms of dynamic loading) is loaded
// only when something is rendered. This binary links the whole program's libraries like the CLI does.
#include <gtest/gtest.h>

#include "analytic_test_util.h"
#include "rendering/gl_context.h"

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

}  // namespace
}  // namespace tailsim
