#include "plotting/gnuplot.h"

#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "results/atomic_file.h"

namespace tailsim {

namespace fs = std::filesystem;

std::string gpQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += (c == '\'') ? std::string("''") : std::string(1, c);
  return out + "'";
}

namespace {

std::string shellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string terminalBlock(const GnuplotFigure& f, bool png) {
  std::ostringstream o;
  if (png)
    o << "set terminal pngcairo noenhanced size " << f.width_px << "," << f.height_px
      << " font 'Sans,15' linewidth 2\n"
      << "set output " << gpQuote(f.stem + ".png") << "\n";
  else
    o << "set terminal svg noenhanced size " << f.width_px << "," << f.height_px
      << " font 'Sans,15' linewidth 2 background rgb 'white'\n"
      << "set output " << gpQuote(f.stem + ".svg") << "\n";
  o << f.body << "\nunset output\n";
  return o.str();
}

}  // namespace

void writeDataFile(const std::string& path, const std::vector<std::string>& header,
                   const std::vector<std::vector<double>>& rows) {
  std::string out = "#";
  for (const std::string& h : header) out += " " + h;
  out += "\n";
  char buf[40];
  for (const auto& row : rows) {
    for (size_t i = 0; i < row.size(); ++i) {
      if (i) out += ' ';
      if (std::isfinite(row[i])) {
        std::snprintf(buf, sizeof buf, "%.10g", row[i]);
        out += buf;
      } else {
        out += "NaN";
      }
    }
    out += '\n';
  }
  writeFileAtomic(path, out);
}

std::string renderFigure(const std::string& plots_dir, const GnuplotFigure& fig) {
  fs::create_directories(plots_dir);
  const fs::path dir(plots_dir);
  const std::string script = "# " + fig.stem + ": written by tailsim plot; rerun with `gnuplot " + fig.stem +
                             ".gp` in this folder\nset encoding utf8\nset datafile missing 'NaN'\n" +
                             terminalBlock(fig, true) + terminalBlock(fig, false);
  writeFileAtomic((dir / (fig.stem + ".gp")).string(), script);
  const std::string log = (dir / (fig.stem + ".log")).string();
  const std::string cmd = "cd " + shellQuote(plots_dir) + " && gnuplot " + shellQuote(fig.stem + ".gp") +
                          " > " + shellQuote(log) + " 2>&1";
  const int status = std::system(cmd.c_str());
  std::string err;
  {
    std::ifstream in(log);
    std::stringstream ss;
    ss << in.rdbuf();
    err = ss.str();
  }
  if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error("gnuplot failed on " + (dir / (fig.stem + ".gp")).string() +
                             (WIFEXITED(status) && WEXITSTATUS(status) == 127 ? " (gnuplot not installed?)" : "") +
                             ":\n" + err);
  for (const char* ext : {".png", ".svg"}) {
    const fs::path p = dir / (fig.stem + ext);
    if (!fs::exists(p) || fs::file_size(p) == 0)
      throw std::runtime_error("gnuplot wrote no " + p.string() + ":\n" + err);
  }
  if (err.empty()) fs::remove(log);
  return (dir / (fig.stem + ".png")).string();
}

}  // namespace tailsim
