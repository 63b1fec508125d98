// The README's own-experiment example ("## Experiments"), taken from README.md at test time so
// README and test cannot drift: saved outside the repository and run with build/tailsim from
// another working directory, it must give the number of cases the README promises, every run ok.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

std::string readText(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

struct TempDir {
  fs::path path;
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

// The README's "## Experiments" section (up to the next "## " heading).
std::string experimentsSection(const std::string& readme) {
  const std::size_t b = readme.find("\n## Experiments\n");
  if (b == std::string::npos) return {};
  const std::size_t e = readme.find("\n## ", b + 1);
  return readme.substr(b, e == std::string::npos ? std::string::npos : e - b);
}

// Runs `exe args...` in `cwd` (no shell), stdout and stderr to `log`; returns the exit status.
int runIn(const fs::path& cwd, const std::string& exe, const std::vector<std::string>& args, const fs::path& log) {
  const pid_t pid = fork();
  if (pid == 0) {
    if (chdir(cwd.c_str()) != 0) _exit(126);
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) _exit(126);
    dup2(fd, 1);
    dup2(fd, 2);
    std::vector<char*> argv{const_cast<char*>(exe.c_str())};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(exe.c_str(), argv.data());
    _exit(127);
  }
  int status = 0;
  if (pid < 0 || waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(ReadmeExperiment, RunsAsWrittenFromAnywhere) {
  const std::string section = experimentsSection(readText(fs::path(TAILSIM_SOURCE_DIR) / "README.md"));
  ASSERT_FALSE(section.empty()) << "README.md has no '## Experiments' section";
  std::smatch yaml;
  ASSERT_TRUE(std::regex_search(section, yaml, std::regex("```yaml\n([^`]*)```"))) << "no ```yaml block";
  std::smatch promised;
  const std::string after = yaml.suffix().str();
  ASSERT_TRUE(std::regex_search(after, promised, std::regex(R"((\d+) cases \()")))
      << "the README no longer says how many cases the example gives";
  const std::size_t cases = std::stoul(promised[1].str());

  // Saved outside the repository, run from a sibling folder with relative paths.
  std::string tmpl = (fs::temp_directory_path() / "tailsim_readme_XXXXXX").string();
  ASSERT_NE(mkdtemp(tmpl.data()), nullptr);
  const TempDir tmp{tmpl};
  const fs::path& root = tmp.path;
  fs::create_directories(root / "saved");
  fs::create_directories(root / "elsewhere");
  std::ofstream(root / "saved" / "my_turn.yaml") << yaml[1].str();
  const int rc = runIn(root / "elsewhere", TAILSIM_BINARY_DIR "/tailsim",
                       {"run", "../saved/my_turn.yaml", "--out", "out", "--quiet"}, root / "log.txt");
  EXPECT_EQ(rc, 0) << readText(root / "log.txt");

  const fs::path summary = root / "elsewhere" / "out" / "summary.json";
  ASSERT_TRUE(fs::is_regular_file(summary)) << readText(root / "log.txt");
  const nlohmann::json j = nlohmann::json::parse(readText(summary));
  ASSERT_EQ(j.at("cases").size(), cases) << "README promises " << cases << " cases";
  for (const nlohmann::json& c : j.at("cases")) {
    EXPECT_EQ(c.at("runs").size(), 2u) << c.at("name");  // both models, as the README says
    for (const auto& [model, run] : c.at("runs").items())
      EXPECT_TRUE(run.at("ok").get<bool>()) << c.at("name") << " " << model;
  }
}

}  // namespace
