// `tailsim report DIR`: DIR/report.md, the plots and the paper's findings checked.
#include <cstdio>
#include <memory>

#include "app/commands.h"
#include "plotting/report.h"

namespace tailsim {

void addReportCommand(CLI::App& app, int& exit_code) {
  auto dir = std::make_shared<std::string>();
  auto* report = app.add_subcommand("report", "write DIR/report.md: plots and the paper's findings checked");
  report->add_option("dir", *dir, "result folder")->required()->check(resultFolder());
  report->callback([dir, &exit_code] {
    printSeriesNotes(*dir);
    std::printf("%s\n", writeReport(*dir).c_str());
    exit_code = kExitOk;
  });
}

}  // namespace tailsim
