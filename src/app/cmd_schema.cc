// `tailsim schema`: the JSON Schema of experiment, suite, optimize and maneuver files (or robot files, or the Markdown key tables).
#include <cstdio>
#include <memory>

#include "app/commands.h"
#include "experiments/settings_schema.h"

namespace tailsim {

void addSchemaCommand(CLI::App& app, int& exit_code) {
  struct Args {
    bool markdown = false, robot = false;
  };
  auto a = std::make_shared<Args>();
  auto* schema = app.add_subcommand("schema", "print the JSON Schema of experiment, suite, optimize and maneuver files (for editors)");
  schema->add_flag("--robot", a->robot, "the schema of robot files instead");
  schema->add_flag("--markdown", a->markdown, "the key tables of docs/experiment-format.md instead");
  schema->callback([a, &exit_code] {
    if (a->markdown) std::printf("%s", settingsMarkdown().c_str());
    else std::printf("%s\n", (a->robot ? robotSchema() : experimentSchema()).dump(2).c_str());
    exit_code = kExitOk;
  });
}

}  // namespace tailsim
