// `tailsim optimize EXPERIMENT.yaml --out DIR`: the best tail stroke (kind: optimize,
// docs/design-a-tail-stroke.md), computed by the optimiser module.
#include <memory>

#include "app/commands.h"

namespace tailsim {

void addOptimizeCommand(CLI::App& app, int& exit_code) {
  struct Args {
    std::string exp_path, out;
    bool quiet = false;
  };
  auto a = std::make_shared<Args>();
  auto* optimize = app.add_subcommand("optimize", "optimise a tail stroke (kind: optimize experiment)");
  optimize->add_option("experiment", a->exp_path, "optimize experiment YAML")->required()->check(CLI::ExistingFile);
  optimize->add_option("--out", a->out, "result folder")->required()->check(nonEmptyPath());
  optimize->add_flag("--quiet", a->quiet, "no progress lines");
  optimize->callback([a, &exit_code] {
    using Entry = int (*)(const char*, const char*, int, char*, size_t);
    const auto entry = reinterpret_cast<Entry>(optimiserEntry("optimize", "tailsim_optimize_main"));
    char err[8192] = {0};
    const int rc = entry(a->exp_path.c_str(), a->out.c_str(), a->quiet ? 1 : 0, err, sizeof err);
    exit_code = optimiserExitCode(rc, err);
  });
}

}  // namespace tailsim
