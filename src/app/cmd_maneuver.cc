// `tailsim maneuver EXPERIMENT.yaml --out DIR`: turn to a heading with tail strokes, open- and
// closed-loop (kind: maneuver), computed by the optimiser module.
#include <memory>

#include "app/commands.h"

namespace tailsim {

void addManeuverCommand(CLI::App& app, int& exit_code) {
  struct Args {
    std::string exp_path, out;
    bool quiet = false, video = false;
  };
  auto a = std::make_shared<Args>();
  auto* maneuver = app.add_subcommand("maneuver", "turn to a heading with tail strokes, open- and closed-loop (kind: maneuver experiment)");
  maneuver->add_option("experiment", a->exp_path, "maneuver experiment YAML")->required()->check(CLI::ExistingFile);
  maneuver->add_option("--out", a->out, "result folder")->required()->check(nonEmptyPath());
  maneuver->add_flag("--video", a->video, "also render the closed-loop turn (renders/<name>.mp4)");
  maneuver->add_flag("--quiet", a->quiet, "no progress lines");
  maneuver->callback([a, &exit_code] {
    using Entry = int (*)(const char*, const char*, int, int, char*, size_t);
    const auto entry = reinterpret_cast<Entry>(optimiserEntry("maneuver", "tailsim_maneuver_main"));
    char err[8192] = {0};
    const int rc = entry(a->exp_path.c_str(), a->out.c_str(), a->quiet ? 1 : 0, a->video ? 1 : 0, err, sizeof err);
    exit_code = optimiserExitCode(rc, err);
  });
}

}  // namespace tailsim
