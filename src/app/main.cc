// tailsim: how much can a planar robotic tail turn a standing quadruped?
//   tailsim run EXPERIMENT.yaml --out DIR      both models as the experiment lists, results in DIR
//   tailsim plot DIR | tailsim report DIR      figures / Markdown report from saved results
//   tailsim render EXPERIMENT.yaml --out DIR   headless MP4 + PNG of each case
//   tailsim mjcf [EXPERIMENT.yaml | --links N] (--out FILE | --menagerie DIR)
//                                              the MuJoCo model: one file, or robot + scene (mjcf/README.md)
//   tailsim accuracy EXPERIMENT.yaml --out DIR work-precision study of both models
//   tailsim optimize EXPERIMENT.yaml --out DIR best tail stroke (kind: optimize, docs/design-a-tail-stroke.md)
//   tailsim maneuver EXPERIMENT.yaml --out DIR turn to a heading, open- and closed-loop (kind: maneuver)
//   tailsim trust EXPERIMENT.yaml --out DIR  what the MuJoCo answer depends on (docs/accuracy.md)
//   tailsim robot FILE                       the planar parameters of a MuJoCo robot (docs/your-robot.md)
// Each subcommand is one file, src/app/cmd_<name>.cc (declared in commands.h).
// Exit codes: see kExitCodes below (also printed by --help).
#include <CLI/CLI.hpp>

#include <cstdio>
#include <string>

#include "app/commands.h"
#include "tailsim_version.h"

using namespace tailsim;

namespace {

constexpr const char* kExitCodes =
    "Exit codes:\n"
    "  0    ok\n"
    "  1    error: bad input (named file:line:col) or a failure that stopped the command\n"
    "  2    usage error: unknown subcommand or option, missing or bad argument\n"
    "  3    run: some model runs failed (the rest is saved; see summary.json); optimize: a limit violated on the re-run;\n"
    "       maneuver: a run failed or the closed loop missed the heading\n"
    "  130  run: interrupted by Ctrl-C (SIGINT; finished cases are saved; run again to resume)\n"
    "  143  run: stopped by SIGTERM (a batch system's time limit), likewise\n"
    "       optimize, maneuver: the same codes; optimize keeps the seeds that finished, maneuver only its inputs\n"
    "  129  run: stopped by SIGHUP (the terminal closed), likewise";

std::string versionString() {
  std::string v = std::string("tailsim ") + kVersion;
  if (*kGitCommit) v += std::string(" (git ") + kGitCommit + ")";
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"tailsim: quadruped yaw turning with a planar robotic tail (Rone & Ben-Tzvi 2016)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", versionString(), "print the version and exit");
  app.footer(kExitCodes);

  // Each subcommand's body runs as its callback at the end of app.parse() and sets exit_code.
  int exit_code = kExitOk;
  addRunCommand(app, exit_code);
  addMergeCommand(app, exit_code);
  addMjcfCommand(app, exit_code);
  addRenderCommand(app, exit_code);
  addPlotCommand(app, exit_code);
  addReportCommand(app, exit_code);
  addLadderCommand(app, exit_code);
  addAccuracyCommand(app, exit_code);
  addSchemaCommand(app, exit_code);
  addOptimizeCommand(app, exit_code);
  addManeuverCommand(app, exit_code);
  addRobotCommand(app, exit_code);
  addTrustCommand(app, exit_code);

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // CLI11 says "A subcommand is required" for `tailsim rn`: name the word it did not know.
    const std::string first = argc > 1 ? argv[1] : "";
    if (!first.empty() && first[0] != '-' && app.get_subcommands().empty()) {
      std::string names;
      for (const CLI::App* sc : app.get_subcommands([](CLI::App*) { return true; })) names += (names.empty() ? "" : ", ") + sc->get_name();
      std::fprintf(stderr, "error: unknown subcommand '%s' (one of: %s)\nRun with --help for more information.\n",
                   first.c_str(), names.c_str());
    } else {
      // CLI11 checks required arguments before unknown ones ("--out is required" for
      // `tailsim run --bogus`): name an unknown option first, it is the likelier mistake (and name it
      // the same way when nothing else is wrong).
      std::string unknown, where = "tailsim";
      for (const std::string& a : app.remaining())
        if (unknown.empty() && a.size() > 1 && a[0] == '-') unknown = a;
      for (const CLI::App* sc : app.get_subcommands())
        for (const std::string& a : sc->remaining())
          if (unknown.empty() && a.size() > 1 && a[0] == '-') {
            unknown = a;
            where = "tailsim " + sc->get_name();
          }
      if (!unknown.empty())
        std::fprintf(stderr, "error: unknown option '%s' for '%s'\nRun '%s --help' for the options.\n", unknown.c_str(),
                     where.c_str(), where.c_str());
      else
        app.exit(e);  // CLI11's message names the option or argument
    }
    return kExitUsage;
  } catch (const std::exception& e) {  // a command stopped by an error (ConfigError: bad input)
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitError;
  }
  return exit_code;
}
