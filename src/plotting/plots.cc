#include "plotting/plots.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "plotting/gnuplot.h"

namespace tailsim {

namespace fs = std::filesystem;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string modelColor(const std::string& model) {
  if (model == "analytic") return "#1f5fb4";
  if (model == "mujoco") return "#d62728";
  return "#2ca02c";
}

std::string modelTitle(const std::string& model) {
  if (model == "analytic") return "analytic (stiction)";
  if (model == "mujoco") return "MuJoCo (contact)";
  return model;
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// Series colours for curves that are not models (one per case / per value of a key).
std::string seriesColor(size_t i) {
  static const char* c[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
                            "#e377c2", "#7f7f7f", "#bcbd22", "#17becf", "#393b79", "#637939"};
  return c[i % (sizeof c / sizeof c[0])];
}

struct Ctx {
  const ExperimentResults& r;
  std::string plots;  // r.dir/plots
  std::vector<PlotFile> out;

  std::string data(const std::string& stem) const { return (fs::path(plots) / (stem + ".dat")).string(); }
  void render(const std::string& stem, const std::string& body, const std::string& caption, int w = 1000,
              int h = 700) {
    GnuplotFigure f;
    f.stem = stem;
    f.body = body;
    f.width_px = w;
    f.height_px = h;
    out.push_back({renderFigure(plots, f), caption});
  }
};

std::string header(const std::string& title, const std::string& xlabel, const std::string& ylabel) {
  std::ostringstream o;
  o << "reset\nset grid\nset key top left box opaque\n";
  if (!title.empty()) o << "set title " << gpQuote(title) << "\n";
  o << "set xlabel " << gpQuote(xlabel) << "\nset ylabel " << gpQuote(ylabel) << "\n";
  return o.str();
}

// ---- simulate, one case: phi(t) and moments ------------------------------------------------

void plotSingleCase(Ctx& ctx, const CaseRecord& c, const std::string& stem_prefix) {
  const ExperimentResults& r = ctx.r;
  std::vector<std::string> models;
  std::map<std::string, TimeSeries> ts;
  for (const std::string& m : r.models) {
    try {
      TimeSeries s = r.series(c, m);
      if (s.has("t_s") && s.has("phi_deg")) {
        ts[m] = std::move(s);
        models.push_back(m);
      }
    } catch (const std::exception&) {
    }
  }
  if (models.empty()) return;

  // phi(t), all models overlaid (Figs. 6, 7a).
  std::ostringstream body;
  body << header(r.name + ": body yaw φ(t)", "t [s]", "φ [deg]");
  body << "set key bottom right box opaque\nplot ";  // phi rises from 0 and settles: bottom right is free
  for (size_t i = 0; i < models.size(); ++i) {
    const std::string& m = models[i];
    const TimeSeries& s = ts[m];
    const std::string stem = stem_prefix + "_phi_" + m;
    std::vector<std::vector<double>> rows;
    const auto& t = s.values("t_s");
    const auto& phi = s.values("phi_deg");
    for (size_t k = 0; k < t.size(); ++k) rows.push_back({t[k], phi[k]});
    writeDataFile(ctx.data(stem), {"t_s", "phi_deg"}, rows);
    const double net = r.phiNet(c, m);
    std::string title = modelTitle(m);
    if (std::isfinite(net)) title += ", φ_net = " + fmt("%.2f", net) + " deg";
    body << (i ? ", \\\n     " : "") << gpQuote(stem + ".dat") << " using 1:2 with lines lw 2 lc rgb "
         << gpQuote(modelColor(m)) << " title " << gpQuote(title);
  }
  body << "\n";
  ctx.render(stem_prefix + "_phi", body.str(), r.name + ": φ(t), " + std::to_string(models.size()) + " model(s)");

  // Moments over time, one panel per model (Fig. 7b).
  static const std::vector<std::pair<std::string, std::string>> cols = {
      {"MzT_Nm", "M_z,T (tail)"}, {"MzF_Nm", "M_z,F (friction)"}, {"Izz_phiddot_Nm", "I_zz φ̈ (inertial)"}};
  std::vector<std::string> mm;
  for (const std::string& m : models)
    for (const auto& [col, label] : cols)
      if (ts[m].has(col)) {
        mm.push_back(m);
        break;
      }
  if (mm.empty()) return;
  std::ostringstream mb;
  mb << "reset\nset multiplot layout " << mm.size() << ",1\n";
  for (const std::string& m : mm) {
    const TimeSeries& s = ts[m];
    const std::string stem = stem_prefix + "_moments_" + m;
    std::vector<std::string> names = {"t_s"};
    for (const auto& [col, label] : cols) names.push_back(col);
    std::vector<std::vector<double>> rows;
    for (size_t k = 0; k < s.numRows(); ++k) {
      std::vector<double> row = {s.values("t_s")[k]};
      for (const auto& [col, label] : cols) row.push_back(s.has(col) ? s.values(col)[k] : kNaN);
      rows.push_back(row);
    }
    writeDataFile(ctx.data(stem), names, rows);
    mb << "set grid\nset key top right box opaque\nset title " << gpQuote(r.name + ": moments, " + modelTitle(m))
       << "\nset xlabel 't [s]'\nset ylabel 'moment [N m]'\nplot ";
    int n = 0;
    for (size_t j = 0; j < cols.size(); ++j) {
      if (!s.has(cols[j].first)) continue;
      mb << (n++ ? ", " : "") << gpQuote(stem + ".dat") << " using 1:" << j + 2 << " with lines lw 2 lc rgb "
         << gpQuote(seriesColor(j)) << " title " << gpQuote(cols[j].second);
    }
    mb << "\n";
  }
  mb << "unset multiplot\n";
  ctx.render(stem_prefix + "_moments", mb.str(), r.name + ": M_z,T, M_z,F and I_zz φ̈ over time, per model", 1000,
             450 * static_cast<int>(mm.size()));
}

// ---- heat maps ------------------------------------------------------------------------------

// values[model][iy][ix]; x = axes[1], y = axes[0].
void heatMap(Ctx& ctx, const std::string& stem, const std::string& what, const std::string& cblabel,
             const char* cellfmt, const SweepAxis& ax, const SweepAxis& ay,
             const std::vector<std::pair<std::string, std::vector<std::vector<double>>>>& values) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& [m, grid] : values)
    for (const auto& row : grid)
      for (double v : row)
        if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  if (!std::isfinite(lo)) return;
  if (hi <= lo) hi = lo + 1.0;
  auto tics = [](const SweepAxis& a, const char* axis) {
    std::ostringstream o;
    o << "set " << axis << "tics (";
    for (size_t i = 0; i < a.values.size(); ++i) o << (i ? ", " : "") << gpQuote(a.values[i]) << " " << i;
    o << ")\n";
    return o.str();
  };
  std::ostringstream b;
  b << "reset\nset multiplot layout 1," << values.size() << "\n";
  for (const auto& [m, grid] : values) {
    const std::string dstem = stem + "_" + m;
    std::vector<std::vector<double>> rows;
    for (size_t iy = 0; iy < grid.size(); ++iy)
      for (size_t ix = 0; ix < grid[iy].size(); ++ix)
        rows.push_back({double(ix), double(iy), grid[iy][ix]});
    writeDataFile(ctx.data(dstem), {"ix", "iy", "value"}, rows);
    b << "set title " << gpQuote(ctx.r.name + ": " + what + ", " + modelTitle(m)) << "\n"
      << "set xlabel " << gpQuote(axisLabel(ax.key)) << "\nset ylabel " << gpQuote(axisLabel(ay.key)) << "\n"
      << "set xrange [-0.5:" << ax.values.size() - 0.5 << "]\nset yrange [-0.5:" << ay.values.size() - 0.5 << "]\n"
      << tics(ax, "x") << tics(ay, "y") << "set cbrange [" << lo << ":" << hi << "]\n"
      << "set cblabel " << gpQuote(cblabel) << "\n"
      << "set palette defined (0 '#fff7bc', 1 '#fec44f', 2 '#f07b2a')\n"
      << "plot " << gpQuote(dstem + ".dat")
      << " using 1:2:(0.5):(0.5):3 with boxxyerror fs solid 1.0 noborder fc palette notitle, \\\n"
      << "     '' using 1:2:(sprintf(" << gpQuote(cellfmt) << ", $3)) with labels font 'Sans,"
      << (ax.values.size() > 9 ? 11 : 12) << "' notitle\n";
  }
  b << "unset multiplot\n";
  const int w = std::max(800, static_cast<int>(80 * ax.values.size() + 320)) * static_cast<int>(values.size());
  const int h = std::max(600, static_cast<int>(50 * ay.values.size() + 250));
  ctx.render(stem, b.str(), ctx.r.name + ": " + what + " over " + leafKey(ax.key) + " and " + leafKey(ay.key), w, h);
}

// ---- simulate, sweeps -----------------------------------------------------------------------

void plotOneKey(Ctx& ctx) {
  const ExperimentResults& r = ctx.r;
  const SweepAxis& a = r.axes[0];
  const std::string stem = r.name + "_phi_net";
  std::vector<std::vector<double>> rows;
  for (size_t i = 0; i < a.values.size(); ++i) {
    std::vector<double> row = {a.number(i)};
    const CaseRecord* c = r.find({{a.key, a.values[i]}});
    for (const std::string& m : r.models) row.push_back(c ? r.phiNet(*c, m) : kNaN);
    rows.push_back(row);
  }
  std::vector<std::string> names = {leafKey(a.key)};
  for (const std::string& m : r.models) names.push_back(m + "_phi_net_deg");
  writeDataFile(ctx.data(stem), names, rows);

  std::ostringstream b;
  b << header(r.name + ": net rotation φ_net", axisLabel(a.key), "φ_net [deg]");
  const bool bars = leafKey(a.key) == "links" || !a.numeric;
  if (bars) {
    b << "set style data histogram\nset style histogram cluster gap 1\nset style fill solid 0.85 border -1\n"
      << "set boxwidth 0.9\nset offsets 0, 0, graph 0.1, 0\nset xzeroaxis lt -1\nset grid noxtics\nplot ";
    for (size_t j = 0; j < r.models.size(); ++j)
      b << (j ? ", " : "") << gpQuote(stem + ".dat") << " using " << j + 2 << (j ? "" : ":xtic(1)") << " lc rgb "
        << gpQuote(modelColor(r.models[j])) << " title " << gpQuote(modelTitle(r.models[j]));
    // gnuplot's xtic(1) prints the number as written in the data file
  } else {
    b << "plot ";
    for (size_t j = 0; j < r.models.size(); ++j)
      b << (j ? ", " : "") << gpQuote(stem + ".dat") << " using 1:" << j + 2
        << " with linespoints lw 2 pt 7 ps 1.2 lc rgb " << gpQuote(modelColor(r.models[j])) << " title "
        << gpQuote(modelTitle(r.models[j]));
  }
  b << "\n";
  ctx.render(stem, b.str(), r.name + ": φ_net over " + leafKey(a.key) + (bars ? " (bars)" : "") + ", per model");

  // phi(t) of every case, one panel per model (few cases only).
  if (r.cases.size() > 12) return;
  std::vector<std::string> models;
  std::ostringstream t;
  std::ostringstream panels;
  for (const std::string& m : r.models) {
    std::ostringstream p;
    int n = 0;
    for (size_t i = 0; i < a.values.size(); ++i) {
      const CaseRecord* c = r.find({{a.key, a.values[i]}});
      if (!c) continue;
      TimeSeries s;
      try {
        s = r.series(*c, m);
      } catch (const std::exception&) {
        continue;
      }
      if (!s.has("t_s") || !s.has("phi_deg")) continue;
      const std::string dstem = r.name + "_phi_t_" + m + "_" + std::to_string(i);
      std::vector<std::vector<double>> rr;
      for (size_t k = 0; k < s.numRows(); ++k) rr.push_back({s.values("t_s")[k], s.values("phi_deg")[k]});
      writeDataFile(ctx.data(dstem), {"t_s", "phi_deg"}, rr);
      p << (n++ ? ", \\\n     " : "plot ") << gpQuote(dstem + ".dat") << " using 1:2 with lines lw 2 lc rgb "
        << gpQuote(seriesColor(i)) << " title " << gpQuote(leafKey(a.key) + " = " + a.values[i]);
    }
    if (!n) continue;
    models.push_back(m);
    panels << "set grid\nset key outside right box\nset title " << gpQuote(r.name + ": φ(t), " + modelTitle(m))
           << "\nset xlabel 't [s]'\nset ylabel 'φ [deg]'\n"
           << p.str() << "\n";
  }
  if (models.empty()) return;
  t << "reset\nset multiplot layout " << models.size() << ",1\n" << panels.str() << "unset multiplot\n";
  ctx.render(r.name + "_phi_t", t.str(), r.name + ": φ(t) of every case, per model", 1100,
             450 * static_cast<int>(models.size()));
}

void plotTwoKeys(Ctx& ctx) {
  const ExperimentResults& r = ctx.r;
  const SweepAxis& ay = r.axes[0];  // slowest-varying key (first in the file)
  const SweepAxis& ax = r.axes[1];
  std::vector<std::pair<std::string, std::vector<std::vector<double>>>> grids;
  for (const std::string& m : r.models) {
    std::vector<std::vector<double>> g(ay.values.size(), std::vector<double>(ax.values.size(), kNaN));
    for (size_t iy = 0; iy < ay.values.size(); ++iy)
      for (size_t ix = 0; ix < ax.values.size(); ++ix)
        if (const CaseRecord* c = r.find({{ay.key, ay.values[iy]}, {ax.key, ax.values[ix]}}))
          g[iy][ix] = r.phiNet(*c, m);
    grids.emplace_back(m, g);
  }
  heatMap(ctx, r.name + "_phi_net_map", "φ_net [deg]", "φ_net [deg]", "%.1f", ax, ay, grids);

  // Curves over the x key, one per y value, one panel per model.
  std::ostringstream b;
  b << "reset\nset multiplot layout 1," << grids.size() << "\n";
  for (const auto& [m, g] : grids) {
    const std::string dstem = r.name + "_phi_net_lines_" + m;
    std::vector<std::vector<double>> rows;
    for (size_t ix = 0; ix < ax.values.size(); ++ix) {
      std::vector<double> row = {ax.number(ix)};
      for (size_t iy = 0; iy < ay.values.size(); ++iy) row.push_back(g[iy][ix]);
      rows.push_back(row);
    }
    std::vector<std::string> names = {leafKey(ax.key)};
    for (const std::string& v : ay.values) names.push_back(leafKey(ay.key) + "=" + v);
    writeDataFile(ctx.data(dstem), names, rows);
    b << "set grid\nset key outside right box\nset title " << gpQuote(r.name + ": φ_net, " + modelTitle(m)) << "\n"
      << "set xlabel " << gpQuote(axisLabel(ax.key)) << "\nset ylabel 'φ_net [deg]'\nplot ";
    for (size_t iy = 0; iy < ay.values.size(); ++iy)
      b << (iy ? ", \\\n     " : "") << gpQuote(dstem + ".dat") << " using 1:" << iy + 2
        << " with linespoints lw 2 pt 7 lc rgb " << gpQuote(seriesColor(iy)) << " title "
        << gpQuote(leafKey(ay.key) + " = " + ay.values[iy]);
    b << "\n";
  }
  b << "unset multiplot\n";
  ctx.render(r.name + "_phi_net_lines", b.str(),
             r.name + ": φ_net over " + leafKey(ax.key) + ", one curve per " + leafKey(ay.key), 1100 * grids.size(), 700);
}

void plotManyKeys(Ctx& ctx) {
  const ExperimentResults& r = ctx.r;
  const std::string stem = r.name + "_phi_net_cases";
  std::vector<std::vector<double>> rows;
  for (size_t i = 0; i < r.cases.size(); ++i) {
    std::vector<double> row = {double(i)};
    for (const std::string& m : r.models) row.push_back(r.phiNet(r.cases[i], m));
    rows.push_back(row);
  }
  writeDataFile(ctx.data(stem), {"case"}, rows);
  std::ostringstream b;
  b << header(r.name + ": φ_net per case (see summary.json for the case order)", "case index", "φ_net [deg]")
    << "plot ";
  for (size_t j = 0; j < r.models.size(); ++j)
    b << (j ? ", " : "") << gpQuote(stem + ".dat") << " using 1:" << j + 2 << " with linespoints pt 7 lc rgb "
      << gpQuote(modelColor(r.models[j])) << " title " << gpQuote(modelTitle(r.models[j]));
  b << "\n";
  ctx.render(stem, b.str(), r.name + ": φ_net per case");
}

// ---- pose -----------------------------------------------------------------------------------

double poseValue(const ExperimentResults& r, const CaseRecord* c, const std::string& model, const std::string& col) {
  if (!c) return kNaN;
  try {
    const TimeSeries s = r.series(*c, model);
    if (!s.has(col) || s.numRows() == 0) return kNaN;
    return s.values(col)[0];
  } catch (const std::exception&) {
    return kNaN;
  }
}

void plotPoseOneKey(Ctx& ctx) {
  const ExperimentResults& r = ctx.r;
  const SweepAxis& a = r.axes[0];
  // Columns present in the first readable pose CSV.
  TimeSeries probe;
  std::string model;
  for (const std::string& m : r.models) {
    for (const CaseRecord& c : r.cases) {
      try {
        probe = r.series(c, m);
        model = m;
        break;
      } catch (const std::exception&) {
      }
    }
    if (!model.empty()) break;
  }
  if (model.empty()) return;
  std::vector<std::pair<std::string, std::string>> parts;
  if (probe.has("MzT_tan_Nm") && probe.has("MzT_cen_Nm"))
    parts = {{"MzT_tan_Nm", "(a) tangential M_z,T,tan / I_zz"}, {"MzT_cen_Nm", "(b) centripetal M_z,T,cen / I_zz"}};
  else if (probe.has("MzT_acc_Nm") && probe.has("MzT_speed_Nm"))
    parts = {{"MzT_acc_Nm", "(a) acceleration-driven M_z,T,acc / I_zz"},
             {"MzT_speed_Nm", "(b) speed-driven M_z,T,speed / I_zz"}};
  const bool perIzz = probe.has("Izz_kgm2");
  if (!parts.empty()) {
    const std::string stem = r.name + "_contributions";
    std::vector<std::vector<double>> rows;
    for (size_t i = 0; i < a.values.size(); ++i) {
      const CaseRecord* c = r.find({{a.key, a.values[i]}});
      const double izz = perIzz ? poseValue(r, c, model, "Izz_kgm2") : 1.0;
      rows.push_back({a.number(i), poseValue(r, c, model, parts[0].first) / izz,
                      poseValue(r, c, model, parts[1].first) / izz});
    }
    writeDataFile(ctx.data(stem), {leafKey(a.key), parts[0].first, parts[1].first}, rows);
    const std::string ylabel = perIzz ? "contribution to φ̈ [rad/s²]" : "moment [N m]";
    std::ostringstream b;
    b << "reset\nset multiplot layout 1,2\n";
    for (int j = 0; j < 2; ++j)
      b << "set grid\nunset key\nset title " << gpQuote(parts[j].second) << "\nset xlabel "
        << gpQuote(axisLabel(a.key)) << "\nset ylabel " << gpQuote(ylabel) << "\nplot " << gpQuote(stem + ".dat")
        << " using 1:" << j + 2 << " with linespoints lw 2 pt 7 lc rgb " << gpQuote(seriesColor(j)) << "\n";
    b << "unset multiplot\n";
    ctx.render(stem, b.str(), r.name + ": " + parts[0].second + " and " + parts[1].second + " over " + leafKey(a.key),
               1600, 650);
  }
  if (probe.has("LF_m")) {
    const std::string stem = r.name + "_LF";
    std::vector<std::vector<double>> rows;
    for (size_t i = 0; i < a.values.size(); ++i)
      rows.push_back({a.number(i), 1e3 * poseValue(r, r.find({{a.key, a.values[i]}}), model, "LF_m")});
    writeDataFile(ctx.data(stem), {leafKey(a.key), "LF_mm"}, rows);
    std::ostringstream b;
    b << header(r.name + ": friction moment arm L_F", axisLabel(a.key), "L_F [mm]") << "unset key\nplot "
      << gpQuote(stem + ".dat") << " using 1:2 with linespoints lw 2 pt 7 lc rgb " << gpQuote(modelColor(model))
      << "\n";
    ctx.render(stem, b.str(), r.name + ": L_F over " + leafKey(a.key));
  }
}

void plotPoseTwoKeys(Ctx& ctx) {
  const ExperimentResults& r = ctx.r;
  const SweepAxis& ay = r.axes[0];
  const SweepAxis& ax = r.axes[1];
  std::vector<std::pair<std::string, std::vector<std::vector<double>>>> grids;
  for (const std::string& m : r.models) {
    std::vector<std::vector<double>> g(ay.values.size(), std::vector<double>(ax.values.size(), kNaN));
    bool any = false;
    for (size_t iy = 0; iy < ay.values.size(); ++iy)
      for (size_t ix = 0; ix < ax.values.size(); ++ix) {
        g[iy][ix] = 1e3 * poseValue(r, r.find({{ay.key, ay.values[iy]}, {ax.key, ax.values[ix]}}), m, "LF_m");
        any = any || std::isfinite(g[iy][ix]);
      }
    if (any) grids.emplace_back(m, g);
  }
  if (!grids.empty()) heatMap(ctx, r.name + "_LF_map", "L_F [mm]", "L_F [mm]", "%.1f", ax, ay, grids);
}

}  // namespace

std::vector<PlotFile> plotExperiment(const ExperimentResults& r) {
  Ctx ctx{r, (fs::path(r.dir) / "plots").string(), {}};
  fs::create_directories(ctx.plots);
  if (r.cases.empty() || r.models.empty()) return {};
  if (r.kind == "pose") {
    if (r.axes.size() == 1) plotPoseOneKey(ctx);
    else if (r.axes.size() >= 2) plotPoseTwoKeys(ctx);
  } else if (r.axes.empty()) {
    plotSingleCase(ctx, r.cases.front(), r.name);
  } else if (r.axes.size() == 1) {
    plotOneKey(ctx);
  } else if (r.axes.size() == 2) {
    plotTwoKeys(ctx);
  } else {
    plotManyKeys(ctx);
  }
  return ctx.out;
}

std::vector<PlotFile> plotResults(const std::string& dir) {
  std::vector<PlotFile> all;
  for (const ExperimentResults& r : loadResultTree(dir)) {
    std::vector<PlotFile> p = plotExperiment(r);
    all.insert(all.end(), p.begin(), p.end());
  }
  return all;
}

}  // namespace tailsim
