// `tailsim plot DIR`: redraw the figures of a result folder (no simulation).
#include <cstdio>
#include <memory>

#include "app/commands.h"
#include "plotting/figure_sheet.h"
#include "plotting/plots.h"
#include "plotting/result_page.h"

namespace tailsim {

void addPlotCommand(CLI::App& app, int& exit_code) {
  struct Args {
    std::string dir, size;
    PlotOptions opt;
    bool no_titles = false;
  };
  auto a = std::make_shared<Args>();
  auto* plot = app.add_subcommand("plot", "redraw the figures of a result folder (no simulation)");
  plot->add_option("dir", a->dir, "result folder")->required()->check(resultFolder());
  plot->add_flag("--no-titles", a->no_titles, "no title drawn in the figures (figures.html's captions keep them)");
  plot->add_option("--size", a->size, "W,H: every figure W x H pixels (PNG; the SVG in points)");
  plot->add_option("--font-scale", a->opt.font_scale, "every font scaled by this factor (default 1)")
      ->check(CLI::PositiveNumber);
  plot->callback([a, &exit_code] {
    PlotOptions opt = a->opt;
    opt.titles = !a->no_titles;
    if (!a->size.empty()) {
      int w = 0, h = 0;
      char extra = 0;
      if (std::sscanf(a->size.c_str(), "%d,%d%c", &w, &h, &extra) != 2 || w < 100 || h < 100 || w > 30000 ||
          h > 30000) {
        std::fprintf(stderr, "error: --size %s: expected W,H in pixels, each 100..30000 (e.g. --size 1600,1000)\n",
                     a->size.c_str());
        exit_code = kExitUsage;
        return;
      }
      opt.width_px = w, opt.height_px = h;
    }
    printSeriesNotes(a->dir);
    const auto files = plotResults(a->dir, opt);
    for (const auto& f : files) std::printf("%s\n", f.png.c_str());
    std::printf("%s\n", writeResultPage(a->dir).c_str());
    std::printf("%s\n", figureSheetPath(a->dir).c_str());
    exit_code = kExitOk;
  });
}

}  // namespace tailsim
