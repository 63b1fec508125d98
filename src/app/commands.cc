// What several subcommands share: the non-empty path check and the notes on missing time series.
#include "app/commands.h"

#include <dlfcn.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "experiments/yaml_file.h"
#include "plotting/result_folder.h"

namespace tailsim {

const CLI::Validator& nonEmptyPath() {
  static const CLI::Validator v(
      [](std::string& s) { return s.empty() ? std::string("is empty: give a folder or file name") : std::string(); },
      "PATH");
  return v;
}

const CLI::Validator& resultFolder() {
  static const CLI::Validator v(
      [](std::string& s) {
        std::string why = CLI::ExistingDirectory(s);
        if (!why.empty())
          if (const std::string note = inputFileNote(s); !note.empty()) why = note + ", then give DIR";
        return why;
      },
      "DIR");
  return v;
}

void printSeriesNotes(const std::string& dir) {
  try {
    for (const ExperimentResults& r : loadResultTree(dir))
      if (const std::string note = r.seriesNote(); !note.empty()) std::fprintf(stderr, "note: %s\n", note.c_str());
  } catch (const std::exception&) {  // the command itself reports an unreadable folder
  }
}

void* optimiserEntry(const char* what, const char* entry) {
  namespace fs = std::filesystem;
  const fs::path exe = fs::read_symlink("/proc/self/exe");
  std::string tried;
  void* lib = nullptr;
  for (const fs::path& p : {exe.parent_path() / "tailsim_optimize.so",
                            exe.parent_path().parent_path() / "lib" / "tailsim" / "tailsim_optimize.so"}) {
    lib = ::dlopen(p.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (lib) break;
    const char* why = ::dlerror();
    tried += "\n  " + p.string() + ": " + (why ? why : "?");
  }
  if (!lib) throw std::runtime_error(std::string(what) + ": cannot load the optimiser module:" + tried);
  void* f = ::dlsym(lib, entry);
  if (!f) throw std::runtime_error(std::string(what) + ": the optimiser module has no " + entry);
  return f;
}

int optimiserExitCode(int rc, const char* err) {
  if (rc == -1) throw ConfigError(err);
  if (rc < 0) throw std::runtime_error(err);
  if (rc >= 128) return rc;  // stopped by a signal: 128 + the signal, as `run`
  return rc == 0 ? kExitOk : kExitRunsFailed;
}

}  // namespace tailsim
