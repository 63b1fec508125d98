// libFuzzer target for the experiment loader (issue 16): every input is written as an experiment
// file and loaded with loadExperimentSuite (so suite files are fuzzed too). The loader's contract
// is "a ConfigError or a valid Experiment": any other exception, a crash, a sanitizer report, a
// hang or unbounded memory is a finding. Built only with -DTAILSIM_FUZZ=ON (clang);
// scripts/fuzz.sh builds and runs it, docs/testing.md describes longer runs.
//
// The input lives in a scratch folder laid out like configs/: exp/input.yaml, with the packaged
// robots at robots/ and exp/robots/ and the paper experiments beside it, so the seed corpus
// (configs/) resolves its relative paths and a fuzzed suite can list real experiments.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "experiments/experiment_loader.h"

namespace {

namespace fs = std::filesystem;

fs::path g_root;
std::string g_input;

void removeScratch() {
  std::error_code ec;
  if (!g_root.empty()) fs::remove_all(g_root, ec);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  std::string tmpl = (fs::temp_directory_path() / "tailsim-fuzz-XXXXXX").string();
  if (!mkdtemp(tmpl.data())) {
    std::perror("mkdtemp");
    std::abort();
  }
  g_root = tmpl;
  std::atexit(removeScratch);
  const fs::path configs = fs::path(TAILSIM_SOURCE_DIR) / "configs";
  fs::create_directories(g_root / "exp");
  fs::create_directory_symlink(configs / "robots", g_root / "robots");
  fs::create_directory_symlink(configs / "robots", g_root / "exp" / "robots");
  for (const auto& e : fs::directory_iterator(configs / "paper"))
    if (e.path().extension() == ".yaml") fs::create_symlink(e.path(), g_root / "exp" / e.path().filename());
  g_input = (g_root / "exp" / "input.yaml").string();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FILE* f = std::fopen(g_input.c_str(), "wb");
  if (!f) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  try {
    (void)tailsim::loadExperimentSuite(g_input);
  } catch (const tailsim::ConfigError&) {
    // refused with file:line:col: the expected outcome for most inputs
  }
  return 0;
}
