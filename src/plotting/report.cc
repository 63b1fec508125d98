#include "plotting/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "experiments/model_registry.h"
#include "plotting/figure_sheet.h"
#include "plotting/style.h"
#include "plotting/sweep_summary.h"
#include "common/atomic_file.h"
#include "common/number_text.h"

namespace tailsim {

namespace fs = std::filesystem;

namespace {

std::string num(double v, const char* f = "%+.3f") { return std::isfinite(v) ? formatNumber(f, v) : std::string("n/a"); }

// Table cells must not contain a bare '|'.
std::string cell(std::string s) {
  for (size_t p = s.find('|'); p != std::string::npos; p = s.find('|', p + 2)) s.replace(p, 1, "\\|");
  return s;
}

std::string relativeTo(const std::string& path, const std::string& base) {
  std::error_code ec;
  const fs::path rel = fs::relative(fs::absolute(path), fs::absolute(base), ec);
  return ec || rel.empty() ? path : rel.generic_string();
}

bool under(const std::string& file, const std::string& dir) {
  const std::string f = fs::absolute(file).lexically_normal().generic_string();
  std::string d = fs::absolute(dir).lexically_normal().generic_string();
  if (!d.empty() && d.back() != '/') d += '/';
  return f.compare(0, d.size(), d) == 0;
}

std::vector<PlotFile> existingPlots(const ExperimentResults& r) {
  std::vector<PlotFile> out;
  const fs::path p = fs::path(r.dir) / "plots";
  if (!fs::is_directory(p)) return out;
  for (const auto& e : fs::directory_iterator(p))
    if (e.path().extension() == ".png") out.push_back({e.path().string(), e.path().stem().string(), ""});
  std::sort(out.begin(), out.end(), [](const PlotFile& a, const PlotFile& b) { return a.png < b.png; });
  return out;
}

void findingsSection(std::ostringstream& o, const std::vector<Finding>& findings) {
  o << "## Paper claims, model by model\n\n"
    << "YES: the model's results show the claim, NO: they do not (the numbers say where), n/a: no data "
       "(experiment or model not run). phi_net is compared signed (positive = counter-clockwise, against the "
       "tail's clockwise swing).\n\n";
  o << "| where | claim | analytic | MuJoCo |\n|---|---|---|---|\n";
  for (const Finding& f : findings) {
    auto v = [&](const std::string& m) -> std::string {
      if (const ModelVerdict* mv = f.verdictFor(m)) return verdictText(mv->verdict);
      return "";
    };
    std::string a = v(kAnalyticModel), mj = v(kMujocoModel);
    if (const ModelVerdict* cmp = f.verdictFor("mujoco vs analytic")) a = mj = std::string(verdictText(cmp->verdict)) + " (comparison)";
    o << "| " << cell(f.where) << " | " << cell(f.brief.empty() ? f.claim : f.brief) << " | " << a << " | " << mj
      << " |\n";
  }
  o << "\n### Details\n\n";
  for (const Finding& f : findings) {
    o << "- **" << f.where << "** — " << f.claim << ":\n";
    for (const ModelVerdict& v : f.verdicts)
      o << "  - " << v.model << " **" << verdictText(v.verdict) << "**: " << v.detail << "\n";
  }
  o << "\n";
  // Plain statement of what does not reproduce.
  std::vector<std::string> no;
  for (const Finding& f : findings)
    for (const ModelVerdict& v : f.verdicts)
      if (v.verdict == Verdict::kNo) no.push_back(v.model + ": " + f.where + " (" + f.id + ")");
  o << "### Not reproduced\n\n";
  if (no.empty()) o << "Every claim with data is reproduced.\n\n";
  else {
    for (const std::string& s : no) o << "- " << s << "\n";
    o << "\n";
  }
}

void fig06Table(std::ostringstream& o, const std::vector<ExperimentResults>& results) {
  std::vector<const ExperimentResults*> rs;
  for (const ExperimentResults& r : results)
    if (r.name.compare(0, 5, "fig06") == 0) rs.push_back(&r);
  if (rs.empty()) return;
  o << "## Fig. 6: net rotation, analytic vs MuJoCo\n\n"
    << "| experiment | model | phi_net [deg] | t_stop [s] | stick/slip events | wall time [s] |\n|---|---|---|---|---|---|\n";
  for (const ExperimentResults* r : rs)
    for (const CaseRecord& c : r->cases)
      for (const auto& [m, run] : c.runs)
        o << "| " << r->name << (r->cases.size() > 1 ? " " + c.name : "") << " | " << m << " | "
          << (run.ok ? run.phiText() : "failed: " + cell(run.error)) << " | " << num(run.t_stop_s, "%.3f")
          << " | " << run.stick_slip_events << " | " << num(run.wall_time_s, "%.3f") << " |\n";
  o << "\n";
}

void muSwapTable(std::ostringstream& o, const std::vector<ExperimentResults>& results) {
  const ExperimentResults* base = findExperiment(results, "fig07");
  const ExperimentResults* sw = findExperiment(results, "mu_swapped");
  if (!sw) return;
  o << "## Table 1's friction coefficients swapped (docs/paper-notes.md point 1)\n\n"
    << "The Fig. 7 case as printed (mu_s 0.25, mu_d 0.30: breakaway at max(mu_s, mu_d) = 0.30) and with the two "
       "coefficients swapped (mu_s 0.30, mu_d 0.25).\n\n"
    << "| model | phi_net as printed [deg] | phi_net swapped [deg] | change [deg] |\n|---|---|---|---|\n";
  for (const std::string& m : sw->models) {
    const double a = (base && !base->cases.empty()) ? base->phiNet(base->cases.front(), m) : NAN;
    const double b = sw->cases.empty() ? NAN : sw->phiNet(sw->cases.front(), m);
    o << "| " << m << " | " << num(a) << " | " << num(b) << " | " << num(b - a) << " |\n";
  }
  o << "\nThe analytic model breaks away at max(mu_s, mu_d) and slides at mu_d, so the swap changes its sliding "
       "friction only. MuJoCo's contact has one coefficient, max(mu_s, mu_d) unless `mujoco.mu` is set "
       "(mujoco_settings.h), so the swap leaves it unchanged by construction.\n\n";
}

void experimentSection(std::ostringstream& o, const ExperimentResults& r, const std::vector<PlotFile>& plots,
                       const std::string& base) {
  o << "### " << r.name << "\n\n";
  if (!r.description.empty()) o << r.description << "\n\n";
  o << "Folder `" << relativeTo(r.dir, base) << "`, kind " << r.kind << ", " << r.cases.size() << " case(s)";
  if (!r.axes.empty()) {
    o << ", swept:";
    for (const SweepAxis& a : r.axes)
      o << (&a == &r.axes.front() ? " " : "; ") << leafKey(a.key) << " (" << a.values.size() << " values, "
        << a.values.front() << " .. " << a.values.back() << ")";
  }
  o << ", models:";
  for (const std::string& m : r.models) {
    int ok = 0, failed = 0;
    double wall = 0;
    for (const CaseRecord& c : r.cases)
      if (auto it = c.runs.find(m); it != c.runs.end()) {
        (it->second.ok ? ok : failed)++;
        if (std::isfinite(it->second.wall_time_s)) wall += it->second.wall_time_s;
      }
    o << (m == r.models.front() ? " " : "; ") << m << " (" << ok << " ok"
      << (failed ? ", " + std::to_string(failed) + " FAILED" : "") << ", " << formatNumber("%.3g", wall)
      << " s wall time in the simulations)";
  }
  o << ".\n\n";
  for (const CaseRecord& c : r.cases)
    for (const auto& [m, run] : c.runs)
      if (!run.ok) o << "- failed: " << c.name << " / " << m << ": " << run.error << "\n";
  {
    const SweepSummary sum = summarizeSweep(r);
    auto list = [&](const char* what, const std::vector<std::string>& lines) {
      if (lines.empty()) return;
      o << "\n" << what << ":\n\n";
      for (const std::string& l : lines) o << "- " << l << "\n";
    };
    list("Largest phi_net per model", sum.best);
    list("Trend along each swept key", sum.trends);
    list("Where the models differ", sum.disagree);
    list("Warnings (each once, with the number of runs)", sum.warnings);
  }
  // The verdict across the models, once per case (experiments/verdict.h).
  if (std::any_of(r.cases.begin(), r.cases.end(), [](const CaseRecord& c) { return !c.verdict.empty(); })) {
    o << "\nVerdict across the models (docs/accuracy.md \"Verdict across the models\"):\n\n"
      << "| case | verdict |\n|---|---|\n";
    for (const CaseRecord& c : r.cases)
      if (!c.verdict.empty()) o << "| " << cell(c.name) << " | " << cell(c.verdict) << " |\n";
  }
  // One-axis phi_net table (small sweeps): the numbers behind the line plots.
  if (r.kind != "pose" && r.axes.size() == 1 && r.cases.size() <= 20) {
    const SweepAxis& a = r.axes[0];
    o << "\n| " << leafKey(a.key);
    for (const std::string& m : r.models) o << " | " << m << " phi_net [deg]";
    o << " |\n|---";
    for (size_t i = 0; i < r.models.size(); ++i) o << "|---";
    o << "|\n";
    for (const std::string& v : a.values) {
      o << "| " << v;
      const CaseRecord* c = r.find({{a.key, v}});
      for (const std::string& m : r.models) {
        const auto run = c ? c->runs.find(m) : std::map<std::string, RunRecord>::const_iterator();
        o << " | " << (c && run != c->runs.end() ? run->second.phiText() : std::string("n/a"));
      }
      o << " |\n";
    }
  }
  o << "\n";
  for (const PlotFile& p : plots)
    if (under(p.png, r.dir)) o << "![" << p.caption << "](" << relativeTo(p.png, base) << ")\n\n";
}

}  // namespace

std::string reportMarkdown(const std::vector<ExperimentResults>& results, const std::vector<Finding>& findings,
                           const std::vector<PlotFile>& plots, const std::string& base_dir) {
  std::ostringstream o;
  const bool paper = std::any_of(results.begin(), results.end(), [](const ExperimentResults& r) { return isPaperFigure(r); });
  if (paper) {
    o << "# tailsim reproduction report: Rone & Ben-Tzvi 2016\n\n"
      << "Generated by `tailsim report` from the result folder(s) under `" << base_dir << "` ("
      << results.size() << " experiment(s)). Analytic = the paper's model (\"Simulink\", stiction friction); "
      << "MuJoCo = the contact model standing in for the paper's ADAMS model. Experiment files: "
         "configs/paper/*.yaml; choices are documented in docs/reproduction.md.\n\n";
    findingsSection(o, findings);
    fig06Table(o, results);
    muSwapTable(o, results);
  } else {
    o << "# tailsim report: " << (results.size() == 1 ? results[0].name : base_dir) << "\n\n"
      << "Generated by `tailsim report` from the result folder(s) under `" << base_dir << "` ("
      << results.size() << " experiment(s)). " << modelGlossary(allModels(results))
      << " No experiment here reproduces a paper figure, so no paper claim is checked.\n\n";
  }
  o << "## Experiments and figures\n\n";
  for (const ExperimentResults& r : results) {
    std::vector<PlotFile> mine;
    for (const PlotFile& p : plots)
      if (under(p.png, r.dir)) mine.push_back(p);
    if (plots.empty()) mine = existingPlots(r);
    experimentSection(o, r, mine, base_dir);
  }
  return o.str();
}

// A report.md of an earlier tailsim (before manifests), recognised by its title.
bool earlierReport(const std::string& text) { return text.compare(0, 9, "# tailsim") == 0; }

std::string writeReport(const std::string& dir, bool draw_plots) {
  checkOwnedFile(dir, "report.md", std::nullopt, earlierReport);  // before any work
  const std::vector<ExperimentResults> results = loadResultTree(dir);
  std::vector<PlotFile> plots;
  if (draw_plots)
    for (const ExperimentResults& r : results) {
      std::vector<PlotFile> p = plotExperiment(r);
      plots.insert(plots.end(), p.begin(), p.end());
    }
  if (draw_plots) writeFigureSheet(dir, results, plots);
  const std::vector<Finding> findings = computeFindings(results);
  const std::string path = (fs::path(dir) / "report.md").string();
  writeOwnedFile(dir, "report.md", reportMarkdown(results, findings, plots, dir), earlierReport);
  return path;
}

}  // namespace tailsim
