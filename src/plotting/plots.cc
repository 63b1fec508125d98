#include "plotting/plots.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include "plotting/figure_sheet.h"
#include "common/atomic_file.h"
#include "results/columns.h"
#include "plotting/gnuplot.h"
#include "plotting/style.h"
#include "experiments/model_registry.h"
#include "common/number_text.h"

namespace tailsim {

namespace fs = std::filesystem;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string fmt(const char* f, double v) {
  std::string s = formatNumber(f, v);
  // "-0.0" -> "0.0": a value that rounds to zero has no sign.
  if (s.size() > 1 && s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

// Text in two forms: gnuplot enhanced text for the figure, plain Unicode for captions.
struct Txt {
  std::string gp, plain;
  Txt operator+(const Txt& o) const { return {gp + o.gp, plain + o.plain}; }
};
// Words with tailsim identifiers (phi_net, d_Q2B, ...) turned into symbols.
Txt W(const std::string& words) { return {gpSymbols(words), plainSymbols(words)}; }
// A swept key's symbol.
Txt K(const std::string& key) {
  const KeyDisplay d = keyDisplay(key);
  return {d.symbol, d.plain};
}
Txt V(const std::string& key, const std::string& value) {
  return {gpValueLabel(key, value), plainValueLabel(key, value)};
}

// Whether a model reads a key: "analytic.coupling" is read by the analytic model only (a section
// named after another model); every other section by every model.
bool modelReads(const std::string& model, const std::string& key) {
  const std::string section = key.substr(0, key.find('.'));
  const std::vector<std::string> models = modelNames();
  return section == model || std::find(models.begin(), models.end(), section) == models.end();
}

// A tic label: the value in the axis's unit (d_Q2B in mm), words for non-numeric values.
std::string ticLabel(const std::string& key, const std::string& value) {
  const auto v = parseNumber(value);
  if (!v) return gpValueLabel(key, value, false);
  return fmt("%g", *v * keyDisplay(key).scale);
}

struct Ctx {
  const ExperimentResults& r;
  std::string plots;  // r.dir/plots
  Txt fig;            // "Fig. 6a"
  Txt tail;           // ", 1-link tail" when the experiment has one tail
  std::vector<PlotFile> out;
  PlotOptions opt;

  Txt title(const Txt& what) const { return fig + Txt{" — ", " — "} + what; }
  // The figure's own title for `set title` / `set multiplot ... title`: empty with --no-titles
  // (the caption keeps it). Panel titles (which model, which facet) stay.
  std::string figTitle(const Txt& t, int width_px, double font_pt = 15) const {
    return opt.titles ? gpTitle(t.gp, width_px, font_pt) : std::string("''");
  }
  std::string data(const std::string& stem) const { return (fs::path(plots) / (stem + ".dat")).string(); }
  void render(const std::string& stem, const std::string& body, const Txt& title, const std::string& caption,
              int w = 1000, int h = 700) {
    GnuplotFigure f;
    f.stem = stem;
    f.body = body;
    f.width_px = opt.width_px > 0 ? opt.width_px : w;
    f.height_px = opt.height_px > 0 ? opt.height_px : h;
    f.font_scale = opt.font_scale;
    out.push_back({renderFigure(plots, f), caption, title.plain});
  }
};

// width_px: the figure's width, so that a long title is wrapped to fit it.
std::string header(const Ctx& ctx, const Txt& title, const std::string& xlabel, const std::string& ylabel,
                   int width_px = 1000) {
  std::ostringstream o;
  o << "reset\nset grid\nset key top left box opaque\n";
  o << "set title " << ctx.figTitle(title, width_px) << "\n";
  o << "set xlabel " << gpQuote(xlabel) << "\nset ylabel " << gpQuote(ylabel) << "\n";
  return o.str();
}

std::string range(const char* axis, double lo, double hi) {
  return std::string("set ") + axis + "range [" + fmt("%.6g", lo) + ":" + fmt("%.6g", hi) + "]\n";
}

// A panel's y range, or gnuplot's autoscale when the panel has no finite value.
std::string yRangeOrAuto(const std::pair<double, double>& r) {
  return std::isfinite(r.first) ? range("y", r.first, r.second) : std::string("set autoscale y\n");
}

// The start of a figure of panels: a multiplot of rows x cols under the figure's title.
std::string multiplotHead(const Ctx& ctx, const Txt& title, int width_px, size_t rows, size_t cols = 1) {
  std::ostringstream o;
  o << "reset\nset multiplot layout " << rows << "," << cols << " title " << ctx.figTitle(title, width_px, 17)
    << " font 'Sans,17'\n";
  return o.str();
}

// Tics at the index of every `every`-th value of a, labelled with the value: "set xtics (...)", no newline.
std::string indexTics(const SweepAxis& a, const char* axis = "x", size_t every = 1) {
  std::ostringstream o;
  o << "set " << axis << "tics (";
  for (size_t i = 0; i < a.values.size(); i += every) o << (i ? ", " : "") << gpQuote(ticLabel(a.key, a.values[i])) << " " << i;
  o << ")";
  return o.str();
}

// A categorical x axis: one tic a value at its index, 0.3 of a step of margin on both sides.
std::string categoricalXAxis(const SweepAxis& a) {
  std::ostringstream o;
  o << "set xrange [-0.3:" << a.values.size() - 0.7 << "]\n" << indexTics(a) << "\n";
  return o.str();
}

// One series' phi(t) as a data file (t_s, phi_deg).
void writePhiData(const Ctx& ctx, const std::string& stem, const TimeSeries& s) {
  std::vector<std::vector<double>> rows;
  const auto& t = s.values(col::kT);
  const auto& phi = s.values(col::kPhi);
  for (size_t k = 0; k < t.size(); ++k) rows.push_back({t[k], phi[k]});
  writeDataFile(ctx.data(stem), {col::kT, col::kPhi}, rows);
}

// [lo, hi] of the finite values, widened by `margin` of the span on both sides.
std::pair<double, double> span(const std::vector<double>& v, double margin) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (double x : v)
    if (std::isfinite(x)) lo = std::min(lo, x), hi = std::max(hi, x);
  if (!std::isfinite(lo)) return {kNaN, kNaN};
  double d = hi - lo;
  if (d <= 0) d = std::max(1e-3, std::fabs(hi));
  return {lo - margin * d, hi + margin * d};
}

// The y ranges of panels that compare models: one shared range, unless one panel's values span
// more than three times another's (a model's spikes or blow-up would squash the others' curves);
// then each panel its own. Returns one range per panel and whether they are shared.
std::pair<std::vector<std::pair<double, double>>, bool> panelRanges(const std::vector<std::vector<double>>& panels,
                                                                    double margin) {
  std::vector<std::pair<double, double>> own;
  std::vector<double> all;
  double widest = 0, narrowest = std::numeric_limits<double>::infinity();
  for (const auto& v : panels) {
    own.push_back(span(v, margin));
    all.insert(all.end(), v.begin(), v.end());
    if (std::isfinite(own.back().first)) {
      const double w = own.back().second - own.back().first;
      widest = std::max(widest, w), narrowest = std::min(narrowest, w);
    }
  }
  if (widest > 3 * narrowest) return {own, false};
  return {std::vector<std::pair<double, double>>(panels.size(), span(all, margin)), true};
}

// ---- time axes and phases -------------------------------------------------------------------

std::vector<std::string> jointSpeedColumns(const TimeSeries& s) {
  std::vector<std::string> cols;
  for (int i = 1; s.has(col::thetadot(i)); ++i) cols.push_back(col::thetadot(i));
  return cols;
}

// Start and end of the tail's motion: the first and last sample where some joint moves faster
// than `rel` times the peak joint speed (NaN if the CSV has no joint speeds).
std::pair<double, double> tailMotion(const TimeSeries& s, double rel) {
  const auto cols = jointSpeedColumns(s);
  if (cols.empty() || !s.has(col::kT)) return {kNaN, kNaN};
  double peak = 0;
  for (const auto& c : cols)
    for (double v : s.values(c))
      if (std::isfinite(v)) peak = std::max(peak, std::fabs(v));
  if (!(peak > 0)) return {kNaN, kNaN};
  const auto& t = s.values(col::kT);
  double first = kNaN, last = kNaN;
  for (size_t k = 0; k < t.size(); ++k)
    for (const auto& c : cols)
      if (std::fabs(s.values(c)[k]) > rel * peak) {
        if (!std::isfinite(first)) first = t[k];
        last = t[k];
      }
  return {first, last};
}

// End of a time axis: the later of the tail's end and the models' t_stop_s, plus 15 % (at
// least two output samples), never beyond the data.
double timeAxisEnd(const std::vector<const TimeSeries*>& series, const std::vector<double>& t_stops) {
  double last = 0, data_end = 0, dt = 0;
  for (const TimeSeries* s : series) {
    if (!s->has(col::kT) || s->numRows() < 2) continue;
    const auto& t = s->values(col::kT);
    data_end = std::max(data_end, t.back());
    dt = std::max(dt, t[1] - t[0]);
    const double end = tailMotion(*s, 0.01).second;  // 1 %: a servo's jitter is not motion
    if (std::isfinite(end)) last = std::max(last, end);
  }
  for (double ts : t_stops)
    if (std::isfinite(ts)) last = std::max(last, ts);
  if (!(last > 0) || !(data_end > 0)) return data_end;
  return std::min(data_end, last + std::max(0.15 * last, 2 * dt));
}

struct Phases {
  bool ok = false;
  double t_start = 0, t1 = 0, t_rev = 0, t_stuck = 0, t2 = 0;
};

// Fig. 7's phases from the analytic run's own events: A tail accelerates (tail start -> t1, peak
// joint speed), B tail decelerates while the body still turns forward (t1 -> phidot changes
// sign), C body turns back (-> rot_state returns to stuck), D body at rest. t2 = end of the tail's
// motion. Needs t_s, joint speeds, phidot_dps and rot_state, with the events in this order.
Phases findPhases(const TimeSeries& s) {
  Phases p;
  const auto cols = jointSpeedColumns(s);
  if (cols.empty() || !s.has(col::kT) || !s.has(col::kPhidot) || !s.has(col::kRotState) || s.numRows() < 4) return p;
  const auto& t = s.values(col::kT);
  const auto& w = s.values(col::kPhidot);
  const auto& rot = s.values(col::kRotState);
  const auto& th = s.values(cols[0]);
  size_t ipk = 0;
  for (size_t k = 0; k < th.size(); ++k)
    if (std::fabs(th[k]) > std::fabs(th[ipk])) ipk = k;
  const auto [start, end] = tailMotion(s, 1e-6);  // the analytic profile is exact
  if (!std::isfinite(start)) return p;
  // first sample of the tail's motion: the sample before it is still at rest
  size_t i0 = 0;
  while (i0 + 1 < t.size() && t[i0 + 1] < start) ++i0;
  p.t_start = t[i0];
  p.t1 = t[ipk];
  // phidot's sign after the tail starts, then its first change of sign after t1
  double sign = 0;
  for (size_t k = i0; k < w.size() && sign == 0; ++k)
    if (std::fabs(w[k]) > 1e-9) sign = w[k] > 0 ? 1 : -1;
  size_t irev = w.size();
  for (size_t k = ipk; k < w.size(); ++k)
    if (w[k] * sign < 0) { irev = k; break; }
  if (irev == w.size()) return p;
  size_t istuck = rot.size();
  for (size_t k = irev; k < rot.size(); ++k)
    if (rot[k] == 0 && rot[k - 1] == 1) { istuck = k; break; }
  if (istuck == rot.size()) return p;
  p.t_rev = t[irev];
  p.t_stuck = t[istuck];
  p.t2 = end;
  p.ok = p.t_start < p.t1 && p.t1 < p.t_rev && p.t_rev < p.t_stuck;
  return p;
}

// Shaded bands and letters for the phases (gnuplot objects persist over a multiplot's panels),
// and the tail's t1, t2 as dotted lines.
std::string phaseObjects(const Phases& p, double t_end) {
  if (!p.ok) return {};
  std::ostringstream o;
  const double b[] = {p.t_start, p.t1, p.t_rev, p.t_stuck, std::max(t_end, p.t_stuck)};
  // Grey levels 0.80 and 0.91 (about 20 and 9 % below white): distinct from each other and from
  // the white plot area in print and on a projector, light enough for every curve colour on top.
  const char* shade[] = {"#CCCCCC", "#E8E8E8", "#CCCCCC", "#E8E8E8"};
  const char* letter[] = {"A", "B", "C", "D"};
  for (int i = 0; i < 4; ++i) {
    o << "set object " << 10 + i << " rect from " << fmt("%.6g", b[i]) << ", graph 0 to " << fmt("%.6g", b[i + 1])
      << ", graph 1 behind fc rgb '" << shade[i] << "' fs solid 1.0 noborder\n"
      << "set label " << 10 + i << " '" << letter[i] << "' at " << fmt("%.6g", 0.5 * (b[i] + b[i + 1]))
      << ", graph 0.92 center font 'Sans,17' tc rgb '#444444' front\n";
  }
  o << "set arrow 20 from " << fmt("%.6g", p.t1) << ", graph 0 to " << fmt("%.6g", p.t1)
    << ", graph 1 nohead dt 3 lw 1 lc rgb '#666666' back\n";
  if (std::isfinite(p.t2))
    o << "set arrow 21 from " << fmt("%.6g", p.t2) << ", graph 0 to " << fmt("%.6g", p.t2)
      << ", graph 1 nohead dt 3 lw 1 lc rgb '#666666' back\n"
      << "set label 21 't_2' at " << fmt("%.6g", p.t2) << ", graph 0.975 left offset char 0.3,0 font 'Sans,12' "
      << "tc rgb '#444444' front\n";
  o << "set label 20 't_1' at " << fmt("%.6g", p.t1) << ", graph 0.975 left offset char 0.3,0 font 'Sans,12' "
    << "tc rgb '#444444' front\n";
  return o.str();
}

std::string phaseCaption(const Phases& p) {
  if (!p.ok) return {};
  return " Shaded phases from the analytic run's events: A tail accelerates (" + fmt("%.3f", p.t_start) + "–" +
         fmt("%.3f", p.t1) + " s, t1 = peak joint speed), B tail decelerates while the body still turns (to φ̇ = 0 at " +
         fmt("%.3f", p.t_rev) + " s), C body turns back (until it sticks again, rot_state, at " +
         fmt("%.3f", p.t_stuck) + " s), D body at rest; t2 = end of the tail's motion.";
}

// ---- simulate, one case: phi(t) and moments ------------------------------------------------

// One case's readable series (with t and phi), the models that have one in the experiment's
// order, the end of their time axis and the analytic run's phases.
struct CaseSeries {
  std::vector<std::string> models;
  std::map<std::string, TimeSeries> ts;
  double t_end = 0;
  Phases phases;
};

// Stage 1 of plotSingleCase: the series, their time axis and phases.
CaseSeries loadCaseSeries(const ExperimentResults& r, const CaseRecord& c) {
  CaseSeries cs;
  for (const std::string& m : r.models) {
    try {
      TimeSeries s = r.series(c, m);
      if (s.has(col::kT) && s.has(col::kPhi)) {
        cs.ts[m] = std::move(s);
        cs.models.push_back(m);
      }
    } catch (const std::exception&) {
    }
  }
  if (cs.models.empty()) return cs;
  std::vector<const TimeSeries*> all;
  std::vector<double> stops;
  for (const std::string& m : cs.models) {
    all.push_back(&cs.ts.at(m));
    if (auto it = c.runs.find(m); it != c.runs.end() && it->second.ok) stops.push_back(it->second.t_stop_s);
  }
  cs.t_end = timeAxisEnd(all, stops);
  cs.phases = cs.ts.count(kAnalyticModel) ? findPhases(cs.ts.at(kAnalyticModel)) : Phases{};
  return cs;
}

// The title's ": analytic vs MuJoCo" or ": <model>", when the figure shows those.
Txt modelsInTitle(const ExperimentResults& r, const CaseSeries& cs) {
  if (cs.models.size() == 2 && cs.ts.count(kAnalyticModel) && cs.ts.count(kMujocoModel)) {
    const std::string v = ": " + modelShortTitle(kAnalyticModel) + " vs " + modelShortTitle(kMujocoModel);
    return {v, v};
  }
  if (cs.models.size() == 1) return {": " + gpText(r.modelTitle(cs.models[0])), ": " + r.modelTitle(cs.models[0])};
  return {"", ""};
}

// Stage 2: phi(t), all models overlaid (Figs. 6, 7a).
void plotPhiOfTime(Ctx& ctx, const CaseRecord& c, const CaseSeries& cs, const std::string& stem_prefix) {
  const Txt phi_title = ctx.title(W("body yaw phi(t)") + ctx.tail + modelsInTitle(ctx.r, cs));
  std::ostringstream body;
  body << header(ctx, phi_title, "t [s]", "φ [deg]") << range("x", 0, cs.t_end) << phaseObjects(cs.phases, cs.t_end);
  body << "set key bottom right box opaque\nplot ";  // phi rises from 0 and settles: bottom right is free
  for (size_t i = 0; i < cs.models.size(); ++i) {
    const std::string& m = cs.models[i];
    const std::string stem = stem_prefix + "_phi_" + m;
    writePhiData(ctx, stem, cs.ts.at(m));
    const double net = ctx.r.phiNet(c, m);
    std::string title = gpText(ctx.r.modelTitle(m));
    if (std::isfinite(net)) title += ", φ_{net} = " + fmt("%.2f", net) + "°";
    body << (i ? ", \\\n     " : "") << gpFileName(stem + ".dat") << " using 1:2 with lines lw 2.5 lc rgb "
         << gpQuote(modelColor(m)) << " title " << gpQuote(title);
  }
  body << "\n";
  ctx.render(stem_prefix + "_phi", body.str(), phi_title,
             phi_title.plain + ". Body yaw angle over time" +
                 (cs.models.size() > 1 ? std::string(", both models overlaid") : std::string()) +
                 "; the legend gives each model's net rotation φ_net." + phaseCaption(cs.phases));
}

// The moment columns of Fig. 7b and their legend titles.
const std::vector<std::pair<std::string, std::string>>& momentColumns() {
  static const std::vector<std::pair<std::string, std::string>> cols = {
      {col::kMzT, "M_{z,T} (tail)"}, {col::kMzF, "M_{z,F} (friction)"}, {col::kIzzPhiddot, "I_{zz} φ̈ (inertial)"}};
  return cols;
}

// One moments panel: its y range (its values up to t_end with a margin, nothing clipped: one
// model's spikes, MuJoCo's impulse averages in docs/mujoco-model.md "Force and moment columns",
// never squash another model's curves), its data file and its plot.
std::string momentsPanel(const Ctx& ctx, const TimeSeries& s, const std::string& m, const std::string& stem,
                         double t_end) {
  const auto& cols = momentColumns();
  std::vector<double> yv;
  for (const auto& [col, label] : cols)
    if (s.has(col))
      for (size_t k = 0; k < s.numRows(); ++k)
        if (s.values(col::kT)[k] <= t_end) yv.push_back(s.values(col)[k]);
  std::ostringstream mb;
  mb << yRangeOrAuto(span(yv, 0.12));
  std::vector<std::string> names = {col::kT};
  for (const auto& [col, label] : cols) names.push_back(col);
  std::vector<std::vector<double>> rows;
  for (size_t k = 0; k < s.numRows(); ++k) {
    std::vector<double> row = {s.values(col::kT)[k]};
    for (const auto& [col, label] : cols) row.push_back(s.has(col) ? s.values(col)[k] : kNaN);
    rows.push_back(row);
  }
  writeDataFile(ctx.data(stem), names, rows);
  std::string panel = gpText(ctx.r.modelTitle(m));
  if (const ModelEntry* e = findModel(m); e && !e->moments_note.empty()) panel += ": " + e->moments_note;
  // the legend beside the panel: inside, it hid curves wherever it was put
  mb << "set grid\nset key outside right top vertical box\nset title " << gpTitle(panel, 1000)
     << "\nset xlabel 't [s]'\nset ylabel 'moment [N m]'\nplot ";
  int n = 0;
  for (size_t j = 0; j < cols.size(); ++j) {
    if (!s.has(cols[j].first)) continue;
    mb << (n++ ? ", " : "") << gpFileName(stem + ".dat") << " using 1:" << j + 2 << " with lines lw 2 lc rgb "
       << gpQuote(quantityColor(j)) << " title " << gpQuote(cols[j].second);
  }
  mb << "\n";
  return mb.str();
}

// Stage 3: moments over time, one panel per model that has any, one time scale (Fig. 7b).
void plotMoments(Ctx& ctx, const CaseSeries& cs, const std::string& stem_prefix) {
  std::vector<std::string> mm;
  for (const std::string& m : cs.models)
    for (const auto& [col, label] : momentColumns())
      if (cs.ts.at(m).has(col)) {
        mm.push_back(m);
        break;
      }
  if (mm.empty()) return;
  const Txt mom_title = ctx.title(W("moments about the system COM") + ctx.tail);
  std::ostringstream mb;
  mb << multiplotHead(ctx, mom_title, 1200, mm.size()) << range("x", 0, cs.t_end) << phaseObjects(cs.phases, cs.t_end);
  for (const std::string& m : mm) mb << momentsPanel(ctx, cs.ts.at(m), m, stem_prefix + "_moments_" + m, cs.t_end);
  mb << "unset multiplot\n";
  std::string cap = mom_title.plain +
                    ". Tail moment M_z,T (Eq. 13), friction moment M_z,F and inertial moment I_zz φ̈ over time, one "
                    "panel per model, one time scale; each panel has its own moment scale (read the y tics).";
  for (const std::string& m : mm)
    if (const ModelEntry* e = findModel(m); e && !e->moments_caption.empty()) cap += " " + e->moments_caption;
  ctx.render(stem_prefix + "_moments", mb.str(), mom_title, cap + phaseCaption(cs.phases), 1200,
             60 + 430 * static_cast<int>(mm.size()));
}

void plotSingleCase(Ctx& ctx, const CaseRecord& c, const std::string& stem_prefix) {
  const CaseSeries cs = loadCaseSeries(ctx.r, c);
  if (cs.models.empty()) return;
  plotPhiOfTime(ctx, c, cs, stem_prefix);
  plotMoments(ctx, cs, stem_prefix);
}

// ---- heat maps ------------------------------------------------------------------------------

}  // namespace

FacetKeys facetKeys(const std::vector<SweepAxis>& axes) {
  FacetKeys f;
  if (axes.size() < 2) return f;
  // x: the numeric key with the most values (the first such), else the key with the most values.
  size_t x = axes.size();
  for (size_t i = 0; i < axes.size(); ++i)
    if (axes[i].numeric && (x == axes.size() || axes[i].values.size() > axes[x].values.size())) x = i;
  if (x == axes.size()) {
    x = 0;
    for (size_t i = 1; i < axes.size(); ++i)
      if (axes[i].values.size() > axes[x].values.size()) x = i;
  }
  // series: the remaining key with the fewest values (the first such).
  size_t s = axes.size();
  for (size_t i = 0; i < axes.size(); ++i)
    if (i != x && (s == axes.size() || axes[i].values.size() < axes[s].values.size())) s = i;
  f.x = x, f.series = s;
  for (size_t i = 0; i < axes.size(); ++i)
    if (i != x && i != s) f.facets.push_back(i);
  return f;
}

HeatMapLayout heatMapLayout(size_t nx, size_t ny) {
  HeatMapLayout l;
  nx = std::max<size_t>(nx, 1), ny = std::max<size_t>(ny, 1);
  l.cell_w = static_cast<int>(std::clamp<size_t>(2000 / nx, 1, 105));
  l.cell_h = static_cast<int>(std::clamp<size_t>(1400 / ny, 1, 82));
  l.values_in_cells = l.cell_w >= 60 && l.cell_h >= 30;  // "-12.3" in 15 pt Sans: ~50 x 20 px
  l.xtic_every = (80 + l.cell_w - 1) / l.cell_w;  // a tic label: up to ~8 characters, 80 px
  l.ytic_every = (24 + l.cell_h - 1) / l.cell_h;  // one line of 15 pt text
  l.panel_w = static_cast<int>(std::max<size_t>(4, nx)) * l.cell_w + 420;
  l.panel_h = static_cast<int>(std::max<size_t>(3, ny)) * l.cell_h + 230;
  return l;
}

namespace {

// One heat-map panel: its data file, title, colour bar and colour scale.
struct HeatPanel {
  std::string dstem, title, cblabel;
  std::vector<std::vector<double>> grid;
  bool diverging = false;
  bool negative = false;  // sequential with every value <= 0: dark at the most negative
  double cblo = 0, cbhi = 1;
};

// A panel's colour scale over [lo, hi]: diverging (centred on zero) when forced or when the
// values have both signs, else sequential.
void setColourScale(HeatPanel& p, double lo, double hi, bool force_diverging) {
  p.diverging = force_diverging || (lo < 0 && hi > 0);
  p.negative = !p.diverging && hi <= 0 && lo < 0;
  p.cblo = lo, p.cbhi = hi;
  if (p.diverging) p.cbhi = std::max(std::fabs(lo), std::fabs(hi)), p.cblo = -p.cbhi;
  if (p.cbhi <= p.cblo) p.cbhi = p.cblo + 1.0;
}

using ModelGrids = std::vector<std::pair<std::string, std::vector<std::vector<double>>>>;

// Stage of heatMap: one difference panel per model after the first (the reference), that model
// minus the first, all on one diverging scale; appended to panels. Returns the caption's
// sentence about them (empty when no difference is finite).
std::string addDifferencePanels(std::vector<HeatPanel>& panels, const std::string& stem, const std::string& cblabel,
                                const ModelGrids& values) {
  const auto& [m0, g0] = values[0];
  std::vector<HeatPanel> diffs;
  double dlo = std::numeric_limits<double>::infinity(), dhi = -dlo;
  for (size_t k = 1; k < values.size(); ++k) {
    const auto& [mk, gk] = values[k];
    HeatPanel d{stem + (values.size() == 2 ? std::string("_difference") : "_difference_" + mk),
                gpText(modelShortTitle(mk)) + " − " + gpText(modelShortTitle(m0)), "difference " + cblabel, g0};
    for (size_t iy = 0; iy < g0.size(); ++iy)
      for (size_t ix = 0; ix < g0[iy].size(); ++ix) {
        d.grid[iy][ix] = gk[iy][ix] - g0[iy][ix];
        if (std::isfinite(d.grid[iy][ix])) dlo = std::min(dlo, d.grid[iy][ix]), dhi = std::max(dhi, d.grid[iy][ix]);
      }
    diffs.push_back(d);
  }
  if (!std::isfinite(dlo)) return {};
  for (HeatPanel& d : diffs) setColourScale(d, dlo, dhi, true), panels.push_back(d);
  if (values.size() == 2)
    return " The last panel is " + modelShortTitle(values[1].first) + " minus " + modelShortTitle(m0) +
           " on its own scale (diverging, centred on zero: blue where " + modelShortTitle(values[1].first) +
           " is lower, vermillion where it is higher).";
  return " The last " + std::to_string(diffs.size()) + " panels are each other model minus " + modelShortTitle(m0) +
         ", on one scale of their own (diverging, centred on zero: blue where the model is lower than " +
         modelShortTitle(m0) + ", vermillion where it is higher).";
}

// Stage of heatMap: one panel's data file (ix, iy, value) and its plot: cells with their values
// printed when they fit, else one pixel block per cell.
std::string heatPanelPlot(const Ctx& ctx, const HeatPanel& p, const SweepAxis& ax, const SweepAxis& ay,
                          const HeatMapLayout& lay) {
  std::vector<std::vector<double>> rows;
  for (size_t iy = 0; iy < p.grid.size(); ++iy)
    for (size_t ix = 0; ix < p.grid[iy].size(); ++ix) rows.push_back({double(ix), double(iy), p.grid[iy][ix]});
  writeDataFile(ctx.data(p.dstem), {"ix", "iy", "value"}, rows);
  const std::string text = "(abs($3) < 0.05 ? '0.0' : sprintf('%.1f', $3))";
  // Dark cells: |value| beyond 60 % of the scale (diverging), the darkest 40 % (sequential).
  const std::string dark =
      p.diverging ? "(abs($3) > " + fmt("%.6g", 0.6 * p.cbhi) + ")"
      : p.negative ? "($3 < " + fmt("%.6g", p.cbhi - 0.6 * (p.cbhi - p.cblo)) + ")"
                   : "($3 > " + fmt("%.6g", p.cblo + 0.6 * (p.cbhi - p.cblo)) + ")";
  std::ostringstream b;
  b << "set title " << gpTitle(p.title, lay.panel_w - 120) << "\n"
    << "set xlabel " << gpQuote(gpAxisLabel(ax.key)) << "\nset ylabel " << gpQuote(gpAxisLabel(ay.key)) << "\n"
    << "set xrange [-0.5:" << ax.values.size() - 0.5 << "]\nset yrange [-0.5:" << ay.values.size() - 0.5 << "]\n"
    << indexTics(ax, "x", lay.xtic_every) << "\n" << indexTics(ay, "y", lay.ytic_every) << "\n"
    << range("cb", p.cblo, p.cbhi) << "set cblabel " << gpQuote(p.cblabel)
    << " offset char 2.5,0\nset rmargin 16\nset cbtics format '%g'\n"
    << (p.diverging ? divergingPalette() : sequentialPalette(p.negative));
  if (lay.values_in_cells)
    b << "plot " << gpFileName(p.dstem + ".dat")
      << " using 1:2:(0.5):(0.5):3 with boxxyerror fs solid 1.0 noborder fc palette notitle, \\\n"
      << "     '' using 1:2:(" << dark << " ? '' : " << text << ") with labels font 'Sans,15' tc rgb 'black' notitle, \\\n"
      << "     '' using 1:2:(" << dark << " ? " << text << " : '') with labels font 'Sans,15' tc rgb 'white' notitle\n";
  else  // one pixel block per cell (the rows are a full grid, ix fastest); NaN cells stay empty
    b << "set xtics rotate by -45\nplot " << gpFileName(p.dstem + ".dat") << " using 1:2:3 with image pixels notitle\n";
  return b.str();
}

// values[model][iy][ix]; x = axes[1], y = axes[0]. The models share one colour scale: sequential
// (white to dark) when every value has one sign, dark at the largest magnitude; diverging centred on
// zero only when the values have both signs. with_difference and two or more models: one panel per
// model after the first, that model minus the first, on one diverging scale of their own centred on
// zero. Cell text is white on dark cells; a value that rounds to zero prints unsigned.
void heatMap(Ctx& ctx, const std::string& stem, const Txt& what, const std::string& cblabel, const SweepAxis& ax,
             const SweepAxis& ay, const ModelGrids& values, const std::string& caption_more, bool with_difference) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& [m, grid] : values)
    for (const auto& row : grid)
      for (double v : row)
        if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  if (!std::isfinite(lo)) return;
  std::vector<HeatPanel> panels;
  for (const auto& [m, grid] : values) {
    HeatPanel p{stem + "_" + m, gpPanelTitle(m, {ax, ay}), cblabel, grid};
    setColourScale(p, lo, hi, false);
    panels.push_back(p);
  }
  const std::string diff_caption =
      with_difference && values.size() >= 2 ? addDifferencePanels(panels, stem, cblabel, values) : std::string();
  const HeatMapLayout lay = heatMapLayout(ax.values.size(), ay.values.size());
  // Up to three panels in a row (a column when the maps are wider than tall); more in two columns:
  // with differences, each model in the left column and its difference from the first model
  // beside it (the first model's right cell empty).
  const int n = static_cast<int>(panels.size());
  const bool stacked = ax.values.size() > ay.values.size() && n > 1;
  const int cols = n > 3 ? 2 : stacked ? 1 : n;
  std::vector<const HeatPanel*> cells;  // in gnuplot's order (rows first); nullptr: an empty cell
  const size_t nm = values.size();
  if (n > 3 && !diff_caption.empty()) {
    cells = {&panels[0], nullptr};
    for (size_t k = 1; k < nm; ++k) cells.push_back(&panels[k]), cells.push_back(&panels[nm + k - 1]);
  } else {
    for (const HeatPanel& p : panels) cells.push_back(&p);
  }
  const int rows = (static_cast<int>(cells.size()) + cols - 1) / cols;
  const int w = lay.panel_w * cols, h = lay.panel_h * rows + 40;
  const Txt title = ctx.title(what + ctx.tail);
  std::ostringstream b;
  b << multiplotHead(ctx, title, w, rows, cols);
  for (const HeatPanel* cell : cells) b << (cell ? heatPanelPlot(ctx, *cell, ax, ay, lay) : "set multiplot next\n");
  b << "unset multiplot\n";
  std::string cap = title.plain + ". " + caption_more;
  if (!lay.values_in_cells)
    cap += " (" + std::to_string(ax.values.size()) + " × " + std::to_string(ay.values.size()) +
           " cells: too many to print the values, they are in the .dat files).";
  cap += " One panel per model, one colour scale";
  cap += panels.front().diverging ? " (diverging, centred on zero: the values have both signs; blue negative, vermillion positive)."
         : panels.front().negative ? " (sequential: every value is negative, darker is more negative)."
                                   : " (sequential: every value has one sign, darker is larger).";
  cap += diff_caption;
  ctx.render(stem, b.str(), title, cap, w, h);
}

// ---- simulate, sweeps -----------------------------------------------------------------------

// phi(t) of a and b within tol of each other at 200 times over [0, t_end] (linear interpolation,
// each series held at its last value after it ends).
bool curvesCoincide(const TimeSeries& a, const TimeSeries& b, double t_end, double tol) {
  auto at = [](const TimeSeries& s, double t) {
    const auto& ts = s.values(col::kT);
    const auto& ph = s.values(col::kPhi);
    if (ts.empty()) return kNaN;
    const size_t k = std::upper_bound(ts.begin(), ts.end(), t) - ts.begin();
    if (k == 0) return ph.front();
    if (k == ts.size()) return ph.back();
    const double w = (t - ts[k - 1]) / (ts[k] - ts[k - 1]);
    return ph[k - 1] + w * (ph[k] - ph[k - 1]);
  };
  for (int i = 0; i <= 200; ++i) {
    const double t = t_end * i / 200.0;
    const double d = std::fabs(at(a, t) - at(b, t));
    if (!(d <= tol)) return false;
  }
  return true;
}

// Stage 1 of plotOneKey: phi_net over the key, one colour per model; bars for the number of links
// or a categorical key, else lines.
void plotPhiNetOverKey(Ctx& ctx) {
  const ExperimentResults& r = ctx.r;
  const SweepAxis& a = r.axes[0];
  const KeyDisplay kd = keyDisplay(a.key);
  const std::string stem = r.name + "_phi_net";
  std::vector<std::vector<double>> rows;
  for (size_t i = 0; i < a.values.size(); ++i) {
    std::vector<double> row = {a.numeric ? a.number(i) * kd.scale : double(i)};
    const CaseRecord* c = r.find({{a.key, a.values[i]}});
    for (const std::string& m : r.models) row.push_back(c ? r.phiNet(*c, m) : kNaN);
    rows.push_back(row);
  }
  std::vector<std::string> names = {leafKey(a.key)};
  for (const std::string& m : r.models) names.push_back(m + "_phi_net_deg");
  writeDataFile(ctx.data(stem), names, rows);

  const Txt title = ctx.title(W("net body rotation phi_net over ") + K(a.key) + ctx.tail);
  std::ostringstream b;
  // The legend right of the plot, never over the curves (phi_net is often largest at one end of the key).
  b << header(ctx, title, gpAxisLabel(a.key), "φ_{net} [deg]", 1300) << "set key outside right top vertical box\n";
  const bool bars = leafKey(a.key) == "links" || !a.numeric;
  if (bars) {
    b << "set style data histogram\nset style histogram cluster gap 1\nset style fill solid 0.85 border -1\n"
      << "set boxwidth 0.9\nset offsets 0, 0, graph 0.1, 0\nset xzeroaxis lt -1\nset grid noxtics\n"
      << indexTics(a) << "\nplot ";
    for (size_t j = 0; j < r.models.size(); ++j)
      b << (j ? ", " : "") << gpFileName(stem + ".dat") << " using " << j + 2 << " lc rgb "
        << gpQuote(modelColor(r.models[j])) << " title " << gpQuote(gpText(ctx.r.modelTitle(r.models[j])));
  } else {
    b << "set xzeroaxis lt -1\nplot ";
    for (size_t j = 0; j < r.models.size(); ++j)
      b << (j ? ", " : "") << gpFileName(stem + ".dat") << " using 1:" << j + 2
        << " with linespoints lw 2.5 pt " << seriesPoint(j) << " ps 1.3 lc rgb " << gpQuote(modelColor(r.models[j]))
        << " title " << gpQuote(gpText(ctx.r.modelTitle(r.models[j])));
  }
  b << "\n";
  ctx.render(stem, b.str(), title,
             title.plain + ". Net body rotation φ_net of each case" + (bars ? " (bars)" : "") + ", one colour per model.",
             1300, 700);
}

// phi(t) curves of one key's cases, one panel per model: each curve's data file, value index and
// series; the series, their stop times and each panel's phi values.
struct CurvePanels {
  struct Curve {
    std::string dat;
    size_t i;
    size_t series;  // index in `loaded`
  };
  std::vector<std::pair<std::string, std::vector<Curve>>> panels;
  std::vector<TimeSeries> loaded;
  std::vector<double> stops;
  std::vector<std::vector<double>> phis;  // per panel
};

// Stage 2 of plotOneKey: every case's readable phi(t) per model, each written as a data file.
CurvePanels loadCurvePanels(const Ctx& ctx) {
  const ExperimentResults& r = ctx.r;
  const SweepAxis& a = r.axes[0];
  CurvePanels cp;
  cp.loaded.reserve(r.cases.size() * r.models.size());
  for (const std::string& m : r.models) {
    std::vector<CurvePanels::Curve> curves;
    std::vector<double> mine;
    for (size_t i = 0; i < a.values.size(); ++i) {
      const CaseRecord* c = r.find({{a.key, a.values[i]}});
      if (!c) continue;
      TimeSeries s;
      try {
        s = r.series(*c, m);
      } catch (const std::exception&) {
        continue;
      }
      if (!s.has(col::kT) || !s.has(col::kPhi)) continue;
      const std::string dstem = r.name + "_phi_t_" + m + "_" + std::to_string(i);
      writePhiData(ctx, dstem, s);
      for (double v : s.values(col::kPhi)) mine.push_back(v);
      if (auto it = c->runs.find(m); it != c->runs.end() && it->second.ok) cp.stops.push_back(it->second.t_stop_s);
      cp.loaded.push_back(std::move(s));
      curves.push_back({dstem + ".dat", i, cp.loaded.size() - 1});
    }
    if (!curves.empty()) cp.panels.emplace_back(m, curves), cp.phis.push_back(mine);
  }
  return cp;
}

// Stage 3 of plotOneKey: phi(t) of every case, one panel per model, one time and one angle scale.
void plotPhiOfTimePerValue(Ctx& ctx) {
  const ExperimentResults& r = ctx.r;
  const SweepAxis& a = r.axes[0];
  const CurvePanels cp = loadCurvePanels(ctx);
  if (cp.panels.empty()) return;
  std::vector<const TimeSeries*> all;
  for (const TimeSeries& s : cp.loaded) all.push_back(&s);
  const double t_end = timeAxisEnd(all, cp.stops);
  const auto [yr, shared] = panelRanges(cp.phis, 0.06);
  const Txt ttitle = ctx.title(W("body yaw phi(t) for each ") + K(a.key) + ctx.tail);
  bool any_dashed = false;
  std::ostringstream t;
  t << multiplotHead(ctx, ttitle, 1150, cp.panels.size()) << range("x", 0, t_end);
  for (size_t p = 0; p < cp.panels.size(); ++p) {
    const auto& [m, curves] = cp.panels[p];
    t << yRangeOrAuto(yr[p]);
    t << "set grid\nset key outside right box\nset title " << gpTitle(gpPanelTitle(m, {a}), 900)
      << "\nset xlabel 't [s]'\nset ylabel 'φ [deg]'\nplot ";
    // A curve that lies on an earlier one (within 1 % of the panel's range) is drawn dashed, so the
    // earlier one shows between its dashes.
    const double tol = 0.01 * (std::isfinite(yr[p].first) ? yr[p].second - yr[p].first : 1.0);
    for (size_t n = 0; n < curves.size(); ++n) {
      bool on_earlier = false;
      for (size_t e = 0; e < n && !on_earlier; ++e)
        on_earlier = curvesCoincide(cp.loaded[curves[e].series], cp.loaded[curves[n].series], t_end, tol);
      t << (n ? ", \\\n     " : "") << gpFileName(curves[n].dat) << " using 1:2 with lines lw 2 dt "
        << (on_earlier ? "(12,9)" : std::to_string(seriesDash(curves[n].i))) << " lc rgb "
        << gpQuote(seriesColor(curves[n].i)) << " title " << gpQuote(V(a.key, a.values[curves[n].i]).gp);
      if (on_earlier) any_dashed = true;
    }
    t << "\n";
  }
  t << "unset multiplot\n";
  ctx.render(r.name + "_phi_t", t.str(), ttitle,
             ttitle.plain + ". Body yaw over time, one curve per value of " + K(a.key).plain +
                 ", one panel per model, one time scale; " +
                 (shared ? std::string("one angle scale.")
                         : std::string("each panel its own angle scale (the models' ranges differ more than threefold).")) +
                 (any_dashed ? " A dashed curve lies on an earlier one of the legend (drawn under it)." : ""),
             1150, 60 + 430 * static_cast<int>(cp.panels.size()));
}

void plotOneKey(Ctx& ctx) {
  plotPhiNetOverKey(ctx);
  if (ctx.r.cases.size() <= 12) plotPhiOfTimePerValue(ctx);  // few cases only
}

// The cluster key of plotGroupedBars: read by every model first, then categorical, then the first.
size_t clusterAxis(const ExperimentResults& r) {
  auto readByAll = [&](const SweepAxis& a) {
    for (const std::string& m : r.models)
      if (!modelReads(m, a.key)) return false;
    return true;
  };
  size_t ic = 0;
  int best = -1;
  for (size_t i = 0; i < 2; ++i) {
    const int score = (readByAll(r.axes[i]) ? 2 : 0) + (r.axes[i].numeric ? 0 : 1);
    if (score > best) best = score, ic = i;
  }
  return ic;
}

// One bar of each group: a model and a value of the bar key.
struct BarSeries {
  std::string model;
  int ib;  // value of the bar key, -1: the model does not read it (its first case per cluster)
};

// The bars of each group: per model, one per value of ab, or one when the model does not read ab.
std::vector<BarSeries> barSeries(const ExperimentResults& r, const SweepAxis& ab) {
  std::vector<BarSeries> series;
  for (const std::string& m : r.models) {
    if (!modelReads(m, ab.key)) series.push_back({m, -1});
    else
      for (size_t j = 0; j < ab.values.size(); ++j) series.push_back({m, static_cast<int>(j)});
  }
  return series;
}

// Stage of plotGroupedBars: one row per cluster value, its index and each bar's phi_net.
std::vector<std::vector<double>> barRows(const ExperimentResults& r, const SweepAxis& ac, const SweepAxis& ab,
                                         const std::vector<BarSeries>& series) {
  const auto cells = caseGrid(r, ac, ab);  // [cluster value][bar value]
  std::vector<std::vector<double>> rows;
  for (size_t i = 0; i < ac.values.size(); ++i) {
    std::vector<double> row = {double(i)};
    for (const BarSeries& sr : series) {
      const CaseRecord* c = nullptr;
      if (sr.ib >= 0) c = cells[i][sr.ib];
      else
        for (size_t j = 0; j < ab.values.size() && !c; ++j) c = cells[i][j];
      row.push_back(c ? r.phiNet(*c, sr.model) : kNaN);
    }
    rows.push_back(row);
  }
  return rows;
}

// Stage of plotGroupedBars: the bars (colour = model, fill = value of ab) and each bar's value
// above it (below a negative bar), `pad` from its end.
std::string barPlot(const std::string& dat, const SweepAxis& ab, const std::vector<BarSeries>& series, double pad) {
  std::ostringstream b;
  // shades of the other key's values: solid, light, hatched two ways, then open
  static const char* const fills[] = {"fs solid 1.0 border -1", "fs solid 0.4 border -1", "fs pattern 4 border -1",
                                      "fs pattern 5 border -1", "fs empty border -1"};
  for (size_t k = 0; k < series.size(); ++k) {
    const BarSeries& sr = series[k];
    std::string t = gpText(modelShortTitle(sr.model));
    if (sr.ib >= 0) t += ", " + gpValueLabel(ab.key, ab.values[sr.ib]);
    else t += " (" + keyDisplay(ab.key).symbol + " not used)";
    b << (k ? ", \\\n     " : "") << dat << " using " << k + 2 << " "
      << fills[sr.ib < 0 ? 0 : sr.ib % 5] << " lc rgb " << gpQuote(modelColor(sr.model)) << " title " << gpQuote(t);
  }
  // Bar k of a cluster of nb (gap 1) is centred at cluster + (k + 0.5 - nb / 2) / (nb + 1).
  const size_t nb = series.size();
  for (size_t k = 0; k < nb; ++k)
    b << ", \\\n     " << dat << " using ($1 + " << fmt("%.6g", (k + 0.5 - 0.5 * nb) / (nb + 1.0))
      << "):($" << k + 2 << " + ($" << k + 2 << " < 0 ? -1 : 1) * " << fmt("%.6g", 0.35 * pad) << "):(sprintf('%.2f', $"
      << k + 2 << ")) with labels font 'Sans,12' notitle";
  return b.str();
}

// Two swept keys of which one or both are categorical (friction law, coupling, foot shape):
// grouped bars. One group per value of the cluster key (a key every model reads, categorical
// first), in each group one bar per model and value of the other key; a model that does not read
// the other key ("analytic.coupling" for MuJoCo) has one bar per group, not copies. Colour = model;
// the other key's values are fill shades (solid, light, hatched, ...), named in the legend.
void plotGroupedBars(Ctx& ctx) {
  const ExperimentResults& r = ctx.r;
  const size_t ic = clusterAxis(r);
  const SweepAxis& ac = r.axes[ic];
  const SweepAxis& ab = r.axes[1 - ic];
  const std::vector<BarSeries> series = barSeries(r, ab);
  const std::string stem = r.name + "_phi_net_bars";
  const std::vector<std::vector<double>> rows = barRows(r, ac, ab, series);
  std::vector<std::string> names = {leafKey(ac.key)};
  for (const BarSeries& sr : series)
    names.push_back(sr.model + (sr.ib >= 0 ? "_" + leafKey(ab.key) + "=" + ab.values[sr.ib] : std::string()));
  writeDataFile(ctx.data(stem), names, rows);

  const Txt title = ctx.title(W("net body rotation phi_net over ") + K(ac.key) + W(" and ") + K(ab.key) + ctx.tail);
  const int w = std::max(1000, 260 + static_cast<int>(ac.values.size() * (series.size() + 1)) * 70);
  // Bars start at zero: the y range holds zero and every value, with room for the value labels.
  double lo = 0, hi = 0;
  for (const auto& row : rows)
    for (size_t k = 1; k < row.size(); ++k)
      if (std::isfinite(row[k])) lo = std::min(lo, row[k]), hi = std::max(hi, row[k]);
  const double pad = 0.12 * std::max(hi - lo, 1e-3);
  std::ostringstream b;
  b << header(ctx, title, gpAxisLabel(ac.key), "φ_{net} [deg]", w)
    << "set style data histogram\nset style histogram cluster gap 1\nset boxwidth 0.9\n"
    << range("y", lo < 0 ? lo - pad : 0.0, hi > 0 ? hi + pad : 0.0)
    << "set xrange [-0.6:" << ac.values.size() - 0.4 << "]\n"
    << "set xzeroaxis lt -1\nset grid noxtics\nset key outside right top box\n"
    << indexTics(ac) << "\nplot " << barPlot(gpFileName(stem + ".dat"), ab, series, pad) << "\n";
  std::string cap = title.plain + ". φ_net of each case as bars, grouped by " + K(ac.key).plain +
                    "; colour = model, fill = " + K(ab.key).plain + " (solid, light, hatched, in the legend's order).";
  for (const std::string& m : r.models)
    if (!modelReads(m, ab.key))
      cap += " " + modelShortTitle(m) + " does not read " + K(ab.key).plain + ": one bar per group.";
  ctx.render(stem, b.str(), title, cap, w + 360, 700);
}

void plotTwoKeys(Ctx& ctx) {
  const ExperimentResults& r = ctx.r;
  if (!r.axes[0].numeric || !r.axes[1].numeric) {
    plotGroupedBars(ctx);
    return;
  }
  const SweepAxis& ay = r.axes[0];  // slowest-varying key (first in the file)
  const SweepAxis& ax = r.axes[1];
  ModelGrids grids;
  const auto cells = caseGrid(r, ay, ax);
  for (const std::string& m : r.models) {
    std::vector<std::vector<double>> g(ay.values.size(), std::vector<double>(ax.values.size(), kNaN));
    for (size_t iy = 0; iy < ay.values.size(); ++iy)
      for (size_t ix = 0; ix < ax.values.size(); ++ix)
        if (const CaseRecord* c = cells[iy][ix]) g[iy][ix] = r.phiNet(*c, m);
    grids.emplace_back(m, g);
  }
  heatMap(ctx, r.name + "_phi_net_map", W("net body rotation phi_net over ") + K(ax.key) + W(" and ") + K(ay.key),
          "φ_{net} [deg]", ax, ay, grids, "Cells: φ_net in degrees for each case.", true);

  // Curves over the x key, one per y value, one panel per model; one y scale unless the models'
  // ranges differ more than threefold (panelRanges).
  const KeyDisplay kx = keyDisplay(ax.key);
  std::vector<std::vector<double>> per_model;
  for (const auto& [m, g] : grids) {
    per_model.emplace_back();
    for (const auto& row : g) per_model.back().insert(per_model.back().end(), row.begin(), row.end());
  }
  const auto [yr, shared] = panelRanges(per_model, 0.08);
  const Txt title = ctx.title(W("phi_net over ") + K(ax.key) + W(", one curve per ") + K(ay.key) + ctx.tail);
  std::ostringstream b;
  // One panel per model, stacked: the figure keeps the width of figures.html's column, so its text
  // stays legible there (figures.html shows images at most 1100 px wide).
  const int panel_w = 1150, fig_w = panel_w, fig_h = 60 + 430 * static_cast<int>(grids.size());
  b << multiplotHead(ctx, title, fig_w, grids.size());
  if (!ax.numeric) b << categoricalXAxis(ax);
  for (size_t p = 0; p < grids.size(); ++p) {
    const auto& [m, g] = grids[p];
    b << yRangeOrAuto(yr[p]);
    const std::string dstem = r.name + "_phi_net_lines_" + m;
    std::vector<std::vector<double>> rows;
    for (size_t ix = 0; ix < ax.values.size(); ++ix) {
      std::vector<double> row = {ax.numeric ? ax.number(ix) * kx.scale : double(ix)};
      for (size_t iy = 0; iy < ay.values.size(); ++iy) row.push_back(g[iy][ix]);
      rows.push_back(row);
    }
    std::vector<std::string> names = {leafKey(ax.key)};
    for (const std::string& v : ay.values) names.push_back(leafKey(ay.key) + "=" + v);
    writeDataFile(ctx.data(dstem), names, rows);
    b << "set grid\nset key outside right box\nset title " << gpTitle(gpPanelTitle(m, {ax, ay}), panel_w - 250) << "\n"
      << "set xlabel " << gpQuote(gpAxisLabel(ax.key)) << "\nset ylabel 'φ_{net} [deg]'\nplot ";
    for (size_t iy = 0; iy < ay.values.size(); ++iy)
      b << (iy ? ", \\\n     " : "") << gpFileName(dstem + ".dat") << " using 1:" << iy + 2
        << " with linespoints lw 2 pt " << seriesPoint(iy) << " ps 1.3 dt " << seriesDash(iy) << " lc rgb " << gpQuote(seriesColor(iy)) << " title " << gpQuote(V(ay.key, ay.values[iy]).gp);
    b << "\n";
  }
  b << "unset multiplot\n";
  ctx.render(r.name + "_phi_net_lines", b.str(), title,
             title.plain + ". φ_net over " + K(ax.key).plain + ", one curve per value of " + K(ay.key).plain +
                 ", one panel per model, " +
                 (shared ? std::string("same y scale.")
                         : std::string("each panel its own y scale (the models' ranges differ more than threefold).")),
             fig_w, fig_h);
}

// The cases by their values of every axis, in axes order ("" for a key a case does not set).
std::map<std::vector<std::string>, const CaseRecord*> caseIndex(const ExperimentResults& r) {
  std::map<std::vector<std::string>, const CaseRecord*> index;
  for (const CaseRecord& c : r.cases) {
    std::vector<std::string> k;
    for (const SweepAxis& a : r.axes) {
      const auto it = c.sweep.find(a.key);
      k.push_back(it == c.sweep.end() ? std::string() : it->second);
    }
    index.emplace(k, &c);
  }
  return index;
}

// Every combination of the facet keys' values (indices), the last facet key fastest.
std::vector<std::vector<size_t>> facetCombos(const ExperimentResults& r, const FacetKeys& fk) {
  std::vector<std::vector<size_t>> combos(1);
  for (size_t f : fk.facets) {
    std::vector<std::vector<size_t>> next;
    for (const auto& c : combos)
      for (size_t i = 0; i < r.axes[f].values.size(); ++i) {
        next.push_back(c);
        next.back().push_back(i);
      }
    combos = std::move(next);
  }
  return combos;
}

// The small multiples' grid: rows and columns of panels, their size and the figure's.
struct FacetGrid {
  size_t cols = 1, rows = 1;
  int panel_w = 0, panel_h = 0, legend_w = 260, fig_w = 0, fig_h = 0;
};

// Rows and columns are the two facet keys when there are two, else a near-square grid; panels
// shrink with their number, the whole figure within about 3000 x 2400 px.
FacetGrid facetGrid(const ExperimentResults& r, const FacetKeys& fk, size_t np) {
  FacetGrid g;
  if (fk.facets.size() == 2) {
    g.rows = r.axes[fk.facets[0]].values.size();
    g.cols = r.axes[fk.facets[1]].values.size();
  } else {
    g.cols = static_cast<size_t>(std::ceil(std::sqrt(static_cast<double>(np))));
    g.rows = (np + g.cols - 1) / g.cols;
  }
  g.panel_w = std::clamp(3000 / static_cast<int>(g.cols), 380, 620);
  g.panel_h = std::clamp(2400 / static_cast<int>(g.rows), 300, 440);
  g.fig_w = g.panel_w * static_cast<int>(g.cols) + g.legend_w, g.fig_h = g.panel_h * static_cast<int>(g.rows) + 90;
  return g;
}

// Stage of plotManyKeys: model m's data file of each panel (phi_net over the x key, a column per
// series value); the finite values go to `all`. Returns the files' names.
std::vector<std::string> writeFacetData(const Ctx& ctx, const std::string& m, const FacetKeys& fk,
                                        const std::map<std::vector<std::string>, const CaseRecord*>& index,
                                        const std::vector<std::vector<size_t>>& combos, std::vector<double>& all) {
  const ExperimentResults& r = ctx.r;
  const SweepAxis& ax = r.axes[fk.x];
  const SweepAxis& as = r.axes[fk.series];
  const KeyDisplay kx = keyDisplay(ax.key);
  std::vector<std::string> dats;
  for (size_t p = 0; p < combos.size(); ++p) {
    std::vector<std::vector<double>> rowsd;
    for (size_t ix = 0; ix < ax.values.size(); ++ix) {
      std::vector<double> row = {ax.numeric ? ax.number(ix) * kx.scale : double(ix)};
      for (size_t is = 0; is < as.values.size(); ++is) {
        std::vector<std::string> k(r.axes.size());
        k[fk.x] = ax.values[ix];
        k[fk.series] = as.values[is];
        for (size_t f = 0; f < fk.facets.size(); ++f) k[fk.facets[f]] = r.axes[fk.facets[f]].values[combos[p][f]];
        const auto it = index.find(k);
        const double v = it == index.end() ? kNaN : r.phiNet(*it->second, m);
        row.push_back(v);
        if (std::isfinite(v)) all.push_back(v);
      }
      rowsd.push_back(row);
    }
    const std::string dstem = r.name + "_phi_net_facets_" + m + "_" + std::to_string(p);
    std::vector<std::string> names = {leafKey(ax.key)};
    for (const std::string& v : as.values) names.push_back(leafKey(as.key) + "=" + v);
    writeDataFile(ctx.data(dstem), names, rowsd);
    dats.push_back(dstem + ".dat");
  }
  return dats;
}

// Stage of plotManyKeys: the figure's title, with the keys model m does not read
// ("mujoco.foot_shape" for the analytic model).
Txt facetTitle(const Ctx& ctx, const std::string& m, const FacetKeys& fk, const std::string& facet_words) {
  const ExperimentResults& r = ctx.r;
  std::string unused;
  for (const SweepAxis& a : r.axes)
    if (!modelReads(m, a.key)) unused += (unused.empty() ? "" : ", ") + keyDisplay(a.key).plain;
  Txt who{gpText(ctx.r.modelTitle(m)), ctx.r.modelTitle(m)};
  if (!unused.empty()) who = who + Txt{gpText(" (" + unused + " not used)"), " (" + unused + " not used)"};
  return ctx.title(W("phi_net over ") + K(r.axes[fk.x].key) + W(", one curve per ") + K(r.axes[fk.series].key) +
                   Txt{", one panel per " + gpText(facet_words), ", one panel per " + facet_words} + ctx.tail +
                   W(": ") + who);
}

// Stage of plotManyKeys: panel p at its place in the grid, titled with its facet values, one curve
// per series value; the first panel carries the legend beside the top-right panel.
std::string facetPanel(const ExperimentResults& r, const FacetKeys& fk, const FacetGrid& g, size_t p,
                       const std::vector<size_t>& combo, const std::string& dat, double right, double top) {
  const SweepAxis& as = r.axes[fk.series];
  std::ostringstream b;
  const size_t row = p / g.cols, col = p % g.cols;
  const double w = right / g.cols, h = top / g.rows;
  std::string ptitle;
  for (size_t f = 0; f < fk.facets.size(); ++f) {
    const SweepAxis& fa = r.axes[fk.facets[f]];
    ptitle += (f ? ", " : "") + gpValueLabel(fa.key, fa.values[combo[f]]);
  }
  b << "set origin " << fmt("%.5f", col * w) << "," << fmt("%.5f", top - (row + 1) * h) << "\nset size "
    << fmt("%.5f", w) << "," << fmt("%.5f", h) << "\nset title " << gpQuote(ptitle) << "\n";
  if (p == 0) {
    b << "set key at screen " << fmt("%.5f", right + 0.01) << ", screen " << fmt("%.5f", top)
      << " left top box opaque title " << gpQuote(keyDisplay(as.key).symbol) << "\n";
  } else if (p == 1) {
    b << "unset key\n";
  }
  b << "plot ";
  for (size_t is = 0; is < as.values.size(); ++is)
    b << (is ? ", \\\n     " : "") << gpFileName(dat) << " using 1:" << is + 2 << " with linespoints lw 2 pt "
      << seriesPoint(is) << " ps 1.1 dt " << seriesDash(is) << " lc rgb " << gpQuote(seriesColor(is))
      << " title " << gpQuote(gpValueLabel(as.key, as.values[is], false));
  b << "\n";
  return b.str();
}

// Small multiples for 3 or more swept keys (facetKeys): one figure per model, one panel per
// combination of the facet keys' values (a grid: rows and columns are the two facet keys when
// there are two), in each panel phi_net over the x key with one curve per value of the series key.
// Every panel of a figure has the same axes, so panels compare by eye.
void plotManyKeys(Ctx& ctx) {
  const ExperimentResults& r = ctx.r;
  const FacetKeys fk = facetKeys(r.axes);
  const SweepAxis& ax = r.axes[fk.x];
  const SweepAxis& as = r.axes[fk.series];
  const KeyDisplay kx = keyDisplay(ax.key);
  const auto index = caseIndex(r);
  const std::vector<std::vector<size_t>> combos = facetCombos(r, fk);
  const FacetGrid g = facetGrid(r, fk, combos.size());
  std::string facet_words;
  for (size_t f = 0; f < fk.facets.size(); ++f)
    facet_words += std::string(f ? " and " : "") + keyDisplay(r.axes[fk.facets[f]].key).plain;

  for (const std::string& m : r.models) {
    std::vector<double> all;
    const std::vector<std::string> dats = writeFacetData(ctx, m, fk, index, combos, all);
    if (all.empty()) continue;
    const auto [ylo, yhi] = span(all, 0.08);
    const Txt title = facetTitle(ctx, m, fk, facet_words);
    std::ostringstream b;
    // Panels leave room on the right for one legend beside the top-right panel.
    const double right = 1.0 - static_cast<double>(g.legend_w) / g.fig_w;
    const double top = 1.0 - 70.0 / g.fig_h;
    b << "reset\nset multiplot title " << ctx.figTitle(title, g.fig_w, 17) << " font 'Sans,17'\n"
      << (std::isfinite(ylo) ? range("y", ylo, yhi) : std::string()) << "set grid\nset xzeroaxis lt -1\n"
      << "set xlabel " << gpQuote(gpAxisLabel(ax.key)) << "\nset ylabel 'φ_{net} [deg]'\n";
    if (!ax.numeric) {
      b << categoricalXAxis(ax);
    } else {  // the swept values and a 3 % margin, not gnuplot's rounded tics
      std::vector<double> xs;
      for (size_t i = 0; i < ax.values.size(); ++i) xs.push_back(ax.number(i) * kx.scale);
      const auto [xlo, xhi] = span(xs, 0.03);
      if (std::isfinite(xlo)) b << range("x", xlo, xhi);
    }
    for (size_t p = 0; p < combos.size(); ++p) b << facetPanel(r, fk, g, p, combos[p], dats[p], right, top);
    b << "unset multiplot\n";
    ctx.render(r.name + "_phi_net_facets_" + m, b.str(), title,
               title.plain + ". φ_net of " + ctx.r.modelTitle(m) + " over " + K(ax.key).plain + ", one curve per value of " +
                   K(as.key).plain + ", one panel per value of " + facet_words +
                   "; every panel has the same axes. A missing point is a case that was not run or failed.",
               g.fig_w, g.fig_h);
  }
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
  const KeyDisplay kd = keyDisplay(a.key);
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
  struct Part {
    std::string col, gp, plain;
  };
  std::vector<Part> parts;
  if (probe.has(col::kMzTTan) && probe.has(col::kMzTCen))
    parts = {{"MzT_tan_Nm", "(a) tangential M_{z,T,tan} / I_{zz}", "tangential M_z,T,tan / I_zz"},
             {"MzT_cen_Nm", "(b) centripetal M_{z,T,cen} / I_{zz}", "centripetal M_z,T,cen / I_zz"}};
  else if (probe.has(col::kMzTAcc) && probe.has(col::kMzTSpeed))
    parts = {{"MzT_acc_Nm", "(a) acceleration-driven M_{z,T,acc} / I_{zz}", "acceleration-driven M_z,T,acc / I_zz"},
             {"MzT_speed_Nm", "(b) speed-driven M_{z,T,speed} / I_{zz}", "speed-driven M_z,T,speed / I_zz"}};
  const bool perIzz = probe.has(col::kIzz);
  const double xs = a.numeric ? kd.scale : 1.0;
  if (!parts.empty()) {
    const std::string stem = r.name + "_contributions";
    std::vector<std::vector<double>> rows;
    for (size_t i = 0; i < a.values.size(); ++i) {
      const CaseRecord* c = r.find({{a.key, a.values[i]}});
      const double izz = perIzz ? poseValue(r, c, model, col::kIzz) : 1.0;
      rows.push_back({a.number(i) * xs, poseValue(r, c, model, parts[0].col) / izz,
                      poseValue(r, c, model, parts[1].col) / izz});
    }
    writeDataFile(ctx.data(stem), {leafKey(a.key), parts[0].col, parts[1].col}, rows);
    const std::string ylabel = perIzz ? "contribution to φ̈ [rad/s^2]" : "moment [N m]";
    const Txt title = ctx.title(Txt{"tail moment contributions over ", "tail moment contributions over "} + K(a.key) + ctx.tail);
    std::ostringstream b;
    b << multiplotHead(ctx, title, 1600, 1, 2);
    for (int j = 0; j < 2; ++j)
      b << "set grid\nunset key\nset xzeroaxis lt -1\nset title " << gpTitle(parts[j].gp, 800) << "\nset xlabel "
        << gpQuote(gpAxisLabel(a.key)) << "\nset ylabel " << gpQuote(ylabel) << "\nplot " << gpFileName(stem + ".dat")
        << " using 1:" << j + 2 << " with linespoints lw 2.5 pt 7 lc rgb " << gpQuote(modelColor(model)) << "\n";
    b << "unset multiplot\n";
    ctx.render(stem, b.str(), title,
               title.plain + ": (a) " + parts[0].plain + " and (b) " + parts[1].plain + " over " + kd.plain + " (" +
                   ctx.r.modelTitle(model) + ").",
               1600, 690);
  }
  if (probe.has(col::kLF)) {
    const std::string stem = r.name + "_LF";
    std::vector<std::vector<double>> rows;
    for (size_t i = 0; i < a.values.size(); ++i)
      rows.push_back({a.number(i) * xs, 1e3 * poseValue(r, r.find({{a.key, a.values[i]}}), model, col::kLF)});
    writeDataFile(ctx.data(stem), {leafKey(a.key), "LF_mm"}, rows);
    const Txt title = ctx.title(W("friction moment arm L_F over ") + K(a.key) + ctx.tail);
    std::ostringstream b;
    b << header(ctx, title, gpAxisLabel(a.key), "L_F [mm]") << "unset key\nplot " << gpFileName(stem + ".dat")
      << " using 1:2 with linespoints lw 2.5 pt 7 lc rgb " << gpQuote(modelColor(model)) << "\n";
    ctx.render(stem, b.str(), title, title.plain + " (Eqs. 17-19, " + ctx.r.modelTitle(model) + ").");
  }
}

void plotPoseTwoKeys(Ctx& ctx) {
  const ExperimentResults& r = ctx.r;
  const SweepAxis& ay = r.axes[0];
  const SweepAxis& ax = r.axes[1];
  ModelGrids grids;
  const auto cells = caseGrid(r, ay, ax);
  for (const std::string& m : r.models) {
    std::vector<std::vector<double>> g(ay.values.size(), std::vector<double>(ax.values.size(), kNaN));
    bool any = false;
    for (size_t iy = 0; iy < ay.values.size(); ++iy)
      for (size_t ix = 0; ix < ax.values.size(); ++ix) {
        g[iy][ix] = 1e3 * poseValue(r, cells[iy][ix], m, col::kLF);
        any = any || std::isfinite(g[iy][ix]);
      }
    if (any) grids.emplace_back(m, g);
  }
  if (!grids.empty())
    heatMap(ctx, r.name + "_LF_map", W("friction moment arm L_F over ") + K(ax.key) + W(" and ") + K(ay.key),
            "L_F [mm]", ax, ay, grids, "Cells: L_F in millimetres (Eqs. 17-19).", false);
}

}  // namespace

std::vector<PlotFile> plotExperiment(const ExperimentResults& r, const PlotOptions& opt) {
  Ctx ctx{r, (fs::path(r.dir) / "plots").string(), {}, {}, {}, opt};
  const std::string name = figureName(r.description, r.name);
  ctx.fig = {gpFigureName(r.description, r.name), name};
  if (r.links > 0) {
    const std::string t = ", " + std::to_string(r.links) + "-link tail";
    // the figure name may say it already ("Fig. 6 1-link case")
    if (name.find(std::to_string(r.links) + "-link") == std::string::npos) ctx.tail = {t, t};
  }
  makeResultDir(ctx.plots);
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

std::vector<PlotFile> plotResults(const std::string& dir, const PlotOptions& opt) {
  std::vector<PlotFile> all;
  const std::vector<ExperimentResults> results = loadResultTree(dir);
  for (const ExperimentResults& r : results) {
    std::vector<PlotFile> p = plotExperiment(r, opt);
    all.insert(all.end(), p.begin(), p.end());
  }
  writeFigureSheet(dir, results, all);
  return all;
}

}  // namespace tailsim
