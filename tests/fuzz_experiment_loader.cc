// libFuzzer target for every file kind tailsim reads and for the Python module's keyword path:
//   - an input starting with '{' (after blanks) is a tailsim.simulate() call: a JSON object of
//     keyword arguments (robot, trajectory, model and the sections) turned into the experiment's
//     text by simulateExperimentText (experiments/keyword_args.h, what the module calls) and
//     loaded with loadExperimentText;
//   - any other input is written as a file and loaded with loadExperimentSuite (experiments and
//     suites), and, when it mentions optimize or maneuver, with loadOptimizeSpec or
//     loadManeuverSpec (design files, kind: optimize / kind: maneuver).
// Each loader's contract is "a ConfigError or a valid result" (a KeywordError for a keyword
// simulate() does not take): any other exception, a crash, a sanitizer report, a hang or
// unbounded memory is a finding. Built only with -DTAILSIM_FUZZ=ON (clang); scripts/fuzz.sh
// builds and runs it, docs/testing.md describes longer runs.
//
// The input lives in a scratch folder laid out like configs/: exp/input.yaml, with the packaged
// robots at robots/ and exp/robots/, the paper experiments beside it and the design files' base
// experiments at exp/base/, so the seed corpus (configs/, tests/fuzz_seeds/) resolves its
// relative paths, a fuzzed suite can list real experiments and a design file can name a base.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <cstring>

#include "design/maneuver.h"
#include "design/optimize_config.h"
#include "experiments/experiment_loader.h"
#include "experiments/keyword_args.h"

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
  fs::create_directory_symlink(configs / "design" / "base", g_root / "exp" / "base");
  g_input = (g_root / "exp" / "input.yaml").string();
  return 0;
}

namespace {

// A tailsim.simulate() call: {"robot": ..., "trajectory": ..., "model": ..., <sections>}.
void simulateCall(const uint8_t* data, size_t size) {
  const auto args = nlohmann::ordered_json::parse(data, data + size, nullptr, false);
  if (args.is_discarded() || !args.is_object()) return;  // the module only ever passes a dict
  nlohmann::ordered_json sections = args;
  std::string robot = "paper", model = "analytic";
  nlohmann::ordered_json trajectory;
  if (args.contains("robot") && args["robot"].is_string()) {
    robot = args["robot"].get<std::string>();
    sections.erase("robot");
  }
  if (args.contains("model") && args["model"].is_string()) {
    model = args["model"].get<std::string>();
    sections.erase("model");
  }
  if (args.contains("trajectory")) {
    trajectory = args["trajectory"];
    sections.erase("trajectory");
  }
  if (robot.find('\0') != std::string::npos) return;  // refused by the module (ValueError)
  try {
    (void)tailsim::loadExperimentText(tailsim::simulateExperimentText(robot, trajectory, model, sections),
                                      "<tailsim.simulate>");
  } catch (const tailsim::ConfigError&) {
  } catch (const tailsim::KeywordError&) {
  }
}

bool mentions(const uint8_t* data, size_t size, const char* word) {
  const std::size_t n = std::strlen(word);
  for (std::size_t i = 0; i + n <= size; ++i)
    if (std::memcmp(data + i, word, n) == 0) return true;
  return false;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  size_t first = 0;
  while (first < size && (data[first] == ' ' || data[first] == '\n' || data[first] == '\t' || data[first] == '\r')) ++first;
  if (first < size && data[first] == '{') {
    simulateCall(data, size);
    return 0;
  }
  FILE* f = std::fopen(g_input.c_str(), "wb");
  if (!f) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  try {
    (void)tailsim::loadExperimentSuite(g_input);
  } catch (const tailsim::ConfigError&) {
    // refused with file:line:col: the expected outcome for most inputs
  }
  if (mentions(data, size, "optimize")) {
    try {
      (void)tailsim::loadOptimizeSpec(g_input);
    } catch (const tailsim::ConfigError&) {
    }
  }
  if (mentions(data, size, "maneuver")) {
    try {
      (void)tailsim::loadManeuverSpec(g_input);
    } catch (const tailsim::ConfigError&) {
    }
  }
  return 0;
}
