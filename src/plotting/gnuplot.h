// Running gnuplot on a generated script: every figure is written as PNG (pngcairo) and SVG from
// the same plot commands, with its script and data files kept beside it (DIR/plots/). Both
// terminals use enhanced text (φ_{net}, 10^{-3}): escape free text with gpText (style.h).
#pragma once

#include <string>
#include <vector>

namespace tailsim {

struct GnuplotFigure {
  std::string stem;        // file name without extension: <experiment>_<what>
  std::string body;        // plot commands (no terminal/output); starts from a `reset` state
  int width_px = 1000;     // PNG size; the SVG gets the same size in points
  int height_px = 700;
  double font_scale = 1.0;  // every font of the figure scaled (the terminals' fontscale)
};

// Writes <plots_dir>/<stem>.gp, runs gnuplot in plots_dir (posix_spawn, no shell; plots_dir may be
// relative to the current directory), checks <stem>.png and .svg exist and are not empty. Throws
// std::runtime_error with gnuplot's output (kept in <plots_dir>/<stem>.log) on failure.
// Returns the PNG path, as plots_dir / "<stem>.png".
std::string renderFigure(const std::string& plots_dir, const GnuplotFigure& fig);

// A whitespace-separated data file for gnuplot (NaN for missing values), written atomically.
void writeDataFile(const std::string& path, const std::vector<std::string>& header,
                   const std::vector<std::vector<double>>& rows);

// Quotes a string for gnuplot as a string expression of single-quoted literals: a quote becomes
// '."'".' and a line break '."\n".' (`set title`, `set output`, `plot 'file'`, `title`, `lc rgb`
// all take a string expression). The only way text that is not tailsim's own (names, labels,
// paths) enters a gnuplot script: inside single quotes gnuplot expands no backquotes, macros (@)
// or backslash escapes; a doubled quote is not used (gnuplot 5.4 misreads '' next to another
// quote or at the start); other control characters (NUL, CR, tab) become spaces. Every script
// tailsim writes quotes its text with it.
std::string gpQuote(const std::string& s);

// A file name relative to the script's folder (a data file, `set output`, `load`), for a gnuplot
// script: "./" + name, quoted with gpQuote. gnuplot opens a name starting with '|' (set output)
// or '<' (plot) as a pipe to a shell command and reads one starting with '$' as a datablock; with
// "./" in front no name, whatever its text, is anything but a file. Every file name a tailsim
// script holds goes through this function.
std::string gpFileName(const std::string& relative_name);

}  // namespace tailsim
