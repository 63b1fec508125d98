#include "plotting/figure_sheet.h"

#include <algorithm>
#include <filesystem>
#include <sstream>

#include "plotting/style.h"
#include "plotting/sweep_summary.h"
#include "common/atomic_file.h"

namespace tailsim {

namespace fs = std::filesystem;

namespace {

// A description's text after its head (figureName: the text before the first ':'), trimmed; ""
// when the head is all of it (the heading already shows it).
std::string afterHead(const std::string& description) {
  const std::size_t colon = description.find(':');
  if (colon == std::string::npos) return "";
  const std::size_t b = description.find_first_not_of(" \t", colon + 1);
  return b == std::string::npos ? "" : description.substr(b);
}

std::string html(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}


bool under(const std::string& file, const std::string& dir) {
  const fs::path f = fs::absolute(file).lexically_normal(), d = fs::absolute(dir).lexically_normal();
  const std::string rel = f.lexically_relative(d).generic_string();
  return !rel.empty() && rel.rfind("..", 0) != 0;
}

}  // namespace

// Relative URL of `file` seen from `dir` (path segments percent-encoded where needed).
std::string relUrl(const std::string& file, const std::string& dir) {
  const std::string rel = fs::absolute(file).lexically_normal().lexically_relative(fs::absolute(dir).lexically_normal()).generic_string();
  std::string o;
  for (unsigned char c : rel) {
    if (std::isalnum(c) || c == '/' || c == '.' || c == '_' || c == '-' || c == '~') {
      o += static_cast<char>(c);
    } else {
      static const char* hex = "0123456789ABCDEF";
      o += '%';
      o += hex[c >> 4];
      o += hex[c & 15];
    }
  }
  return o;
}

std::string figureSheetPath(const std::string& dir) { return (fs::path(dir) / "figures.html").string(); }

std::string figureSheetHtml(const std::string& dir, const std::vector<ExperimentResults>& results,
                            const std::vector<PlotFile>& plots) {
  std::vector<const ExperimentResults*> order;
  for (const ExperimentResults& r : results) order.push_back(&r);
  std::stable_sort(order.begin(), order.end(), [](const ExperimentResults* a, const ExperimentResults* b) {
    const double oa = figureOrder(a->description), ob = figureOrder(b->description);
    return oa != ob ? oa < ob : a->name < b->name;
  });
  std::ostringstream o;
  const std::string where = fs::absolute(dir).lexically_normal().filename().string();
  const bool paper = std::any_of(results.begin(), results.end(), [](const ExperimentResults& r) { return isPaperFigure(r); });
  std::string heading = "tailsim figures: " + where;
  if (paper) heading = "tailsim figures: Rone &amp; Ben-Tzvi 2016 reproduction";
  else if (results.size() == 1) heading = "tailsim figures: " + html(results[0].name);
  o << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
    << "<title>tailsim figures: " << html(where) << "</title>\n"
    << "<style>\nbody{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}\n"
    << "figure{margin:1.5em 0 2.5em 0}img{max-width:100%;height:auto;border:1px solid #ddd}\n"
    << "figcaption{margin-top:.4em;line-height:1.4}figcaption a{color:#0072B2}\n"
    << "h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}nav li{margin:.15em 0}\n</style>\n"
    << "</head>\n<body>\n<h1>" << heading << "</h1>\n"
    << "<p>Every figure drawn by <code>tailsim plot</code> from the result folder <code>" << html(where)
    << "</code>" << (paper ? ", in paper order" : "")
    << ". " << html(modelGlossary(allModels(results))) << " "
    << "Under each experiment: what its results say (the largest φ<sub>net</sub> per model, its trend along "
       "each swept key, where the models differ, every run's warnings once), then its figures. "
    << "Each figure's SVG, gnuplot script and data files are beside its PNG.</p>\n<nav><ul>\n";
  int section = 0;
  for (const ExperimentResults* r : order) {
    ++section;
    o << "<li><a href=\"#s" << section << "\">" << html(figureName(r->description, r->name)) << "</a>";
    if (const std::string rest = afterHead(r->description); !rest.empty()) o << ": " << html(plainSymbols(rest));
    o << "</li>\n";
  }
  o << "</ul></nav>\n";
  section = 0;
  int number = 0;
  for (const ExperimentResults* r : order) {
    ++section;
    o << "<h2 id=\"s" << section << "\">" << html(figureName(r->description, r->name)) << "</h2>\n";
    if (const std::string rest = afterHead(r->description); !rest.empty()) o << "<p>" << html(plainSymbols(rest)) << "</p>\n";
    const SweepSummary sum = summarizeSweep(*r);
    auto list = [&](const char* what, const std::vector<std::string>& lines) {
      if (lines.empty()) return;
      o << "<p><b>" << what << "</b></p>\n<ul>\n";
      for (const std::string& l : lines) o << "<li>" << html(l) << "</li>\n";
      o << "</ul>\n";
    };
    list("Largest φ<sub>net</sub> per model", sum.best);
    list("Trend along each swept key", sum.trends);
    list("Where the models differ", sum.disagree);
    list("Warnings (each once, with the number of runs)", sum.warnings);
    int mine = 0;
    for (const PlotFile& p : plots) {
      if (!under(p.png, r->dir)) continue;
      ++mine;
      ++number;
      const std::string png = relUrl(p.png, dir);
      const std::string svg = relUrl(fs::path(p.png).replace_extension(".svg").string(), dir);
      const std::string gp = relUrl(fs::path(p.png).replace_extension(".gp").string(), dir);
      o << "<figure id=\"f" << number << "\">\n<a href=\"" << png << "\"><img src=\"" << png << "\" alt=\""
        << html(p.title.empty() ? p.caption : p.title) << "\" loading=\"lazy\"></a>\n<figcaption><b>Figure " << number
        << ".</b> " << html(p.caption) << " <a href=\"" << svg << "\">SVG</a> · <a href=\"" << gp
        << "\">gnuplot script</a></figcaption>\n</figure>\n";
    }
    if (!mine) o << "<p><i>No figure for this experiment (no readable data).</i></p>\n";
  }
  o << "</body>\n</html>\n";
  return o.str();
}

std::string writeFigureSheet(const std::string& dir, const std::vector<ExperimentResults>& results,
                             const std::vector<PlotFile>& plots) {
  const std::string path = figureSheetPath(dir);
  writeOwnedFile(dir, fs::path(path).filename().string(), figureSheetHtml(dir, results, plots), [](const std::string& text) {
    return text.find("<title>tailsim figures: ") != std::string::npos;  // an earlier tailsim's sheet
  });
  return path;
}

}  // namespace tailsim
