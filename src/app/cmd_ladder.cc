// `tailsim ladder DIR`: DIR/ladder.md, the gap ladder of a configs/ladder/ result folder.
#include <cstdio>
#include <memory>

#include "app/commands.h"
#include "plotting/ladder.h"

namespace tailsim {

void addLadderCommand(CLI::App& app, int& exit_code) {
  auto dir = std::make_shared<std::string>();
  auto* ladder = app.add_subcommand("ladder", "write DIR/ladder.md: the gap ladder of a configs/ladder/ result folder");
  ladder->add_option("dir", *dir, "result folder")->required()->check(resultFolder());
  ladder->callback([dir, &exit_code] {
    for (const std::string& f : writeLadder(*dir)) std::printf("%s\n", f.c_str());
    exit_code = kExitOk;
  });
}

}  // namespace tailsim
