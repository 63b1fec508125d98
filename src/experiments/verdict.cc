#include "experiments/verdict.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace tailsim {

namespace {

bool contains(const std::string& s, const char* what) { return s.find(what) != std::string::npos; }

bool uncertainWarning(const RunSummary& s) {
  return std::any_of(s.warnings.begin(), s.warnings.end(), [](const std::string& w) {
    return w.compare(0, sizeof kUncertainWarning - 1, kUncertainWarning) == 0;
  });
}

std::string fmt(const char* f, double x) {
  char b[64];
  std::snprintf(b, sizeof b, f, x);
  return b;
}

struct Entry {
  const RunSummary* run;
  const char* title;
  bool fell;
};

bool isMujoco(const RunSummary& r) { return r.model == "mujoco"; }

// A standing model's result as the verdict quotes it: "+- U" only for an estimate the run made.
std::string quote(const Entry& e) {
  std::string s = std::string(e.title) + " " + fmt("%+.3f", e.run->phi_net_deg);
  const double u = ownUncertaintyDeg(*e.run);
  if (std::isfinite(u)) return s + " +- " + fmt("%.3f", u);
  if (!isMujoco(*e.run)) return s;
  return s + (e.run->extra.count("phi_net_uncertainty_deg") ? " (uncertainty not estimated: its check run failed)"
                                                              : " (uncertainty not estimated)");
}

std::string join(const std::vector<const Entry*>& v) {
  std::string s;
  for (size_t i = 0; i < v.size(); ++i) s += (i == 0 ? "" : i + 1 == v.size() ? " and " : ", ") + std::string(v[i]->title);
  return s;
}

// What the agreement test used for each model: its own estimate or the floor.
std::string toleranceNote(const std::vector<Entry>& e) {
  std::vector<const Entry*> own, floor;
  bool mujocoFloor = false;
  for (const Entry& x : e) {
    const bool has = std::isfinite(ownUncertaintyDeg(*x.run));
    (has ? own : floor).push_back(&x);
    mujocoFloor = mujocoFloor || (!has && isMujoco(*x.run));
  }
  std::string s = "; tolerance, the sum of two models' uncertainties: ";
  if (!own.empty()) s += join(own) + (own.size() == 1 ? " its own estimate" : " their own estimates");
  if (!floor.empty())
    s += (own.empty() ? "" : "; ") + join(floor) + " none estimated, the floor " +
         fmt("%g", 100.0 * kUncertaintyFloorShare) + " % of max(|phi_net|, " + fmt("%g", kUncertaintyFloorDeg) + " deg)";
  if (mujocoFloor)
    s += " (MuJoCo's error was not estimated, mujoco.uncertainty false or its check run failed: the floor is the "
         "least it could be)";
  return s;
}

// Which ladder step a gap between two adjacent models belongs to.
// articulated: MuJoCo ran the user's robot from its model file (legs and all), not the rigid box.
const char* ladderStep(const std::string& a, const std::string& b, bool articulated) {
  if (a == "perfoot" && b == "mujoco" && articulated)
    return "the articulated robot (MuJoCo ran the model file's robot: its legs on their servos, its feet, MuJoCo's "
           "soft contact and the body's tilt, against the planar models' rigid body on Coulomb feet)";
  if (a == "analytic" && b == "perfoot")
    return "coupling and per-foot friction (the ladder's first steps: one friction moment for the whole body and "
           "the analytic coupling against Coulomb friction at each foot)";
  if (a == "perfoot" && b == "mujoco")
    return "contact model (the ladder's contact step: MuJoCo's soft contact, its load distribution and tilt, "
           "against rigid Coulomb feet)";
  return "coupling, per-foot friction and contact model together (run the perfoot model too to split the gap)";
}

}  // namespace

double ownUncertaintyDeg(const RunSummary& run) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (!run.ok || !std::isfinite(run.phi_net_deg)) return nan;
  const auto it = run.extra.find("phi_net_uncertainty_deg");
  return it != run.extra.end() && std::isfinite(it->second) ? it->second : nan;
}

double phiUncertaintyDeg(const RunSummary& run) {
  if (!run.ok || !std::isfinite(run.phi_net_deg)) return std::numeric_limits<double>::quiet_NaN();
  const double own = ownUncertaintyDeg(run);
  return std::isfinite(own) ? own : kUncertaintyFloorShare * std::max(std::abs(run.phi_net_deg), kUncertaintyFloorDeg);
}

std::string caseVerdict(const std::vector<RunSummary>& runs) {
  static const std::pair<const char*, const char*> kOrder[] = {
      {"analytic", "analytic"}, {"perfoot", "per-foot"}, {"mujoco", "MuJoCo"}};
  std::vector<Entry> e;
  for (const auto& [name, title] : kOrder)
    for (const RunSummary& r : runs)
      if (r.model == name)
        e.push_back({&r, title, !r.ok && (contains(r.error, kPlanarTipText) || contains(r.error, kMujocoFallText))});
  if (e.size() < 2) return {};
  for (const Entry& x : e)
    if (!x.run->ok && !x.fell) return std::string("no-verdict: ") + x.title + " failed without falling over";

  std::vector<const Entry*> fallen, standing;
  for (const Entry& x : e) (x.fell ? fallen : standing).push_back(&x);
  const Entry* mj = nullptr;
  for (const Entry& x : e)
    if (x.run->model == "mujoco") mj = &x;
  const bool articulated = mj && mj->run->extra.count("stand_max_tilt_from_stance_deg");
  if (standing.empty()) return "fall: every model sees the robot fall (" + join(fallen) + ")";
  if (!fallen.empty()) {
    std::string s = "falls: " + join(fallen) + (fallen.size() == 1 ? " falls, " : " fall, ") + join(standing) +
                    (standing.size() == 1 ? " stands" : " stand");
    double tilt = std::numeric_limits<double>::quiet_NaN();
    if (mj)
      for (const char* key : {"max_tilt_deg", "stroke_max_tilt_from_stance_deg"})  // the rigid box's, the articulated run's
        if (const auto it = mj->run->extra.find(key); it != mj->run->extra.end() && !std::isfinite(tilt)) tilt = it->second;
    if (mj && mj->fell) {
      s += ": dynamic load transfer (the tail's inertial loads rock the robot onto two feet and over while the "
           "planar models' support check, the system COM or the centre of pressure of a rigid body that cannot "
           "tilt, stays inside the support rectangle)";
    } else if (mj) {
      s += " (MuJoCo's largest tilt " + (std::isfinite(tilt) ? fmt("%.2f", tilt) : std::string("n/a")) +
           " deg): support margin (the planar check fails the moment the system COM or the centre of pressure "
           "crosses the support edge; MuJoCo's body tilts and comes back before the max_tilt_deg limit)";
      if (uncertainWarning(*mj->run))
        s += "; but MuJoCo's own result is uncertain (its warning says why: a near fall, a failed check run, or "
             "its uncertainty beyond mujoco.uncertainty_warn_share), so a converged MuJoCo run may see it fall too";
    } else {
      s += ": support margin (the analytic model checks the system COM, the per-foot model with load transfer the "
           "centre of pressure shifted by the friction forces)";
    }
    return s;
  }

  // Everyone stands: adjacent rungs compared within the sum of their uncertainties.
  auto agree = [](const Entry& a, const Entry& b) {
    return std::abs(a.run->phi_net_deg - b.run->phi_net_deg) <= phiUncertaintyDeg(*a.run) + phiUncertaintyDeg(*b.run);
  };
  std::string gaps;
  for (size_t i = 0; i + 1 < e.size(); ++i) {
    const Entry &a = e[i], &b = e[i + 1];
    if (agree(a, b)) continue;
    const double d = a.run->phi_net_deg - b.run->phi_net_deg;
    gaps += std::string(gaps.empty() ? "" : "; ") + a.title + " - " + b.title + " = " + fmt("%+.3f", d) + " deg (" +
            fmt("%.1f", 100.0 * std::abs(d) / std::max(std::abs(b.run->phi_net_deg), kUncertaintyFloorDeg)) +
            " %): " + ladderStep(a.run->model, b.run->model, articulated);
  }
  if (gaps.empty() && !agree(e.front(), e.back()))
    gaps = std::string(e.front().title) + " - " + e.back().title + " = " +
           fmt("%+.3f", e.front().run->phi_net_deg - e.back().run->phi_net_deg) +
           " deg, although each step between them is within the uncertainties";
  std::string values;
  for (const Entry& x : e) values += (values.empty() ? "" : ", ") + quote(x);
  std::string s = (gaps.empty() ? "agree: " + values + " deg" : "differ: " + gaps + " [" + values + " deg]") +
                  toleranceNote(e);
  if (mj && uncertainWarning(*mj->run))
    s = "uncertain: MuJoCo's result is uncertain (its warning says why: its own uncertainty beyond "
        "mujoco.uncertainty_warn_share, a failed check run, or a near fall); " + s;
  return s;
}

}  // namespace tailsim
