// Where the tests find the MuJoCo Menagerie models nobody here wrote (go1/, anymal_c/): the folder
// shared/robots/menagerie beside the source tree or beside one of its ancestors. The repository
// ships none; a test that needs them skips when the folder is absent.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

namespace tailsim_test {

// shared/robots/menagerie beside the source dir or beside one of its ancestors ("" if absent).
inline std::filesystem::path menagerieDir() {
  namespace fs = std::filesystem;
  for (fs::path p = fs::absolute(TAILSIM_SOURCE_DIR); !p.empty(); p = p.parent_path()) {
    const fs::path m = p.parent_path() / "shared" / "robots" / "menagerie";
    std::error_code ec;
    if (fs::is_directory(m, ec)) return m;
    if (p == p.parent_path()) break;
  }
  return {};
}

// A scratch folder under the test temp dir, named PREFIX_<pid>, removed when the test ends.
struct Scratch {
  std::filesystem::path dir;
  explicit Scratch(const std::string& prefix)
      : dir(std::filesystem::path(::testing::TempDir()) / (prefix + "_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
  }
  ~Scratch() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(dir / name) << text;
    return (dir / name).string();
  }
};

}  // namespace tailsim_test
