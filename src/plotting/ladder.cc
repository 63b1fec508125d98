#include "plotting/ladder.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <stdexcept>

#include "experiments/model_registry.h"
#include "plotting/gnuplot.h"
#include "plotting/result_folder.h"
#include "plotting/style.h"
#include "common/atomic_file.h"
#include "common/number_text.h"

namespace tailsim {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The rungs, in ladder order (the last is MuJoCo with its default constant mu).
struct Rung {
  const char* key;
  const char* title;
  double LadderCase::*value;
};
const std::vector<Rung>& rungs() {
  static const std::vector<Rung> k = {
      {"paper", "paper model", &LadderCase::paper},
      {"exact", "exact coupling", &LadderCase::exact},
      {"perfoot_coulomb", "per-foot Coulomb", &LadderCase::perfoot_coulomb},
      {"perfoot_adams", "per-foot ADAMS law", &LadderCase::perfoot_adams},
      {"mujoco_adams", "MuJoCo (ADAMS law)", &LadderCase::mujoco_adams},
      {"mujoco_const", "MuJoCo (constant mu)", &LadderCase::mujoco_const},
  };
  return k;
}
// The five steps between consecutive rungs.
const std::vector<std::string>& stepNames() {
  static const std::vector<std::string> k = {"coupling", "per-foot friction", "friction law (per foot)",
                                             "contact model (ADAMS law)", "MuJoCo law: ADAMS -> constant mu"};
  return k;
}

std::string fmt(const char* f, double x) {
  if (!std::isfinite(x)) return "n/a";
  return formatNumber(f, x);
}

double median(std::vector<double> v) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}
double maxOf(const std::vector<double>& v) {
  double m = kNaN;
  for (double x : v)
    if (std::isfinite(x) && !(x <= m)) m = x;
  return m;
}
// |a - b| in % of |b| (b: the reference, MuJoCo).
double relPct(double a, double b) { return 100.0 * std::abs(a - b) / std::abs(b); }

// The ladder experiment's cases grouped by the figure case (all other swept keys).
void addExperiment(const ExperimentResults& r, std::vector<LadderCase>& out) {
  bool has_coupling = false, has_friction = false;
  for (const SweepAxis& a : r.axes) {
    has_coupling = has_coupling || leafKey(a.key) == "coupling";
    has_friction = has_friction || leafKey(a.key) == "friction";
  }
  if (!has_coupling || !has_friction)
    throw std::runtime_error(r.dir + ": not a ladder experiment (analytic.coupling and effects.friction must be swept, "
                                     "configs/ladder/)");
  for (const char* m : {kAnalyticModel, kPerFootModel, kMujocoModel})
    if (!r.hasModel(m)) throw std::runtime_error(r.dir + ": model " + std::string(m) + " was not run");
  std::map<std::string, LadderCase> by;  // figure case name -> rungs
  std::vector<std::string> order;
  for (const CaseRecord& c : r.cases) {
    std::string name, coupling, friction;
    for (const SweepAxis& a : r.axes) {  // summary order, as the case names are built
      const auto v = c.sweep.find(a.key);
      if (v == c.sweep.end()) continue;
      if (leafKey(a.key) == "coupling") coupling = v->second;
      else if (leafKey(a.key) == "friction") friction = v->second;
      else name += (name.empty() ? "" : ",") + leafKey(a.key) + "=" + v->second;
    }
    if (name.empty()) name = "base";
    auto [it, fresh] = by.try_emplace(name);
    LadderCase& L = it->second;
    if (fresh) {
      order.push_back(name);
      L.experiment = r.name;
      L.name = name;
      for (const Rung& g : rungs()) L.*g.value = kNaN;
      L.paper_adams = kNaN;
    }
    const double a = r.phiNet(c, kAnalyticModel), p = r.phiNet(c, kPerFootModel), mj = r.phiNet(c, kMujocoModel);
    if (friction == "stiction") {
      if (coupling == "paper") {
        L.paper = a;
        L.perfoot_coulomb = p;  // the per-foot model and MuJoCo ignore analytic.coupling
        L.mujoco_const = mj;
      } else if (coupling == "exact") {
        L.exact = a;
      }
    } else if (friction == "continuous" && coupling == "paper") {
      L.paper_adams = a;
      L.perfoot_adams = p;
      L.mujoco_adams = mj;
    }
  }
  for (const std::string& n : order) out.push_back(by.at(n));
}

std::vector<double> steps(const LadderCase& c) {
  std::vector<double> s;
  const auto& g = rungs();
  for (size_t i = 1; i < g.size(); ++i) s.push_back(c.*g[i].value - c.*g[i - 1].value);
  return s;
}

struct Agreement {
  std::vector<double> before, coulomb, adams, adams_deg, coulomb_deg;
};
Agreement agreement(const std::vector<LadderCase>& cs) {
  Agreement a;
  for (const LadderCase& c : cs) {
    a.before.push_back(relPct(c.exact, c.mujoco_const));
    a.coulomb.push_back(relPct(c.perfoot_coulomb, c.mujoco_const));
    a.adams.push_back(relPct(c.perfoot_adams, c.mujoco_adams));
    a.coulomb_deg.push_back(std::abs(c.perfoot_coulomb - c.mujoco_const));
    a.adams_deg.push_back(std::abs(c.perfoot_adams - c.mujoco_adams));
  }
  return a;
}

void tableOf(std::ostringstream& o, const std::vector<LadderCase>& cs) {
  o << "| case |";
  for (const Rung& g : rungs()) o << " " << g.title << " |";
  o << " total gap |";
  for (const std::string& s : stepNames()) o << " " << s << " |";
  o << "\n|---|";
  for (size_t i = 0; i < rungs().size() + 1 + stepNames().size(); ++i) o << "---:|";
  o << "\n";
  for (const LadderCase& c : cs) {
    o << "| " << c.name << " |";
    for (const Rung& g : rungs()) o << " " << fmt("%.2f", c.*g.value) << " |";
    const double total = c.mujoco_const - c.paper;
    o << " " << fmt("%+.2f", total) << " |";
    for (double s : steps(c)) o << " " << fmt("%+.2f", s) << " (" << fmt("%.0f", 100.0 * s / total) << " %) |";
    o << "\n";
  }
  o << "\n";
}

std::string plotFigure(const std::string& plots, const std::string& exp, const std::vector<LadderCase>& cs) {
  const std::string stem = exp.rfind("ladder_", 0) == 0 ? exp : "ladder_" + exp;
  std::ostringstream body;
  body << "set title " << gpTitle(gpText("Gap ladder, " + exp + ": ") + "φ_{net} on each rung", 900)  // key outside
       << "\n"
       << "set ylabel 'φ_{net} [deg]'\nset grid\nset key outside right top box\n";
  std::vector<std::vector<double>> rows;
  std::vector<std::string> header;
  // x: the rungs; each line joins one case's phi_net from rung to rung. Up to 10 cases: one colour
  // each, in the legend; more: every case a thin grey line and their median in black.
  const bool few = cs.size() <= numSeriesColors();
  header = {"rung"};
  for (size_t k = 0; k < cs.size(); ++k) header.push_back("case" + std::to_string(k + 1));
  if (!few) header.push_back("median");
  for (size_t i = 0; i < rungs().size(); ++i) {
    std::vector<double> row{static_cast<double>(i + 1)};
    std::vector<double> finite;
    for (const LadderCase& c : cs) {
      row.push_back(c.*rungs()[i].value);
      if (std::isfinite(row.back())) finite.push_back(row.back());
    }
    if (!few) {
      std::sort(finite.begin(), finite.end());
      const size_t n = finite.size();
      row.push_back(n == 0 ? NAN : n % 2 ? finite[n / 2] : 0.5 * (finite[n / 2 - 1] + finite[n / 2]));
    }
    rows.push_back(row);
  }
  body << "set xtics (";
  for (size_t i = 0; i < rungs().size(); ++i)
    body << (i ? ", " : "") << gpQuote(gpText(rungs()[i].title)) << " " << i + 1;
  body << ") rotate by -25\nset xrange [0.5:" << rungs().size() + 0.5 << "]\nset xlabel 'rung of the ladder'\nplot ";
  if (few) {
    for (size_t k = 0; k < cs.size(); ++k)
      body << (k ? ", \\\n     " : "") << gpFileName(stem + ".dat") << " using 1:" << k + 2
           << " with linespoints lw 2 pt " << seriesPoint(k) << " dt " << seriesDash(k) << " lc rgb "
           << gpQuote(seriesColor(k)) << " title "
           << gpQuote(gpText(cs[k].name));
  } else {
    for (size_t k = 0; k < cs.size(); ++k)
      body << (k ? ", \\\n     " : "") << gpFileName(stem + ".dat") << " using 1:" << k + 2
           << " with lines lw 0.8 lc rgb '#B0B0B0' " << (k ? "notitle" : "title " + gpQuote(
                  gpText(std::to_string(cs.size()) + " cases, one line each")));
    body << ", \\\n     " << gpFileName(stem + ".dat") << " using 1:" << cs.size() + 2
         << " with linespoints lw 3 pt 7 lc rgb '#000000' title 'median'";
  }
  body << "\n";
  writeDataFile((std::filesystem::path(plots) / (stem + ".dat")).string(), header, rows);
  GnuplotFigure f;
  f.stem = stem;
  f.body = body.str();
  f.width_px = 1200;
  return renderFigure(plots, f);
}

// The Fig. 6 verdict (paper Sec. 4.2: ADAMS rotates more "due to the friction modeling").
void verdict(std::ostringstream& o, const std::vector<LadderCase>& cs) {
  o << "## Verdict on the paper's explanation of Fig. 6\n\n"
    << "Sec. 4.2 says the ADAMS model rotates more than the Simulink model \"due to the friction modeling\" "
       "(ADAMS' mu is 0 at zero slip speed). The paper's gap is the ADAMS-law contact model minus the paper "
       "model (here MuJoCo with the ADAMS law minus the paper model); the ladder splits it into: the paper's "
       "dropped coupling (exact - paper), friction per foot instead of per body (per-foot Coulomb - exact), "
       "the friction law itself (per-foot ADAMS - per-foot Coulomb) and what is left to the contact "
       "simulation (MuJoCo ADAMS - per-foot ADAMS). As a cross-check, the friction law swapped inside the "
       "paper's own model (paper model with the ADAMS law - paper model).\n\n"
    << "| case | paper gap [deg] | coupling | per-foot friction | friction law | contact model | law alone in the "
       "paper model |\n|---|---:|---:|---:|---:|---:|---:|\n";
  bool any = false;
  for (const LadderCase& c : cs) {
    if (c.experiment.rfind("ladder_fig06", 0) != 0) continue;
    any = true;
    const double gap = c.mujoco_adams - c.paper;
    auto cell = [&](double s) { return fmt("%+.2f", s) + " (" + fmt("%.0f", 100.0 * s / gap) + " %)"; };
    o << "| " << c.experiment << " " << c.name << " | " << fmt("%+.2f", gap) << " | " << cell(c.exact - c.paper)
      << " | " << cell(c.perfoot_coulomb - c.exact) << " | " << cell(c.perfoot_adams - c.perfoot_coulomb) << " | "
      << cell(c.mujoco_adams - c.perfoot_adams) << " | " << cell(c.paper_adams - c.paper) << " |\n";
  }
  if (!any) {
    o << "\n(no ladder_fig06* experiment in this folder)\n\n";
    return;
  }
  o << "\nEach cell: the step in deg and its share of the paper gap. The friction-law explanation holds to the "
       "extent of the \"friction law\" column; the rest of the gap is carried by the other columns.\n\n";
  for (const LadderCase& c : cs) {
    if (c.experiment.rfind("ladder_fig06", 0) != 0) continue;
    const double gap = c.mujoco_adams - c.paper;
    const std::vector<std::pair<const char*, double>> causes = {{"the dropped coupling", c.exact - c.paper},
                                                                 {"friction per foot", c.perfoot_coulomb - c.exact},
                                                                 {"the friction law", c.perfoot_adams - c.perfoot_coulomb},
                                                                 {"the contact model", c.mujoco_adams - c.perfoot_adams}};
    auto big = std::max_element(causes.begin(), causes.end(), [&](const auto& x, const auto& y) {
      return x.second * gap < y.second * gap;  // the largest contribution in the gap's direction
    });
    o << "- " << c.experiment << " " << c.name << ": the largest cause is " << big->first << " ("
      << fmt("%.0f", 100.0 * big->second / gap) << " % of " << fmt("%+.2f", gap) << " deg); the friction law carries "
      << fmt("%.0f", 100.0 * (c.perfoot_adams - c.perfoot_coulomb) / gap) << " % per foot and "
      << fmt("%.0f", 100.0 * (c.paper_adams - c.paper) / gap) << " % swapped into the paper model.\n";
  }
  o << "\n";
}

// ladder.csv: one row a case, phi_net on each rung and the paper model with the ADAMS law.
std::string ladderCsv(const std::vector<LadderCase>& cs) {
  std::ostringstream csv;
  csv << "experiment,case";
  for (const Rung& g : rungs()) csv << "," << g.key << "_deg";
  csv << ",paper_adams_deg\n";
  for (const LadderCase& c : cs) {
    csv << c.experiment << ",\"" << c.name << "\"";
    for (const Rung& g : rungs()) csv << "," << fmt("%.9g", c.*g.value);
    csv << "," << fmt("%.9g", c.paper_adams) << "\n";
  }
  return csv.str();
}

// ladder.md's agreement of the per-foot model with MuJoCo over all cases: the table, the cases
// where they differ most, and the cases with |MuJoCo phi_net| >= 1 deg only.
void agreementSection(std::ostringstream& o, const std::vector<LadderCase>& cs) {
  const Agreement a = agreement(cs);
  o << "## Per-foot model vs MuJoCo, same friction law (" << cs.size() << " cases)\n\n"
    << "|difference| in % of MuJoCo's |phi_net| (and in deg):\n\n"
    << "| pair | median | max | median [deg] | max [deg] |\n|---|---:|---:|---:|---:|\n"
    << "| before: exact coupling (per-body stiction) vs MuJoCo constant mu | " << fmt("%.1f %%", median(a.before))
    << " | " << fmt("%.1f %%", maxOf(a.before)) << " | | |\n"
    << "| per-foot Coulomb vs MuJoCo constant mu | " << fmt("%.1f %%", median(a.coulomb)) << " | "
    << fmt("%.1f %%", maxOf(a.coulomb)) << " | " << fmt("%.3f", median(a.coulomb_deg)) << " | "
    << fmt("%.3f", maxOf(a.coulomb_deg)) << " |\n"
    << "| per-foot ADAMS law vs MuJoCo ADAMS law | " << fmt("%.1f %%", median(a.adams)) << " | "
    << fmt("%.1f %%", maxOf(a.adams)) << " | " << fmt("%.3f", median(a.adams_deg)) << " | "
    << fmt("%.3f", maxOf(a.adams_deg)) << " |\n\n";
  // Where they differ most: the worst cases of each pair, with MuJoCo's phi_net (a small phi_net
  // makes a large percentage of a small difference).
  for (int law = 0; law < 2; ++law) {
    std::vector<const LadderCase*> w;
    for (const LadderCase& c : cs) w.push_back(&c);
    auto diff = [&](const LadderCase* c) {
      return law ? std::abs(c->perfoot_adams - c->mujoco_adams) : std::abs(c->perfoot_coulomb - c->mujoco_const);
    };
    std::sort(w.begin(), w.end(), [&](const LadderCase* x, const LadderCase* y) { return diff(x) > diff(y); });
    o << "Largest differences, " << (law ? "ADAMS law" : "Coulomb / constant mu") << " [deg]: ";
    for (size_t i = 0; i < std::min<size_t>(5, w.size()); ++i) {
      const LadderCase& c = *w[i];
      o << (i ? "; " : "") << c.experiment << " " << c.name << ": per-foot "
        << fmt("%.2f", law ? c.perfoot_adams : c.perfoot_coulomb) << " vs MuJoCo "
        << fmt("%.2f", law ? c.mujoco_adams : c.mujoco_const);
    }
    o << ".\n\n";
  }
  // Cases with |MuJoCo phi_net| >= 1 deg only (the percentages of the near-zero ones say little).
  std::vector<double> c1, a1;
  for (const LadderCase& c : cs) {
    if (std::abs(c.mujoco_const) >= 1.0) c1.push_back(relPct(c.perfoot_coulomb, c.mujoco_const));
    if (std::abs(c.mujoco_adams) >= 1.0) a1.push_back(relPct(c.perfoot_adams, c.mujoco_adams));
  }
  o << "Cases with |MuJoCo phi_net| >= 1 deg only: Coulomb median " << fmt("%.1f %%", median(c1)) << ", max "
    << fmt("%.1f %%", maxOf(c1)) << " (" << c1.size() << " cases); ADAMS law median " << fmt("%.1f %%", median(a1))
    << ", max " << fmt("%.1f %%", maxOf(a1)) << " (" << a1.size() << " cases).\n\n";
}

// ladder.md's table of the median |step| of each experiment.
void medianStepsSection(std::ostringstream& o, const std::vector<LadderCase>& cs, const std::vector<std::string>& exps) {
  o << "## Median |step| per figure [deg]\n\n| experiment | cases | median |total gap| |";
  for (const std::string& s : stepNames()) o << " " << s << " |";
  o << "\n|---|---:|---:|";
  for (size_t i = 0; i < stepNames().size(); ++i) o << "---:|";
  o << "\n";
  for (const std::string& e : exps) {
    std::vector<double> tot;
    std::vector<std::vector<double>> st(stepNames().size());
    int n = 0;
    for (const LadderCase& c : cs) {
      if (c.experiment != e) continue;
      ++n;
      tot.push_back(std::abs(c.mujoco_const - c.paper));
      const std::vector<double> s = steps(c);
      for (size_t i = 0; i < s.size(); ++i) st[i].push_back(std::abs(s[i]));
    }
    o << "| " << e << " | " << n << " | " << fmt("%.2f", median(tot)) << " |";
    for (const auto& v : st) o << " " << fmt("%.2f", median(v)) << " |";
    o << "\n";
  }
  o << "\n";
}

// ladder.md's last section: each experiment's figure (drawn into plots/, added to files) and table.
void everyCaseSection(std::ostringstream& o, const std::vector<LadderCase>& cs, const std::vector<std::string>& exps,
                      const std::string& plots, std::vector<std::string>& files) {
  o << "## Every case\n\n";
  for (const std::string& e : exps) {
    std::vector<LadderCase> sub;
    for (const LadderCase& c : cs)
      if (c.experiment == e) sub.push_back(c);
    const std::string png = plotFigure(plots, e, sub);
    files.push_back(png);
    o << "### " << e << "\n\n![" << e << "](plots/" << std::filesystem::path(png).filename().string() << ")\n\n";
    tableOf(o, sub);
  }
}

}  // namespace

std::vector<LadderCase> loadLadder(const std::string& dir) {
  std::vector<LadderCase> out;
  for (const ExperimentResults& r : loadResultTree(dir)) addExperiment(r, out);
  if (out.empty()) throw std::runtime_error(dir + ": no ladder experiment results (configs/ladder/)");
  return out;
}

std::vector<std::string> writeLadder(const std::string& dir) {
  const std::vector<LadderCase> cs = loadLadder(dir);
  // ladder.csv and ladder.md only over tailsim's own (an earlier tailsim's without a manifest: by their first line)
  const auto earlier = [](const char* head) {
    return [h = std::string(head)](const std::string& text) { return text.compare(0, h.size(), h) == 0; };
  };
  const EarlierOwnFile earlier_csv = earlier("experiment,case,"), earlier_md = earlier("# The gap ladder\n");
  checkOwnedFile(dir, "ladder.csv", std::nullopt, earlier_csv);  // before anything is written
  checkOwnedFile(dir, "ladder.md", std::nullopt, earlier_md);
  std::vector<std::string> files;
  const std::string plots = (std::filesystem::path(dir) / "plots").string();
  std::filesystem::create_directories(plots);

  std::vector<std::string> exps;
  for (const LadderCase& c : cs)
    if (std::find(exps.begin(), exps.end(), c.experiment) == exps.end()) exps.push_back(c.experiment);

  writeOwnedFile(dir, "ladder.csv", ladderCsv(cs), earlier_csv);
  files.push_back((std::filesystem::path(dir) / "ladder.csv").string());

  std::ostringstream o;
  o << "# The gap ladder\n\n"
    << "phi_net [deg] of every case on six rungs: paper model (analytic, coupling paper, stiction) -> exact "
       "coupling (analytic, coupling exact) -> per-foot Coulomb (perfoot, stiction) -> per-foot ADAMS law "
       "(perfoot, continuous) -> MuJoCo (ADAMS law: effects.friction continuous) -> MuJoCo (constant mu: "
       "effects.friction stiction, today's default). Each step is the next rung minus this one, with its "
       "share of the total gap (MuJoCo constant mu - paper model); the steps add up to the total. "
       "Written by `tailsim ladder` from the result folder (configs/ladder/all.yaml).\n\n";
  agreementSection(o, cs);
  medianStepsSection(o, cs, exps);
  verdict(o, cs);
  everyCaseSection(o, cs, exps, plots, files);
  const std::string md = (std::filesystem::path(dir) / "ladder.md").string();
  writeOwnedFile(dir, "ladder.md", o.str(), earlier_md);
  files.insert(files.begin(), md);
  return files;
}

}  // namespace tailsim
