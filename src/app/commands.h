// The subcommands that live in their own files (src/app/cmd_<name>.cc).
#pragma once

#include <CLI/CLI.hpp>

namespace tailsim {

// `tailsim robot FILE`: the planar models' parameters derived from a MuJoCo model (MJCF or URDF),
// each with its unit and source (docs/your-robot.md). Sets exit_code (0 ok, 1 error) when it runs.
void addRobotCommand(CLI::App& app, int& exit_code);

}  // namespace tailsim
