#include "plotting/sweep_summary.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <regex>

#include "plotting/style.h"

namespace tailsim {

namespace {

std::string deg(double v, const char* f = "%+.2f") {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  std::string s = b;
  if (s == "-0.00" || s == "+0.00") s = "0.00";
  return s + "°";
}

// "Δθ = -90°, ΔT = 0.25 s" for the case's values of the swept keys; "the single case" without any.
std::string where(const ExperimentResults& r, const CaseRecord& c) {
  std::string s;
  for (const SweepAxis& a : r.axes) {
    const auto it = c.sweep.find(a.key);
    if (it != c.sweep.end()) s += (s.empty() ? "" : ", ") + plainValueLabel(a.key, it->second);
  }
  return s.empty() ? "the single case" : s;
}

std::string modelName(const ExperimentResults& r, const std::string& m) { return r.modelTitle(m); }

void trends(const ExperimentResults& r, const std::string& m, std::vector<std::string>& out) {
  for (const SweepAxis& a : r.axes) {
    std::vector<double> mean(a.values.size(), 0.0);
    std::vector<int> n(a.values.size(), 0);
    for (const CaseRecord& c : r.cases) {
      const auto it = c.sweep.find(a.key);
      if (it == c.sweep.end()) continue;
      const int i = a.indexOf(it->second);
      const double v = r.phiNet(c, m);
      if (i < 0 || !std::isfinite(v)) continue;
      mean[i] += v, ++n[i];
    }
    std::vector<size_t> idx;
    for (size_t i = 0; i < mean.size(); ++i)
      if (n[i] > 0) mean[i] /= n[i], idx.push_back(i);
    if (idx.size() < 2) continue;
    const std::string key = keyDisplay(a.key).plain;
    const std::string over = r.axes.size() > 1 ? " (mean over the other keys)" : "";
    auto at = [&](size_t i) { return deg(mean[i]) + " at " + plainValueLabel(a.key, a.values[i]); };
    size_t imax = idx[0], imin = idx[0];
    for (size_t i : idx) {
      if (mean[i] > mean[imax]) imax = i;
      if (mean[i] < mean[imin]) imin = i;
    }
    const double spread = mean[imax] - mean[imin];
    std::string s = modelName(r, m) + ": φ_net ";
    if (spread < std::max(0.01, 0.01 * std::max(std::fabs(mean[imax]), std::fabs(mean[imin])))) {
      s += "does not change with " + key + " (" + deg(mean[idx[0]]) + " throughout)";
    } else if (!a.numeric) {
      s += "over " + key + ": largest " + at(imax) + ", smallest " + at(imin);
    } else {
      bool up = true, down = true;
      for (size_t k = 1; k < idx.size(); ++k) {
        up = up && mean[idx[k]] >= mean[idx[k - 1]];
        down = down && mean[idx[k]] <= mean[idx[k - 1]];
      }
      const size_t first = idx.front(), last = idx.back();
      if (up) s += "rises with " + key + ", from " + at(first) + " to " + at(last);
      else if (down) s += "falls with " + key + ", from " + at(first) + " to " + at(last);
      else if (imax != first && imax != last) s += "peaks over " + key + " at " + at(imax) + " (" + at(first) + ", " + at(last) + ")";
      else if (imin != first && imin != last) s += "dips over " + key + " to " + at(imin) + " (" + at(first) + ", " + at(last) + ")";
      else s += "varies over " + key + ": largest " + at(imax) + ", smallest " + at(imin);
    }
    out.push_back(s + over + ".");
  }
}

}  // namespace

bool isPaperFigure(const ExperimentResults& r) {
  static const std::regex paper_name(R"(^(fig\d\d|model_bridge|mu_swapped))");
  return figureOrder(r.description) < 1e5 || std::regex_search(r.name, paper_name);
}

SweepSummary summarizeSweep(const ExperimentResults& r) {
  SweepSummary s;
  if (r.kind != "pose") {
    for (const std::string& m : r.models) {
      const CaseRecord* best = nullptr;
      int ok = 0;
      for (const CaseRecord& c : r.cases) {
        const double v = r.phiNet(c, m);
        if (!std::isfinite(v)) continue;
        ++ok;
        if (!best || std::fabs(v) > std::fabs(r.phiNet(*best, m))) best = &c;  // the largest turn, either way
      }
      if (!best) {
        s.best.push_back(modelName(r, m) + ": no successful run.");
        continue;
      }
      std::string line = modelName(r, m) + ": largest |φ_net| " + deg(r.phiNet(*best, m)) + " at " + where(r, *best);
      if (ok < static_cast<int>(r.cases.size()))
        line += " (" + std::to_string(ok) + " of " + std::to_string(r.cases.size()) + " runs succeeded)";
      s.best.push_back(line + ".");
      trends(r, m, s.trends);
    }
    for (size_t k = 1; k < r.models.size(); ++k) {
      const std::string& m0 = r.models[0];
      const std::string& m1 = r.models[k];
      const CaseRecord* worst = nullptr;
      double worst_d = 0, sum = 0;
      int n = 0, opposite = 0;
      for (const CaseRecord& c : r.cases) {
        const double a = r.phiNet(c, m0), b = r.phiNet(c, m1);
        if (!std::isfinite(a) || !std::isfinite(b)) continue;
        const double d = b - a;
        ++n, sum += std::fabs(d);
        if (a * b < 0 && std::fabs(a) > 0.01 && std::fabs(b) > 0.01) ++opposite;
        if (!worst || std::fabs(d) > std::fabs(worst_d)) worst = &c, worst_d = d;
      }
      if (!worst) continue;
      std::string line = modelName(r, m1) + " − " + modelName(r, m0) + ": largest difference " + deg(worst_d) + " (" +
                         deg(r.phiNet(*worst, m1)) + " vs " + deg(r.phiNet(*worst, m0)) + ") at " + where(r, *worst);
      if (n > 1) line += "; mean |difference| " + deg(sum / n, "%.2f") + " over " + std::to_string(n) + " cases";
      if (opposite > 0) line += "; opposite signs in " + std::to_string(opposite) + " case" + (opposite > 1 ? "s" : "");
      // The runs' own uncertainties where they have one (MuJoCo's phi_net_uncertainty_deg).
      std::string u;
      for (const std::string& m : {m0, m1}) {
        const auto run = worst->runs.find(m);
        if (run != worst->runs.end() && std::isfinite(run->second.phi_net_uncertainty_deg))
          u += (u.empty() ? "" : "; ") + modelName(r, m) + "'s uncertainty there ±" +
               deg(run->second.phi_net_uncertainty_deg, "%.3f");
      }
      s.disagree.push_back(line + (u.empty() ? ". (No uncertainty is recorded for these results.)" : " (" + u + ")."));
    }
  }
  struct Group {
    std::string model, text, first;
    int runs = 0;
  };
  std::vector<Group> groups;
  std::map<std::pair<std::string, std::string>, size_t> by;
  for (const CaseRecord& c : r.cases)
    for (const auto& [m, run] : c.runs)
      for (const std::string& w : run.warnings) {
        const auto [it, added] = by.emplace(std::make_pair(m, warningShape(w)), groups.size());
        if (added) groups.push_back({m, w, c.name});
        ++groups[it->second].runs;
      }
  for (const Group& g : groups)
    s.warnings.push_back(modelName(r, g.model) + ", " + std::to_string(g.runs) + " run" + (g.runs > 1 ? "s" : "") +
                         " (first: " + g.first + (g.runs > 1 ? "; each run's numbers in results.csv" : "") + "): " +
                         g.text);
  return s;
}

}  // namespace tailsim
