#include "common/number_text.h"
#include "plotting/trust_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <sstream>

#include "experiments/verdict.h"
#include "plotting/gnuplot.h"
#include "plotting/style.h"
#include "common/atomic_file.h"

namespace tailsim {

namespace fs = std::filesystem;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string fmt(const char* f, double x) { return std::isfinite(x) ? formatNumber(f, x) : "n/a"; }

double errOf(const TrustRow& r, const TrustRow* ref) {
  return ref && ref->ok && r.ok ? std::abs(r.phi_net_deg - ref->phi_net_deg) : kNaN;
}

}  // namespace

std::vector<std::string> trustOutputs() {
  return {"trust.md", "trust.csv", "plots/trust.png", "plots/trust.svg", "plots/trust.gp"};
}

namespace {

// trust.csv: one row a case and setting.
std::string trustCsv(const std::vector<TrustStudy>& studies) {
  std::ostringstream csv;
  csv << "case,group,setting,model,ok,phi_net_deg,uncertainty_deg,change_vs_default_deg,error_vs_reference_deg,"
         "wall_time_s,solver_steps,failure\n";
  auto q = [](const std::string& s) {
    std::string o = "\"";
    for (char ch : s) o += ch == '"' ? std::string("\"\"") : std::string(1, ch);
    return o + "\"";
  };
  for (const TrustStudy& st : studies) {
    const TrustRow* def = st.row("default");
    const TrustRow* ref = st.row("reference");
    for (const TrustRow& r : st.rows)
      csv << q(st.case_name) << ',' << r.group << ',' << q(r.setting) << ',' << r.model << ',' << (r.ok ? 1 : 0) << ','
          << fmt("%.9g", r.phi_net_deg) << ',' << fmt("%.6g", r.uncertainty_deg) << ','
          << fmt("%.6g", def && def->ok && r.ok ? r.phi_net_deg - def->phi_net_deg : kNaN) << ','
          << fmt("%.6g", errOf(r, ref)) << ',' << fmt("%.6g", r.wall_s) << ',' << r.steps << ',' << q(r.failure) << '\n';
  }
  return csv.str();
}

// A point's label on the figure.
struct Mark {
  double x, y;
  std::string text;
  bool left;  // the contact settings share one x (their step count): labelled on the left
};

// The figure's gnuplot labels: labels of points closer than about a label's height on one side of
// the same x join into one.
std::vector<std::string> trustLabels(std::vector<Mark> marks) {
  std::sort(marks.begin(), marks.end(), [](const Mark& a, const Mark& b) {
    return a.left != b.left ? a.left < b.left : a.x != b.x ? a.x < b.x : a.y < b.y;
  });
  std::vector<Mark> joined;
  for (const Mark& m : marks)
    if (!joined.empty() && joined.back().left == m.left && m.left == true && joined.back().x == m.x &&
        m.y < joined.back().y * 1.2)
      joined.back().text += "; " + m.text;
    else
      joined.push_back(m);
  std::vector<std::string> labels;
  for (const Mark& m : joined)
    labels.push_back("set label " + gpQuote(gpText(m.text)) + " at " + fmt("%.6g", m.x) + ", " + fmt("%.6g", m.y) +
                     (m.left ? " right offset -1, 0" : " offset 1, 0.6") + " font ',9'");
  return labels;
}

// The figure: error against the reference over the work (MuJoCo steps, the check run's included: a
// count, unlike the wall time on a shared machine), one point a setting and case. Returns the
// image file, or "" when there is nothing to plot.
std::string trustFigure(const std::vector<TrustStudy>& studies, const Experiment& e, const std::string& plots) {
  std::map<std::string, std::vector<std::vector<double>>> groups;
  std::vector<Mark> marks;
  for (const TrustStudy& st : studies) {
    const TrustRow* ref = st.row("reference");
    for (const TrustRow& r : st.rows) {
      if (!r.ok || r.group == "planar" || r.steps <= 0) continue;
      const double work = static_cast<double>(r.steps + r.check_steps);
      const double err = r.group == "reference" ? kNaN : errOf(r, ref);
      if (!std::isfinite(err)) continue;
      groups[r.group].push_back({work, std::max(err, 1e-4)});
      if (studies.size() == 1 && r.group != "jitter")  // the jitter points sit on the default's
        marks.push_back({work, std::max(err, 1e-4), r.group == "default" ? std::string("default") : r.setting,
                         r.group == "contact"});
    }
  }
  std::ostringstream body;
  body << "set logscale xy\nset grid\nset xlabel 'MuJoCo steps per run (its check run included; wall times in trust.md)'\n"
       << "set ylabel '|φ_{net} − reference| [deg]'\nset title "
       << gpTitle(gpText("What the MuJoCo answer depends on and what it costs: " + e.name +
                         (studies.size() == 1 ? ", case " + studies[0].case_name : "")),
                  1400)
       << "\nset rmargin at screen 0.72\nset key at screen 0.73, graph 1 left top Left reverse nobox samplen 2"
       << "\nset offsets graph 0.05, graph 0.35, graph 0.3, graph 0.3\n";
  for (const std::string& l : trustLabels(std::move(marks))) body << l << "\n";
  // The default run's own uncertainty, as a horizontal line (single case).
  std::vector<std::string> parts;
  int k = 0;
  for (const auto& [g, rows] : groups) {
    const std::string dat = "trust_" + std::to_string(k) + ".dat";
    writeDataFile((fs::path(plots) / dat).string(), {"steps", "err_deg"}, rows);
    parts.push_back(gpFileName(dat) + " using 1:2 with points pt " + std::to_string(5 + 2 * k) + " ps 2 lc rgb " +
                    gpQuote(categoricalColor(static_cast<size_t>(k))) + " title " + gpQuote(gpText(g)));
    ++k;
  }
  if (studies.size() == 1)
    if (const TrustRow* d = studies[0].row("default"); d && std::isfinite(d->uncertainty_deg))
      parts.push_back(fmt("%.9g", std::max(d->uncertainty_deg, 1e-4)) +
                      " with lines dt 2 lw 2 lc rgb 'gray40' title " +
                      gpQuote(gpText("default's own uncertainty")));
  if (parts.empty()) return "";
  body << "plot ";
  for (size_t i = 0; i < parts.size(); ++i) body << (i ? ", \\\n     " : "") << parts[i];
  body << "\n";
  GnuplotFigure fig;
  fig.stem = "trust";
  fig.body = body.str();
  fig.width_px = 1400;
  fig.height_px = 800;
  return renderFigure(plots, fig);
}

// One case's section of trust.md: the default against the reference, the table, what the answer
// depends on, the verdict.
void trustCaseMarkdown(const TrustStudy& st, std::ostream& o) {
  const TrustRow* def = st.row("default");
  const TrustRow* ref = st.row("reference");
  o << "## Case " << st.case_name << "\n\n";
  if (def && def->ok && ref && ref->ok) {
    const double err = std::abs(def->phi_net_deg - ref->phi_net_deg);
    o << "MuJoCo at the case's settings: phi_net " << fmt("%+.3f", def->phi_net_deg)
      << (std::isfinite(def->uncertainty_deg) ? " +- " + fmt("%.3f", def->uncertainty_deg)
                                              : std::string(" (uncertainty not estimated: its check run failed)"))
      << " deg (" << fmt("%.3g", 1e3 * def->wall_s)
      << " ms); the reference: " << fmt("%+.3f", ref->phi_net_deg) << " deg (" << fmt("%.3g", 1e3 * ref->wall_s)
      << " ms). The default is off by " << fmt("%.3f", err) << " deg ("
      << fmt("%.2f", 100.0 * err / std::max(std::abs(ref->phi_net_deg), kUncertaintyFloorDeg)) << " %), "
      << (!std::isfinite(def->uncertainty_deg) ? "and it has no uncertainty of its own to compare with."
          : err <= def->uncertainty_deg         ? "within its own uncertainty."
                                                : "more than its own uncertainty says.")
      << "\n\n";
  } else if (def && !def->ok) {
    o << "MuJoCo at the case's settings failed: " << def->failure << "\n\n";
  }
  o << "| group | setting | model | phi_net [deg] | change vs default [deg] | error vs reference [deg] | wall time "
       "[ms] | steps |\n|---|---|---|---:|---:|---:|---:|---:|\n";
  std::map<std::string, double> largest;  // per group: the largest |change vs default|
  for (const TrustRow& r : st.rows) {
    const double change = def && def->ok && r.ok ? r.phi_net_deg - def->phi_net_deg : kNaN;
    if (r.group != "default" && r.group != "planar" && r.group != "reference" && std::isfinite(change))
      largest[r.group] = std::max(largest[r.group], std::abs(change));
    o << "| " << r.group << " | " << r.setting << " | " << r.model << " | "
      << (r.ok ? fmt("%+.3f", r.phi_net_deg) : "failed: " + r.failure) << " | " << fmt("%+.3f", change) << " | "
      << fmt("%.3f", errOf(r, ref)) << " | " << fmt("%.3g", 1e3 * r.wall_s) << " | "
      << (r.check_steps > 0 ? std::to_string(r.steps) + " + " + std::to_string(r.check_steps) : std::to_string(r.steps))
      << " |\n";
  }
  o << "\nWhat the answer depends on (largest |change| against the default):";
  for (const auto& [g, v] : largest) o << " " << g << " " << fmt("%.3f", v) << " deg;";
  o << " the default's own uncertainty "
    << (def && std::isfinite(def->uncertainty_deg) ? fmt("%.3f", def->uncertainty_deg) + " deg"
                                                    : std::string("not estimated (its check run failed)"))
    << ".\n\n";
  if (!st.verdict.empty()) o << "Verdict across the models: " << st.verdict << "\n\n";
}

// trust.md; figure: the figure's image file, or "".
std::string trustMarkdown(const std::vector<TrustStudy>& studies, const Experiment& e, const std::string& figure) {
  std::ostringstream o;
  o << "# tailsim trust: " << e.name << "\n\n"
    << "Written by `tailsim trust` from `" << e.source_file << "`. Each case's MuJoCo run at its own settings "
       "(\"default\", with its own uncertainty phi_net_uncertainty_deg from a check run at twice the timestep), "
       "then once per variant: the timestep (servo w_n kept), the contact compliance (solref time constant, "
       "solimp width, impratio, noslip) and the stroke's dT (jitter). The reference is the case's settings at "
       "timestep / 8 with impratio >= 100 and noslip >= 3 (docs/mujoco-model.md \"Contact settings: the rule and "
       "its evidence\"). Wall time: one run on this machine. docs/accuracy.md \"tailsim trust\" explains the "
       "table.\n\n";
  for (const TrustStudy& st : studies) trustCaseMarkdown(st, o);
  if (!figure.empty())
    o << "![error against the reference over the MuJoCo steps](plots/" << fs::path(figure).filename().string() << ")\n";
  return o.str();
}

}  // namespace

std::vector<std::string> writeTrust(const std::vector<TrustStudy>& studies, const Experiment& e, const std::string& dir) {
  makeResultDir(dir);
  std::vector<std::string> files;
  writeOwnedFile(dir, "trust.csv", trustCsv(studies));
  files.push_back((fs::path(dir) / "trust.csv").string());
  const std::string plots = (fs::path(dir) / "plots").string();
  makeResultDir(plots);
  const std::string figure = trustFigure(studies, e, plots);
  if (!figure.empty()) files.push_back(figure);
  writeOwnedFile(dir, "trust.md", trustMarkdown(studies, e, figure));
  files.insert(files.begin(), (fs::path(dir) / "trust.md").string());
  return files;
}

}  // namespace tailsim
