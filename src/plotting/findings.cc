#include "plotting/findings.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <sstream>

#include "models/planar/system_loads.h"
#include "results/columns.h"
#include "experiments/model_registry.h"
#include "common/number_text.h"
#include "common/units.h"

namespace tailsim {

namespace fs = std::filesystem;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const std::vector<std::string> kModels = modelNames();

std::string signedDeg(double v) { return formatNumber("%+.3f", v) + " deg"; }

ModelVerdict na(const std::string& model, const std::string& why) { return {model, Verdict::kNotAvailable, why}; }

// Models of a finding: analytic and mujoco always (n/a when not run), plus any others present.
std::vector<std::string> modelsOf(const ExperimentResults* r) {
  std::vector<std::string> m = kModels;
  if (r)
    for (const std::string& x : r->models)
      if (std::find(m.begin(), m.end(), x) == m.end()) m.push_back(x);
  return m;
}

std::string notRun(const ExperimentResults& r, const std::string& model) {
  return "not run (" + r.name + " has no " + model + " runs)";
}

// phi_net along `axis` (in the given value order) with the other keys fixed.
std::vector<double> phiAlong(const ExperimentResults& r, const SweepAxis& axis, const std::vector<size_t>& order,
                             const std::string& model, std::map<std::string, std::string> fixed = {}) {
  std::vector<double> y;
  for (size_t i : order) {
    fixed[axis.key] = axis.values[i];
    const CaseRecord* c = r.find(fixed);
    y.push_back(c ? r.phiNet(*c, model) : kNaN);
  }
  return y;
}

std::vector<size_t> ascending(const SweepAxis& a) {
  std::vector<size_t> o(a.values.size());
  std::iota(o.begin(), o.end(), 0);
  return o;
}

std::vector<size_t> byMagnitude(const SweepAxis& a) {
  std::vector<size_t> o = ascending(a);
  std::stable_sort(o.begin(), o.end(), [&](size_t x, size_t y) { return std::fabs(a.number(x)) < std::fabs(a.number(y)); });
  return o;
}

std::string listValues(const std::vector<double>& y, const char* f = "%.2f") {
  std::string s;
  for (size_t i = 0; i < y.size(); ++i) s += (i ? ", " : "") + (std::isfinite(y[i]) ? formatNumber(f, y[i]) : "NaN");
  return s;
}

// A 1-D monotonicity finding over one axis of one experiment (Figs. 11, 13, 14).
void oneAxisTrend(Finding& f, const ExperimentResults* r, const std::string& leaf, bool by_magnitude, int direction,
                  const std::string& what) {
  for (const std::string& m : modelsOf(r)) {
    if (!r) { f.verdicts.push_back(na(m, "experiment not in the results")); continue; }
    const SweepAxis* a = findAxis(*r, leaf);
    if (!a) { f.verdicts.push_back(na(m, r->name + " has no sweep over " + leaf)); continue; }
    if (!r->hasModel(m)) { f.verdicts.push_back(na(m, notRun(*r, m))); continue; }
    const std::vector<size_t> order = by_magnitude ? byMagnitude(*a) : ascending(*a);
    const std::vector<double> y = phiAlong(*r, *a, order, m);
    const Trend t = checkTrend(y, direction, 1e-9, true);
    std::string xs;
    for (size_t k = 0; k < order.size(); ++k) xs += (k ? ", " : "") + a->values[order[k]];
    std::string d = "phi_net = [" + listValues(y) + "] deg at " + leaf + " = [" + xs + "]";
    if (!t.complete) {
      f.verdicts.push_back({m, Verdict::kNo, "incomplete (failed or missing runs): " + d});
      continue;
    }
    if (t.zero_plateaus)
      d += "; " + std::to_string(t.zero_plateaus) + " step(s) skipped where phi_net = 0 on both sides";
    if (t.holds)
      d = "smallest step " + formatNumber("%.3f", t.min_step) + " deg (" + a->values[order[t.worst]] + " -> " +
          a->values[order[t.worst + 1]] + "); " + d;
    else
      d = what + " fails between " + leaf + " = " + a->values[order[t.worst]] + " and " + a->values[order[t.worst + 1]] +
          " (phi_net " + formatNumber("%.3f", y[t.worst]) + " -> " + formatNumber("%.3f", y[t.worst + 1]) + " deg); " + d;
    f.verdicts.push_back({m, t.holds ? Verdict::kYes : Verdict::kNo, d});
  }
}

// A 2-D finding: along axis `along` the trend must hold for every value of axis `across`.
void twoAxisTrend(Finding& f, const ExperimentResults* r, const std::string& along_leaf, bool by_magnitude,
                  int direction, const std::string& across_leaf) {
  for (const std::string& m : modelsOf(r)) {
    if (!r) { f.verdicts.push_back(na(m, "experiment not in the results")); continue; }
    const SweepAxis* along = findAxis(*r, along_leaf);
    const SweepAxis* across = findAxis(*r, across_leaf);
    if (!along || !across) {
      f.verdicts.push_back(na(m, r->name + " does not sweep both " + along_leaf + " and " + across_leaf));
      continue;
    }
    if (!r->hasModel(m)) { f.verdicts.push_back(na(m, notRun(*r, m))); continue; }
    const std::vector<size_t> order = by_magnitude ? byMagnitude(*along) : ascending(*along);
    int held = 0, incomplete = 0, plateaus = 0;
    double min_step = std::numeric_limits<double>::infinity();
    std::string where_min, failures;
    for (size_t j = 0; j < across->values.size(); ++j) {
      const std::vector<double> y = phiAlong(*r, *along, order, m, {{across->key, across->values[j]}});
      const Trend t = checkTrend(y, direction, 1e-9, true);
      if (!t.complete) { ++incomplete; continue; }
      const std::string at = across_leaf + "=" + across->values[j] + ", " + along_leaf + " " +
                             along->values[order[t.worst]] + " -> " + along->values[order[t.worst + 1]];
      plateaus += t.zero_plateaus;
      if (t.holds) ++held;
      else
        failures += (failures.empty() ? "" : "; ") + at + " (phi_net " + formatNumber("%.3f", y[t.worst]) + " -> " +
                    formatNumber("%.3f", y[t.worst + 1]) + " deg)";
      if (t.min_step < min_step) min_step = t.min_step, where_min = at;
    }
    const int n = static_cast<int>(across->values.size());
    std::string d = "holds at " + std::to_string(held) + " of " + std::to_string(n) + " values of " + across_leaf;
    if (incomplete) d += " (" + std::to_string(incomplete) + " incomplete: failed or missing runs)";
    if (std::isfinite(min_step)) d += "; smallest step in the claimed direction " + formatNumber("%.3f", min_step) + " deg at " + where_min;
    if (plateaus)
      d += "; " + std::to_string(plateaus) + " step(s) skipped where phi_net = 0 on both sides (static friction never "
           "broken)";
    if (!failures.empty()) d += "; fails at: " + failures;
    f.verdicts.push_back({m, held == n ? Verdict::kYes : Verdict::kNo, d});
  }
}

// Why a folder has no resolved cases (for n/a verdicts).
std::string unresolved(const ExperimentResults& r) {
  return "the cases as run are not readable from " + r.dir + "/experiment.yaml: " + r.resolve_error;
}

// Index of a column's max |value| and that value; -1 if absent.
std::pair<long, double> peakAbs(const TimeSeries& s, const std::string& col) {
  if (!s.has(col)) return {-1, kNaN};
  const auto& v = s.values(col);
  long best = -1;
  double b = -1;
  for (size_t i = 0; i < v.size(); ++i)
    if (std::isfinite(v[i]) && std::fabs(v[i]) > b) b = std::fabs(v[i]), best = static_cast<long>(i);
  return {best, b};
}

// ---- individual findings --------------------------------------------------------------------

Finding splitCycle(const std::vector<ExperimentResults>& all) {
  Finding f{"split_cycle_peak", "Sec. 3.3, Eqs. (20)-(23)",
            "peak joint speed is 2|dtheta|/dT, reached at t = t0 + w_ss dT; theta goes from theta0 to theta0 + dtheta "
            "(fig07 case, joint 1, measured from each model's joint angles)",
            {}};
  const ExperimentResults* r = findExperiment(all, "fig07");
  for (const std::string& m : modelsOf(r)) {
    if (!r) { f.verdicts.push_back(na(m, "fig07 not in the results")); continue; }
    if (!r->hasModel(m)) { f.verdicts.push_back(na(m, notRun(*r, m))); continue; }
    // Joint 1's trajectory as the case ran it (resolved: defaults, per-joint lists, rule: eq25).
    const ExperimentCase* rc = r->cases.empty() ? nullptr : r->resolvedCase(r->cases.front());
    if (!rc || rc->joints.empty()) {
      f.verdicts.push_back(na(m, r->cases.empty() ? "fig07 has no case" : unresolved(*r)));
      continue;
    }
    const SplitCycleParams& j1 = rc->joints.front();
    const double dT = j1.dT_s, dth = units::degrees(j1.dtheta_rad), w = j1.w_ss, th0 = units::degrees(j1.theta0_rad);
    const double t0 = j1.t0_s;
    TimeSeries s;
    try {
      s = r->series(r->cases.front(), m);
    } catch (const std::exception& e) {
      f.verdicts.push_back(na(m, e.what()));
      continue;
    }
    if (!s.has(col::kT) || !s.has("thetadot1_dps") || !s.has("theta1_deg") || s.numRows() < 3) {
      f.verdicts.push_back(na(m, "CSV lacks t_s, theta1_deg, thetadot1_dps"));
      continue;
    }
    const auto& t = s.values(col::kT);
    const double dt = t[1] - t[0];
    const auto [ip, peak] = peakAbs(s, "thetadot1_dps");
    const double want_peak = 2.0 * std::fabs(dth) / dT, want_t = t0 + w * dT;
    const double th_start = s.values("theta1_deg").front(), th_end = s.values("theta1_deg").back();
    const double peak_err = std::fabs(peak - want_peak) / want_peak, t_err = std::fabs(t[ip] - want_t);
    const double th_err = std::max(std::fabs(th_start - th0), std::fabs(th_end - (th0 + dth)));
    const bool ok = peak_err <= 0.01 && t_err <= std::max(2.0 * dt, 0.02 * dT) && th_err <= 0.5;
    f.verdicts.push_back({m, ok ? Verdict::kYes : Verdict::kNo,
                          "peak " + formatNumber("%.1f", peak) + " deg/s at t = " + formatNumber("%.4f", t[ip]) + " s (expected " +
                              formatNumber("%.1f", want_peak) + " deg/s at " + formatNumber("%.4f", want_t) + " s; tolerance 1 %, " +
                              formatNumber("%.4f", std::max(2.0 * dt, 0.02 * dT)) + " s); theta " + formatNumber("%.2f", th_start) +
                              " -> " + formatNumber("%.2f", th_end) + " deg (expected " + formatNumber("%.2f", th0) + " -> " +
                              formatNumber("%.2f", th0 + dth) + ", tolerance 0.5 deg)"});
  }
  return f;
}

Finding fig07Phases(const std::vector<ExperimentResults>& all) {
  Finding f{"fig07_phases", "Sec. 4.3, Fig. 7",
            "phases A-D: (A) M_zT > 0 from the start and the body turns positive; (B, C) phidot then changes sign, "
            "the body turns back; (D) after the tail stops the body comes to rest (|phidot| < 0.01 deg/s at the end)",
            {}};
  const ExperimentResults* r = findExperiment(all, "fig07");
  for (const std::string& m : modelsOf(r)) {
    if (!r) { f.verdicts.push_back(na(m, "fig07 not in the results")); continue; }
    if (!r->hasModel(m)) { f.verdicts.push_back(na(m, notRun(*r, m))); continue; }
    TimeSeries s;
    try {
      s = r->series(r->cases.front(), m);
    } catch (const std::exception& e) {
      f.verdicts.push_back(na(m, e.what()));
      continue;
    }
    if (!s.has(col::kT) || !s.has(col::kPhidot) || !s.has(col::kMzT) || s.numRows() < 3) {
      f.verdicts.push_back(na(m, "CSV lacks t_s, phidot_dps, MzT_Nm"));
      continue;
    }
    const auto& t = s.values(col::kT);
    const auto& w = s.values(col::kPhidot);
    const auto& mz = s.values(col::kMzT);
    size_t imax = 0, imin = 0, first_neg_mz = mz.size();
    for (size_t i = 0; i < w.size(); ++i) {
      if (w[i] > w[imax]) imax = i;
      if (first_neg_mz == mz.size() && mz[i] < 0) first_neg_mz = i;
    }
    for (size_t i = imax; i < w.size(); ++i)
      if (w[i] < w[imin] || imin < imax) imin = i;
    // A: M_zT positive from the first sample that is not zero until it first turns negative,
    // and the body's speed peaks positive inside that stretch or right after.
    size_t first_pos_mz = 0;
    while (first_pos_mz < mz.size() && std::fabs(mz[first_pos_mz]) < 1e-12) ++first_pos_mz;
    const bool a = first_pos_mz < mz.size() && mz[first_pos_mz] > 0 && w[imax] > 0;
    const bool bc = w[imin] < 0 && imin > imax;
    const bool d = std::fabs(w.back()) < 0.01;
    const std::string tneg = first_neg_mz < mz.size() ? formatNumber("%.3f", t[first_neg_mz]) + " s" : std::string("never");
    f.verdicts.push_back({m, a && bc && d ? Verdict::kYes : Verdict::kNo,
                          std::string("A ") + (a ? "yes" : "no") + " (M_zT > 0 until " + tneg + ", phidot peaks at " +
                              formatNumber("%+.1f", w[imax]) + " deg/s at " + formatNumber("%.3f", t[imax]) + " s); B-C " +
                              (bc ? "yes" : "no") + " (phidot reaches " + formatNumber("%+.1f", w[imin]) + " deg/s at " +
                              formatNumber("%.3f", t[imin]) + " s); D " + (d ? "yes" : "no") + " (phidot at the end " +
                              formatNumber("%+.2g", w.back()) + " deg/s, t = " + formatNumber("%.3f", t.back()) + " s)"});
  }
  return f;
}

Finding eq25(const std::vector<ExperimentResults>& all) {
  Finding f{"eq25_table", "Sec. 4.7, Eq. (25)",
            "with thetadot_max = 600 deg/s, n = 1..6 gives dtheta = -180, -120, -90, -72, -60, -51.43 deg and "
            "dT = 0.600, 0.400, 0.300, 0.240, 0.200, 0.171 s (measured on every joint: start/end angle and peak "
            "speed; dT implied = 2|dtheta|/peak)",
            {}};
  const ExperimentResults* r = findExperiment(all, "fig14");
  for (const std::string& m : modelsOf(r)) {
    if (!r) { f.verdicts.push_back(na(m, "fig14 not in the results")); continue; }
    const SweepAxis* a = findAxis(*r, "links");
    if (!a) { f.verdicts.push_back(na(m, "fig14 has no sweep over links")); continue; }
    if (!r->hasModel(m)) { f.verdicts.push_back(na(m, notRun(*r, m))); continue; }
    bool ok = true;
    double worst_angle = 0, worst_speed = 0;
    std::string d;
    for (size_t i = 0; i < a->values.size(); ++i) {
      const int n = static_cast<int>(std::lround(a->number(i)));
      const CaseRecord* c = r->find({{a->key, a->values[i]}});
      TimeSeries s;
      try {
        if (!c) throw std::runtime_error("missing case");
        s = r->series(*c, m);
      } catch (const std::exception&) {
        ok = false;
        d += (d.empty() ? "" : "; ") + ("n=" + a->values[i] + ": no data");
        continue;
      }
      // The peak speed the case was given (Eq. 25 makes it the same on every joint): 2|dtheta|/dT of
      // joint 1 as run; the paper's table below is checked against it.
      const ExperimentCase* rc = r->resolvedCase(*c);
      if (!rc || rc->joints.empty()) {
        ok = false;
        d += (d.empty() ? "" : "; ") + ("n=" + a->values[i] + ": " + unresolved(*r));
        continue;
      }
      const double vmax = units::degrees(2.0 * std::fabs(rc->joints.front().dtheta_rad) / rc->joints.front().dT_s);
      const double want = 360.0 / (n + 1);  // |dtheta|; theta goes +want/2 -> -want/2
      double dth1 = kNaN, peak1 = kNaN;
      for (int j = 1; j <= n; ++j) {
        const std::string th = col::theta(j), thd = col::thetadot(j);
        if (!s.has(th) || !s.has(thd) || s.numRows() == 0) { ok = false; continue; }
        const double a0 = s.values(th).front(), a1 = s.values(th).back();
        const double pk = peakAbs(s, thd).second;
        worst_angle = std::max({worst_angle, std::fabs(a0 - want / 2), std::fabs(a1 + want / 2)});
        worst_speed = std::max(worst_speed, std::fabs(pk - vmax) / vmax);
        if (j == 1) dth1 = a1 - a0, peak1 = pk;
      }
      d += (d.empty() ? "" : "; ") + ("n=" + std::to_string(n) + ": dtheta " + formatNumber("%.2f", dth1) + " deg, dT " +
                                      formatNumber("%.3f", 2.0 * std::fabs(dth1) / peak1) + " s");
    }
    ok = ok && worst_angle <= 0.5 && worst_speed <= 0.01;
    f.verdicts.push_back({m, ok ? Verdict::kYes : Verdict::kNo,
                          d + " (worst joint angle error " + formatNumber("%.3f", worst_angle) + " deg, worst peak-speed error " +
                              formatNumber("%.2f", 100 * worst_speed) + " %; tolerance 0.5 deg, 1 %)"});
  }
  return f;
}

// One model's fig08 poses: theta and the tangential, centripetal and total tail moments as run,
// and Eq. (24) from the analytic model's code with each pose's robot and rates (when it applies).
struct Fig08Poses {
  bool cols = true;  // every pose's CSV read, with MzT_tan_Nm and MzT_cen_Nm
  std::vector<double> th, tan, cen, tot;
  std::vector<Eq24Terms> want;
  std::string why_no_eq24;
  double Ieff = kNaN, d_Q2B = kNaN;
};

// Stage 1 of fig08Findings: model m's poses over the theta axis a.
Fig08Poses readFig08Poses(const ExperimentResults& r, const SweepAxis& a, const std::string& m) {
  Fig08Poses p;
  for (size_t i = 0; i < a.values.size(); ++i) {
    const CaseRecord* c = r.find({{a.key, a.values[i]}});
    try {
      if (!c) throw std::runtime_error("missing");
      const TimeSeries s = r.series(*c, m);
      if (!s.has(col::kMzTTan) || !s.has(col::kMzTCen) || s.numRows() == 0) { p.cols = false; break; }
      p.th.push_back(units::radians(a.number(i)));
      const ExperimentCase* rc = r.resolvedCase(*c);
      if (!rc) p.why_no_eq24 = unresolved(r);
      else if (rc->robot.numLinks() != 1 || rc->pose.theta_rad.size() != 1)
        p.why_no_eq24 = "Eq. (24) is for a one-link tail; case " + c->name + " has " +
                        std::to_string(rc->robot.numLinks()) + " links";
      else {
        p.want.push_back(eq24OneLinkMoment(rc->robot, rc->pose.theta_rad[0], rc->pose.thetadot_radps[0],
                                           rc->pose.thetaddot_radps2[0]));
        p.Ieff = eq24OneLinkMoment(rc->robot, 0, 0, -1).tangential;  // -Ieff thetaddot cos(theta) at 0, -1
        p.d_Q2B = rc->robot.quadruped.d_Q2B_m;
      }
      p.tan.push_back(s.values(col::kMzTTan)[0]);
      p.cen.push_back(s.values(col::kMzTCen)[0]);
      p.tot.push_back(s.has(col::kMzT) ? s.values(col::kMzT)[0] : kNaN);
    } catch (const std::exception&) {
      p.cols = false;
      break;
    }
  }
  return p;
}

// Stage 2: Fig. 8's peaks, |M_zT,tan| largest at theta = 0 and |M_zT,cen| at theta = +-90 deg.
ModelVerdict fig08PeaksVerdict(const std::string& m, const Fig08Poses& p, const SweepAxis& a) {
  auto argmaxAbs = [](const std::vector<double>& v) {
    size_t b = 0;
    for (size_t i = 1; i < v.size(); ++i)
      if (std::fabs(v[i]) > std::fabs(v[b])) b = i;
    return b;
  };
  const size_t it = argmaxAbs(p.tan), ic = argmaxAbs(p.cen);
  const double th_t = units::degrees(p.th[it]), th_c = units::degrees(p.th[ic]);
  // |cen| is symmetric: both ends count; tolerate ties within 1e-9 relative.
  const bool cen_ok = std::fabs(std::fabs(th_c) - 90) < 1e-6 ||
                      std::fabs(std::fabs(p.cen[ic]) - std::max(std::fabs(p.cen.front()), std::fabs(p.cen.back()))) <=
                          1e-9 * std::fabs(p.cen[ic]);
  const bool tan_ok = std::fabs(th_t) < 1e-6;
  return {m, tan_ok && cen_ok ? Verdict::kYes : Verdict::kNo,
          "max |M_zT,tan| = " + formatNumber("%.4g", std::fabs(p.tan[it])) + " N m at theta = " +
              formatNumber("%.1f", th_t) + " deg; max |M_zT,cen| = " + formatNumber("%.4g", std::fabs(p.cen[ic])) +
              " N m at theta = " + formatNumber("%.1f", th_c) + " deg (grid " + a.values.front() + " .. " +
              a.values.back() + " deg)"};
}

// Stage 3: the moments as run against Eq. (24), relative to its largest term (tolerance 1e-6).
ModelVerdict eq24Verdict(const std::string& m, const Fig08Poses& p) {
  double err = 0, scale = 1e-12;
  bool have_total = true;
  for (size_t i = 0; i < p.th.size(); ++i) {
    const double wt = p.want[i].tangential, wc = p.want[i].centripetal, rot = p.want[i].rotational;
    err = std::max({err, std::fabs(p.tan[i] - wt), std::fabs(p.cen[i] - wc)});
    scale = std::max({scale, std::fabs(wt), std::fabs(wc), std::fabs(rot)});
    if (std::isfinite(p.tot[i])) err = std::max(err, std::fabs(p.tot[i] - p.want[i].total()));
    else have_total = false;
  }
  const double rel = err / scale;
  return {m, rel <= 1e-6 ? Verdict::kYes : Verdict::kNo,
          "max deviation from Eq. (24) " + formatNumber("%.3g", err) + " N m = " + formatNumber("%.2g", rel) +
              " of the largest term (I_eff = " + formatNumber("%.5g", p.Ieff) + " kg m^2, d_Q2B = " +
              formatNumber("%.4g", p.d_Q2B) + " m; " + std::to_string(p.th.size()) + " poses" +
              (have_total ? ", tangential, centripetal and total" : ", tangential and centripetal") +
              "; tolerance 1e-6)"};
}

std::vector<Finding> fig08Findings(const std::vector<ExperimentResults>& all) {
  Finding eq{"eq24_closed_form", "Sec. 4.4, Eq. (24)",
             "for the 1-link tail the general recursion reduces to M_zT = -(I_zz,L + 0.25 m_L L_L^2 m_Q/m) thetaddot "
             "- I_eff thetaddot cos(theta) + I_eff thetadot^2 sin(theta), I_eff = m_Q m_L L_L d_Q2B / (2 m) "
             "(fig08 poses)",
             {}};
  Finding peaks{"fig08_peaks", "Sec. 4.4, Fig. 8",
                "|M_zT,tan| is largest at theta = 0 and |M_zT,cen| at theta = +-90 deg", {}};
  const ExperimentResults* r = findExperiment(all, "fig08");
  for (const std::string& m : modelsOf(r)) {
    if (!r) {
      eq.verdicts.push_back(na(m, "fig08 not in the results"));
      peaks.verdicts.push_back(na(m, "fig08 not in the results"));
      continue;
    }
    const SweepAxis* a = findAxis(*r, "theta_deg");
    if (!a) a = findAxis(*r, "theta_deg[1]");
    if (!a || !r->hasModel(m)) {
      const std::string why = !a ? "fig08 has no sweep over theta_deg" : notRun(*r, m);
      eq.verdicts.push_back(na(m, why));
      peaks.verdicts.push_back(na(m, why));
      continue;
    }
    const Fig08Poses p = readFig08Poses(*r, *a, m);
    if (!p.cols || p.th.empty()) {
      eq.verdicts.push_back(na(m, "pose CSVs missing or without MzT_tan_Nm / MzT_cen_Nm"));
      peaks.verdicts.push_back(na(m, "pose CSVs missing or without MzT_tan_Nm / MzT_cen_Nm"));
      continue;
    }
    peaks.verdicts.push_back(fig08PeaksVerdict(m, p, *a));
    if (!p.why_no_eq24.empty() || p.want.size() != p.th.size()) eq.verdicts.push_back(na(m, p.why_no_eq24));
    else eq.verdicts.push_back(eq24Verdict(m, p));
  }
  return {eq, peaks};
}

Finding modelComparison(const std::vector<ExperimentResults>& all) {
  Finding f{"fig06_contact_rotates_more", "Sec. 4.2, Fig. 6",
            "the contact model (ADAMS there, MuJoCo here) rotates more than the stiction model, for the 1- and the "
            "6-link tail",
            {}};
  std::string d;
  int yes = 0, have = 0, panels = 0;
  for (const char* prefix : {"fig06a", "fig06b"}) {
    const ExperimentResults* r = findExperiment(all, prefix);
    if (!r) continue;
    ++panels;
    const double a = r->cases.empty() ? kNaN : r->phiNet(r->cases.front(), kAnalyticModel);
    const double mj = r->cases.empty() ? kNaN : r->phiNet(r->cases.front(), kMujocoModel);
    d += (d.empty() ? "" : "; ") + r->name + ": analytic " +
         (std::isfinite(a) ? signedDeg(a) : std::string("n/a")) + ", MuJoCo " +
         (std::isfinite(mj) ? signedDeg(mj) : std::string("n/a"));
    if (std::isfinite(a) && std::isfinite(mj)) {
      ++have;
      if (std::fabs(mj) > std::fabs(a)) ++yes;
    }
  }
  if (!panels) f.verdicts.push_back(na("mujoco vs analytic", "fig06a/fig06b not in the results"));
  else if (!have) f.verdicts.push_back(na("mujoco vs analytic", "no panel has both models: " + d));
  else
    f.verdicts.push_back({"mujoco vs analytic", yes == have ? Verdict::kYes : Verdict::kNo,
                          "|phi_net| larger for MuJoCo in " + std::to_string(yes) + " of " + std::to_string(have) +
                              " panels (" + d + ")"});
  return f;
}

Finding argmax60(const std::vector<ExperimentResults>& all) {
  Finding f{"fig09_max_at_60", "Sec. 4.4, Fig. 9",
            "over theta0 in [0, 90] deg the maximum phi_net sits mostly at theta0 = 60 deg (counted over d_Q2B > 0)",
            {}};
  const ExperimentResults* r = findExperiment(all, "fig09");
  for (const std::string& m : modelsOf(r)) {
    if (!r) { f.verdicts.push_back(na(m, "fig09 not in the results")); continue; }
    const SweepAxis* th = findAxis(*r, "theta0_deg");
    const SweepAxis* d = findAxis(*r, "d_Q2B_m");
    if (!th || !d) { f.verdicts.push_back(na(m, "fig09 does not sweep theta0_deg and d_Q2B_m")); continue; }
    if (!r->hasModel(m)) { f.verdicts.push_back(na(m, notRun(*r, m))); continue; }
    int at60 = 0, counted = 0;
    std::string list;
    for (size_t j = 0; j < d->values.size(); ++j) {
      if (d->number(j) <= 0) continue;
      const std::vector<double> y = phiAlong(*r, *th, ascending(*th), m, {{d->key, d->values[j]}});
      size_t b = 0;
      bool finite = std::isfinite(y[0]);
      for (size_t i = 1; i < y.size(); ++i) {
        finite = finite && std::isfinite(y[i]);
        if (y[i] > y[b]) b = i;
      }
      if (!finite) continue;
      ++counted;
      if (std::fabs(th->number(b) - 60) < 1e-9) ++at60;
      list += (list.empty() ? "" : ", ") + ("d_Q2B " + d->values[j] + ": " + th->values[b] + " deg (" +
                                            formatNumber("%.2f", y[b]) + ")");
    }
    if (!counted) { f.verdicts.push_back({m, Verdict::kNo, "no complete theta0 row"}); continue; }
    f.verdicts.push_back({m, 2 * at60 > counted ? Verdict::kYes : Verdict::kNo,
                          "argmax at 60 deg for " + std::to_string(at60) + " of " + std::to_string(counted) +
                              " d_Q2B values; argmax theta0 (phi_net deg): " + list});
  }
  return f;
}

Finding lfVariation(const std::vector<ExperimentResults>& all) {
  Finding f{"fig10_LF_variation", "Sec. 4.4, Fig. 10",
            "L_F varies less than 3 % from its median over theta and d_Q2B (max |L_F - median| / median)", {}};
  const ExperimentResults* r = findExperiment(all, "fig10");
  for (const std::string& m : modelsOf(r)) {
    if (!r) { f.verdicts.push_back(na(m, "fig10 not in the results")); continue; }
    if (!r->hasModel(m)) { f.verdicts.push_back(na(m, notRun(*r, m))); continue; }
    std::vector<std::pair<double, const CaseRecord*>> lf;
    for (const CaseRecord& c : r->cases) {
      try {
        const TimeSeries s = r->series(c, m);
        if (s.has(col::kLF) && s.numRows() > 0 && std::isfinite(s.values(col::kLF)[0]))
          lf.emplace_back(s.values(col::kLF)[0], &c);
      } catch (const std::exception&) {
      }
    }
    if (lf.empty()) { f.verdicts.push_back(na(m, "no L_F values (LF_m column) in the pose CSVs")); continue; }
    std::vector<double> v;
    for (const auto& x : lf) v.push_back(x.first);
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    const double median = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    double worst = 0;
    const CaseRecord* wc = nullptr;
    for (const auto& [x, c] : lf)
      if (std::fabs(x - median) / median >= worst) worst = std::fabs(x - median) / median, wc = c;
    f.verdicts.push_back({m, worst < 0.03 ? Verdict::kYes : Verdict::kNo,
                          "max variation " + formatNumber("%.2f", 100 * worst) + " % (at " + (wc ? wc->name : "?") +
                              "); median L_F " + formatNumber("%.2f", 1e3 * median) + " mm, range " + formatNumber("%.2f", 1e3 * v.front()) +
                              " .. " + formatNumber("%.2f", 1e3 * v.back()) + " mm over " + std::to_string(n) + " poses" +
                              (n < r->cases.size() ? " (" + std::to_string(r->cases.size() - n) + " missing)" : "")});
  }
  return f;
}

}  // namespace

const char* verdictText(Verdict v) {
  switch (v) {
    case Verdict::kYes: return "YES";
    case Verdict::kNo: return "NO";
    default: return "n/a";
  }
}

const ModelVerdict* Finding::verdictFor(const std::string& model) const {
  for (const ModelVerdict& v : verdicts)
    if (v.model == model) return &v;
  return nullptr;
}

Trend checkTrend(const std::vector<double>& y, int direction, double tol, bool zero_plateaus_ok) {
  Trend t;
  t.complete = !y.empty() && std::all_of(y.begin(), y.end(), [](double v) { return std::isfinite(v); });
  if (!t.complete || y.size() < 2) {
    t.holds = false;
    return t;
  }
  t.min_step = std::numeric_limits<double>::infinity();
  bool any = false;
  for (size_t i = 0; i + 1 < y.size(); ++i) {
    if (zero_plateaus_ok && std::fabs(y[i]) <= tol && std::fabs(y[i + 1]) <= tol) {
      ++t.zero_plateaus;
      continue;
    }
    any = true;
    const double step = direction * (y[i + 1] - y[i]);
    if (step < t.min_step) t.min_step = step, t.worst = i;
  }
  if (!any) t.min_step = 0.0;  // all flat at zero: nothing rises
  t.holds = any && t.min_step > tol;
  return t;
}

const ExperimentResults* findExperiment(const std::vector<ExperimentResults>& results, const std::string& prefix) {
  for (const ExperimentResults& r : results)
    if (r.name.compare(0, prefix.size(), prefix) == 0) return &r;
  return nullptr;
}

const SweepAxis* findAxis(const ExperimentResults& r, const std::string& leaf) {
  for (const SweepAxis& a : r.axes)
    if (leafKey(a.key) == leaf) return &a;
  return nullptr;
}

std::vector<Finding> computeFindings(const std::vector<ExperimentResults>& all) {
  std::vector<Finding> out;
  out.push_back(splitCycle(all));
  out.push_back(eq25(all));
  out.push_back(fig07Phases(all));
  for (Finding& f : fig08Findings(all)) out.push_back(std::move(f));
  out.push_back(modelComparison(all));

  Finding rises{"fig09_dQ2B_rises", "Sec. 4.4, Fig. 9", "phi_net rises with d_Q2B at every theta0", {}};
  twoAxisTrend(rises, findExperiment(all, "fig09"), "d_Q2B_m", false, +1, "theta0_deg");
  out.push_back(rises);
  out.push_back(argmax60(all));
  out.push_back(lfVariation(all));

  Finding wss{"fig11_wss_falls", "Sec. 4.5, Fig. 11", "phi_net falls as w_ss rises from 0.1 to 0.9", {}};
  oneAxisTrend(wss, findExperiment(all, "fig11"), "w_ss", false, -1, "falling");
  out.push_back(wss);

  Finding dth{"fig12_dtheta_rises", "Sec. 4.6, Fig. 12", "phi_net rises with |dtheta| (at every dT)", {}};
  twoAxisTrend(dth, findExperiment(all, "fig12"), "dtheta_deg", true, +1, "dT_s");
  out.push_back(dth);
  Finding dT{"fig12_dT_falls", "Sec. 4.6, Fig. 12", "phi_net rises with 1/dT, i.e. falls as dT grows (at every dtheta)",
             {}};
  twoAxisTrend(dT, findExperiment(all, "fig12"), "dT_s", false, -1, "dtheta_deg");
  out.push_back(dT);

  Finding f13{"fig13_larger_dtheta_wins", "Sec. 4.6, Fig. 13",
              "at a fixed peak joint speed of 600 deg/s the larger |dtheta| (with the longer dT) gives the larger "
              "phi_net",
              {}};
  oneAxisTrend(f13, findExperiment(all, "fig13"), "dtheta_deg", true, +1, "rising");
  out.push_back(f13);

  Finding f14{"fig14_links_rises", "Sec. 4.7, Fig. 14", "phi_net rises with the number of tail links n", {}};
  oneAxisTrend(f14, findExperiment(all, "fig14"), "links", false, +1, "rising");
  out.push_back(f14);

  static const std::map<std::string, std::string> briefs = {
      {"split_cycle_peak", "split-cycle peak speed 2|dtheta|/dT at t0 + w_ss dT"},
      {"eq25_table", "Eq. (25) dtheta and dT for n = 1..6"},
      {"fig07_phases", "phases A-D: turn, turn back, come to rest"},
      {"eq24_closed_form", "recursion reduces to Eq. (24) for n = 1"},
      {"fig08_peaks", "|M_tan| peaks at theta = 0, |M_cen| at +-90 deg"},
      {"fig06_contact_rotates_more", "contact model rotates more than stiction model"},
      {"fig09_dQ2B_rises", "phi_net rises with d_Q2B at every theta0"},
      {"fig09_max_at_60", "max phi_net mostly at theta0 = 60 deg"},
      {"fig10_LF_variation", "L_F within 3 % of its median"},
      {"fig11_wss_falls", "phi_net falls as w_ss rises"},
      {"fig12_dtheta_rises", "phi_net rises with |dtheta|"},
      {"fig12_dT_falls", "phi_net rises as dT falls"},
      {"fig13_larger_dtheta_wins", "at 600 deg/s peak speed, larger |dtheta| wins"},
      {"fig14_links_rises", "phi_net rises with tail links n"}};
  for (Finding& f : out)
    if (auto it = briefs.find(f.id); it != briefs.end()) f.brief = it->second;
  return out;
}

}  // namespace tailsim
