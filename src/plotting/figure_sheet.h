// The figure sheet: DIR/figures.html, one self-contained HTML page (inline style, no script, no
// external resource) showing every figure `tailsim plot DIR` drew, in paper order (by the figure
// number in each experiment's description, then by name), each with its caption in words and
// links to its SVG and gnuplot script. Image links are relative, so the folder can be moved.
#pragma once

#include <string>
#include <vector>

#include "plotting/plots.h"
#include "plotting/result_folder.h"

namespace tailsim {

// Relative URL of `file` seen from `dir`: '/'-separated, every byte but [A-Za-z0-9/._~-] percent-encoded
// (the figure sheet and the result page link their files with it).
std::string relUrl(const std::string& file, const std::string& dir);

// DIR/figures.html.
std::string figureSheetPath(const std::string& dir);

// The page's HTML for `plots` (from plotExperiment of `results`), image links relative to dir.
std::string figureSheetHtml(const std::string& dir, const std::vector<ExperimentResults>& results,
                            const std::vector<PlotFile>& plots);

// Writes DIR/figures.html atomically and returns its path.
std::string writeFigureSheet(const std::string& dir, const std::vector<ExperimentResults>& results,
                             const std::vector<PlotFile>& plots);

}  // namespace tailsim
