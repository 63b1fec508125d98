#include "plotting/accuracy_plot.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "plotting/gnuplot.h"

namespace tailsim {

std::vector<std::string> plotAccuracy(const std::vector<AccuracyStudy>& studies, const std::string& dir) {
  std::vector<std::string> pngs;
  for (const AccuracyStudy& st : studies) {
    // DIR/accuracy.png for a single case, DIR/accuracy_<case>.png for several.
    std::string stem = studies.size() == 1 ? std::string("accuracy") : "accuracy_" + st.case_name;
    std::replace_if(stem.begin(), stem.end(), [](char c) { return !std::isalnum(static_cast<unsigned char>(c)) && c != '_'; }, '_');
    // One data file per curve; errors of exactly 0 sit on the plot's floor (1e-12 deg).
    std::map<std::string, std::vector<std::vector<double>>> curves;
    std::vector<std::vector<double>> defaults;
    for (const AccuracyRow& r : st.rows) {
      if (!r.ok || !(r.wall_s > 0)) continue;
      const double err = std::max(r.err_phi_net_deg, 1e-12);
      curves[r.model + " " + r.family].push_back({1e3 * r.wall_s, err, r.value});
      if (r.is_default) defaults.push_back({1e3 * r.wall_s, err, 0});
    }
    std::ostringstream body;
    body << "set logscale xy\nset grid\nset format y '10^{%L}'\nset xlabel 'wall time per run [ms]'\n"
         << "set ylabel '|phi_net - reference| [deg]'\nset title " << gpQuote("Work-precision: " + st.case_name)
         << "\nset key outside right top\nset format y '%.0e'\n";
    std::vector<std::string> parts;
    int k = 0;
    for (const auto& [name, rows] : curves) {
      const std::string dat = stem + "_" + std::to_string(k++) + ".dat";
      writeDataFile(dir + "/" + dat, {"wall_ms", "err_deg", "value"}, rows);
      parts.push_back(gpQuote(dat) + " using 1:2 with linespoints title " + gpQuote(name));
    }
    if (!defaults.empty()) {
      writeDataFile(dir + "/" + stem + "_defaults.dat", {"wall_ms", "err_deg", "value"}, defaults);
      parts.push_back(gpQuote(stem + "_defaults.dat") +
                      " using 1:2 with points pt 6 ps 4 lw 3 lc rgb 'black' title 'tailsim default'");
    }
    if (st.mujoco.present && st.mujoco.noise_default_deg > 0)
      parts.push_back(std::to_string(st.mujoco.noise_default_deg) +
                      " with lines dt 2 lw 2 lc rgb 'gray40' title 'MuJoCo noise floor (phi_net s.d. under dT +- 1 us)'");
    if (parts.empty()) continue;
    body << "plot ";
    for (size_t i = 0; i < parts.size(); ++i) body << (i ? ", \\\n     " : "") << parts[i];
    body << "\n";
    GnuplotFigure fig;
    fig.stem = stem;
    fig.body = body.str();
    fig.width_px = 1300;
    fig.height_px = 750;
    pngs.push_back(renderFigure(dir, fig));
  }
  return pngs;
}

}  // namespace tailsim
