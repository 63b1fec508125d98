// The subcommands that live in their own files (src/app/cmd_<name>.cc): each adds its options
// and its body to the app.
#pragma once

#include <CLI/CLI.hpp>

namespace tailsim {

// `tailsim trust EXPERIMENT --out DIR [--case NAME]` (cmd_trust.cc). Sets exit_code (>= 0) when
// the subcommand ran.
void addTrustCommand(CLI::App& app, int& exit_code);

}  // namespace tailsim
