// The subcommands of `tailsim`, one file each (src/app/cmd_<name>.cc). Each add...Command adds its
// subcommand, options and body to the app: the body runs as the subcommand's callback after the
// whole command line parsed, and sets exit_code (see kExitCodes in main.cc). Errors that stop a
// command are thrown (ConfigError for bad input); main() prints them and exits 1.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

namespace tailsim {

constexpr int kExitOk = 0, kExitError = 1, kExitUsage = 2, kExitRunsFailed = 3, kExitInterrupted = 130;

// --out and --menagerie: a folder or file name, never empty (an empty path would mean "here"
// to some calls and an error to others).
const CLI::Validator& nonEmptyPath();

// A result folder argument (plot, report, ladder): an existing folder. An input file given instead
// is named with the command that reads it ("x.yaml is an experiment file: run it with `tailsim run
// x.yaml --out DIR`, then give DIR").
const CLI::Validator& resultFolder();

// Plots and reports of a folder whose cases kept no time series say so (on stderr): the figures
// over time are left out, those over the swept values come from the results table.
void printSeriesNotes(const std::string& dir);

// The optimiser and the maneuvers live in a module loaded only by `optimize` and `maneuver`
// (src/app/modules/optimize.cc): pagmo's start-up cost stays out of every other command. Returns
// the symbol `entry` of that module; throws naming what was tried. `what` names the command.
void* optimiserEntry(const char* what, const char* entry);
// The exit code of a module entry's return value rc (-1: bad input, other negatives: an error,
// both thrown with the message in err; 0: ok; positive: a limit or the heading missed).
int optimiserExitCode(int rc, const char* err);

void addRunCommand(CLI::App& app, int& exit_code);
void addMergeCommand(CLI::App& app, int& exit_code);
void addMjcfCommand(CLI::App& app, int& exit_code);
void addRenderCommand(CLI::App& app, int& exit_code);
void addPlotCommand(CLI::App& app, int& exit_code);
void addReportCommand(CLI::App& app, int& exit_code);
void addLadderCommand(CLI::App& app, int& exit_code);
void addAccuracyCommand(CLI::App& app, int& exit_code);
void addSchemaCommand(CLI::App& app, int& exit_code);
void addOptimizeCommand(CLI::App& app, int& exit_code);
void addManeuverCommand(CLI::App& app, int& exit_code);
// `tailsim robot FILE`: the planar models' parameters derived from a MuJoCo model (MJCF or URDF),
// each with its unit and source (docs/your-robot.md).
void addRobotCommand(CLI::App& app, int& exit_code);
// `tailsim trust EXPERIMENT --out DIR`: the convergence and sensitivity study of one case (docs/accuracy.md).
void addTrustCommand(CLI::App& app, int& exit_code);

}  // namespace tailsim
