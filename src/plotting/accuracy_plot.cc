#include "plotting/accuracy_plot.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "plotting/gnuplot.h"
#include "plotting/style.h"

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
         << "set ylabel '|φ_{net} − reference| [deg]'\nset title "
         << gpTitle("Work-precision: error of φ_{net} against wall time, case " + gpText(st.case_name), 1400)
         // the legend beside the plot at a fixed place: gnuplot sized the outside legend from its
         // byte count and gave the plot 45 % of the width; now the plot ends at 66 %
         << "\nset rmargin at screen 0.66\nset key at screen 0.67, graph 1 left top Left reverse nobox samplen 2\n";
    std::vector<std::string> parts;
    int k = 0;
    for (const auto& [name, rows] : curves) {
      const std::string dat = stem + "_" + std::to_string(k++) + ".dat";
      writeDataFile(dir + "/" + dat, {"wall_ms", "err_deg", "value"}, rows);
      // One Okabe-Ito colour per series (style.h); point type and, past seven series, dashes as well.
      const size_t i = static_cast<size_t>(k - 1);
      parts.push_back(gpFileName(dat) + " using 1:2 with linespoints lw 2 pt " + std::to_string(1 + i % 13) + " ps 1.4 dt " +
                      std::to_string(1 + static_cast<int>(i / 7) % 4) + " lc rgb " + gpQuote(categoricalColor(i)) +
                      " title " + gpQuote(gpText(name)));
    }
    if (!defaults.empty()) {
      writeDataFile(dir + "/" + stem + "_defaults.dat", {"wall_ms", "err_deg", "value"}, defaults);
      parts.push_back(gpFileName(stem + "_defaults.dat") +
                      " using 1:2 with points pt 6 ps 4 lw 3 lc rgb 'black' title 'tailsim default'");
    }
    if (st.mujoco.present && st.mujoco.noise_default_deg > 0)
      parts.push_back(std::to_string(st.mujoco.noise_default_deg) +
                      " with lines dt 2 lw 2 lc rgb 'gray40' title 'MuJoCo noise floor (φ_{net} s.d. under ΔT ± 1 μs)'");
    if (parts.empty()) continue;
    body << "plot ";
    for (size_t i = 0; i < parts.size(); ++i) body << (i ? ", \\\n     " : "") << parts[i];
    body << "\n";
    GnuplotFigure fig;
    fig.stem = stem;
    fig.body = body.str();
    fig.width_px = 1750;
    fig.height_px = 800;
    pngs.push_back(renderFigure(dir, fig));
  }
  return pngs;
}

}  // namespace tailsim
