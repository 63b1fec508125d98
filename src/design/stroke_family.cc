#include "design/stroke_family.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "models/planar/tail_dynamics.h"
#include "common/units.h"

namespace tailsim {
namespace {
double clamp01(double v) { return std::isfinite(v) ? std::min(1.0, std::max(0.0, v)) : 0.5; }
double lerp(double lo, double hi, double u) { return lo + clamp01(u) * (hi - lo); }
double unlerp(double lo, double hi, double v) { return hi > lo ? clamp01((v - lo) / (hi - lo)) : 0.0; }
}  // namespace

int StrokeSpace::dimPerJoint() const {
  // split-cycle: start, end, speed share, w_ss, t0; spline: start, K knots, (end), dT, t0.
  if (family == StrokeFamily::kSplitCycle) return 5;
  return 1 + knots + (limits.end == StrokeEnd::kAtRest ? 1 : 0) + 2;
}

TailTrajectory StrokeSpace::trajectory(const std::vector<double>& x) const { return trajectory(x, nullptr, nullptr); }

TailTrajectory StrokeSpace::trajectory(const std::vector<double>& x, StrokeFigures* figures, bool* have_figures) const {
  if (static_cast<int>(x.size()) != dim()) throw std::invalid_argument("stroke point has the wrong size");
  const StrokeLimits& L = limits;
  TailTrajectory t;
  const int d = dimPerJoint();
  for (int i = 0; i < n_links; ++i) {
    const double* u = x.data() + static_cast<std::ptrdiff_t>(i) * d;
    const JointLimits J = L.joint(static_cast<std::size_t>(i));
    if (family == StrokeFamily::kSplitCycle) {
      SplitCycleParams p;
      p.theta0_rad = lerp(J.theta_min_rad, J.theta_max_rad, u[0]);
      const int dir = directions.empty() ? 0 : directions.at(static_cast<std::size_t>(i));
      const double end = dir > 0   ? lerp(p.theta0_rad, J.theta_max_rad, u[1])
                         : dir < 0 ? lerp(p.theta0_rad, J.theta_min_rad, u[1])
                                   : lerp(J.theta_min_rad, J.theta_max_rad, u[1]);
      p.dtheta_rad = end - p.theta0_rad;
      // Peak speed 2 |dtheta| / dT (Eq. 23) as a share of the limit: speed kept by construction
      // unless the duration range clips dT.
      const double share = lerp(0.05, 1.0, u[2]);
      p.dT_s = std::min(L.dT_max_s, std::max(L.dT_min_s, 2.0 * std::abs(p.dtheta_rad) / (share * J.thetadot_max_radps)));
      p.w_ss = lerp(L.w_ss_min, L.w_ss_max, u[3]);
      p.t0_s = lerp(0.0, L.t0_max_s, u[4]);
      t.joints.emplace_back(p);
    } else {
      SplineParams s;
      int k = 0;
      for (; k < 1 + knots; ++k) s.knots_rad.push_back(lerp(J.theta_min_rad, J.theta_max_rad, u[k]));
      if (L.end == StrokeEnd::kAtRest) s.knots_rad.push_back(lerp(J.theta_min_rad, J.theta_max_rad, u[k++]));
      else s.knots_rad.push_back(s.knots_rad.front());
      s.dT_s = lerp(L.dT_min_s, L.dT_max_s, u[k++]);
      s.t0_s = lerp(0.0, L.t0_max_s, u[k++]);
      t.joints.emplace_back(s);
    }
  }
  if (have_figures) *have_figures = slow_down_over_torque && figures;
  return slow_down_over_torque ? slowedToTorqueLimit(tail, limits, t, figures) : t;
}

TailTrajectory timeScaled(const TailTrajectory& traj, double k) {
  TailTrajectory out;
  for (const JointProfile& j : traj.joints) {
    if (j.isSpline()) {
      SplineParams s = j.spline();
      s.dT_s /= k;
      s.t0_s /= k;
      out.joints.emplace_back(s);
    } else {
      SplitCycleParams p = j.params();
      p.dT_s /= k;
      p.t0_s /= k;
      out.joints.emplace_back(p);
    }
  }
  return out;
}

namespace {
// strokeFigures' sample times of traj: the grid t = k dt covering the stroke, plus every breakpoint, sorted.
std::vector<double> sampleTimes(const TailTrajectory& traj, double dt) {
  const double t_a = traj.startTime(), t_b = traj.endTime();
  std::vector<double> ts;
  for (long k = static_cast<long>(std::floor(t_a / dt)); k * dt <= t_b + dt; ++k) ts.push_back(k * dt);
  for (double b : traj.breakpoints()) ts.push_back(b);
  std::sort(ts.begin(), ts.end());
  return ts;
}

// strokeFigures, with onSample(t, tau) called at every sample (the joint torques there).
template <typename OnSample>
StrokeFigures sampledFigures(const std::vector<TailLink>& links, const TailTrajectory& traj, double dt, OnSample onSample) {
  StrokeFigures f;
  const double t_a = traj.startTime(), t_b = traj.endTime();
  const std::vector<double> ts = sampleTimes(traj, dt);
  std::vector<JointState> js, js0, js1;
  traj.evaluate(t_a - 1.0, js0);
  traj.evaluate(t_b + 1.0, js1);
  f.theta_min_rad = f.theta_max_rad = js0.empty() ? 0.0 : js0[0].theta;
  f.joints.resize(js0.size());
  for (std::size_t i = 0; i < js0.size(); ++i) f.joints[i].theta_min_rad = f.joints[i].theta_max_rad = js0[i].theta;
  double prev_t = ts.empty() ? 0.0 : ts.front(), prev_p = 0.0;
  TailKinematics kin;       // scratch: no allocation per sample
  std::vector<double> tau;
  for (double t : ts) {
    traj.evaluate(t, js);
    jointTorques(links, js, kin, tau);
    f.addSample(js, tau);
    onSample(t, tau);
    double p = 0.0;
    for (std::size_t i = 0; i < js.size(); ++i) p += std::abs(tau[i] * js[i].theta_dot);
    f.energy_J += 0.5 * (p + prev_p) * (t - prev_t);  // trapezoid
    prev_t = t;
    prev_p = p;
  }
  for (std::size_t i = 0; i < js0.size(); ++i) f.end_offset_rad = std::max(f.end_offset_rad, std::abs(js1[i].theta - js0[i].theta));
  for (std::size_t i = 0; i < traj.joints.size(); ++i)
    if (traj.joints[i].isSpline()) {
      const double v = std::abs(traj.joints[i].peakSpeed());
      f.peak_speed_radps = std::max(f.peak_speed_radps, v);
      if (i < f.joints.size()) f.joints[i].peak_speed_radps = std::max(f.joints[i].peak_speed_radps, v);
    }
  return f;
}

// The largest peak torque / its limit over the joints with a torque limit (0: none), from figures.
double peakOverLimit(const StrokeFigures& f, const StrokeLimits& L) {
  double ratio = 0.0;
  for (std::size_t i = 0; i < f.joints.size(); ++i) {
    const JointLimits J = L.joint(i);
    if (J.torque_max_Nm > 0.0) ratio = std::max(ratio, f.joints[i].peak_torque_Nm / J.torque_max_Nm);
  }
  return ratio;
}

// The same ratio at one sample's torques.
double ratioAt(const std::vector<double>& tau, const StrokeLimits& L) {
  double ratio = 0.0;
  for (std::size_t i = 0; i < tau.size(); ++i) {
    const JointLimits J = L.joint(i);
    if (J.torque_max_Nm > 0.0) ratio = std::max(ratio, std::abs(tau[i]) / J.torque_max_Nm);
  }
  return ratio;
}

// Where a stroke's torque peaks: the raw stroke's time intervals around its samples within kNearPeak of
// its peak ratio. Slowed by s (times x s) they hold the slowed stroke's peak sample, unless another
// hump, lower on the raw grid, comes out higher on the slowed one (peakIn's caller checks).
struct PeakWindows {
  static constexpr double kNearPeak = 0.02, kPad = 2.0;  // share of the peak; padding in samples
  std::vector<std::pair<double, double>> raw;            // [a, b] in the raw stroke's time, merged

  // From the raw stroke's samples (time, ratio) and its peak ratio.
  PeakWindows(const std::vector<std::pair<double, double>>& samples, double peak, double dt) {
    for (const auto& [time, r] : samples) {
      if (r < (1.0 - kNearPeak) * peak) continue;
      const double a = time - kPad * dt, b = time + kPad * dt;
      if (!raw.empty() && a <= raw.back().second) raw.back().second = b;
      else raw.emplace_back(a, b);
    }
  }

  // The largest ratio over u's own sample times (sampleTimes(u), the same doubles strokeFigures
  // evaluates) inside the windows slowed by s: u = t slowed by s.
  double peakIn(const std::vector<TailLink>& links, const StrokeLimits& L, const TailTrajectory& u, double s,
                double dt) const {
    std::vector<JointState> js;
    TailKinematics kin;
    std::vector<double> tau;
    double ratio = 0.0;
    auto at = [&](double time) {
      u.evaluate(time, js);
      jointTorques(links, js, kin, tau);
      ratio = std::max(ratio, ratioAt(tau, L));
    };
    // sampleTimes(u) inside each window, without building the whole list: its grid times k dt
    // (k from floor(t_a / dt), k dt <= t_b + dt) and its breakpoints.
    const long k_first = static_cast<long>(std::floor(u.startTime() / dt));
    const double t_last = u.endTime() + dt;
    const std::vector<double> breaks = u.breakpoints();
    for (const auto& w : raw) {
      const double a = w.first * s, b = w.second * s;
      for (long k = std::max(k_first, static_cast<long>(std::floor(a / dt))); k * dt <= b && k * dt <= t_last; ++k)
        if (k * dt >= a) at(k * dt);
      for (auto it = std::lower_bound(breaks.begin(), breaks.end(), a); it != breaks.end() && *it <= b; ++it) at(*it);
    }
    return ratio;
  }
};

// slowedToTorqueLimit's corrections, ratio(u, s) the peak ratio of u = t slowed by s: from the
// raw stroke's ratio, a few corrections s <- s sqrt(ratio) (torques scale with 1/s^2 up to the
// sampling grid, which samples the slowed motion at other phases), each from the slowed stroke's own
// ratio, ending on the smallest factor seen that keeps the limit (or the last, when none does).
// *s_out: the factor of the stroke returned.
template <typename Ratio>
TailTrajectory correctedSlowDown(const TailTrajectory& t, const StrokeLimits& L, double ratio, Ratio ratioOf,
                                 double* s_out) {
  auto kept = [](double r) { return !exceedsLimit(r, 1.0); };
  double s_max = std::numeric_limits<double>::infinity();  // where a duration or delay reaches its range's end
  for (const JointProfile& j : t.joints) {  // params(): a spline's envelope holds its dT and t0 too
    if (j.params().dT_s > 0.0) s_max = std::min(s_max, L.dT_max_s / j.params().dT_s);
    if (j.params().t0_s > 0.0) s_max = std::min(s_max, L.t0_max_s / j.params().t0_s);
  }
  s_max = std::max(1.0, s_max);
  double s = 1.0, s_kept = std::numeric_limits<double>::infinity();
  TailTrajectory out = t, best;
  for (int it = 0; it < 8; ++it) {
    if (kept(ratio) && s < s_kept) {
      s_kept = s;
      best = out;
      if (ratio > 1.0 - 1e-7) break;
    }
    // A margin over the limit's rounding, grown from the 4th correction on (the grid can keep a
    // stroke a hair over the limit correction after correction).
    const double margin = it < 3 ? 1e-9 : std::pow(10.0, it - 9);
    const double next = std::min(s_max, std::max(1.0, s * std::sqrt(ratio) * (1.0 + margin)));
    if (next == s) break;
    s = next;
    out = timeScaled(t, 1.0 / s);
    ratio = ratioOf(out, s);
  }
  const bool last = !std::isfinite(s_kept) || (kept(ratio) && s < s_kept);  // else the best kept one
  *s_out = last ? s : s_kept;
  return last ? out : best;  // none kept: capped by the ranges, still over
}
}  // namespace

TailTrajectory slowedToTorqueLimit(const std::vector<TailLink>& links, const StrokeLimits& L, const TailTrajectory& t,
                                   StrokeFigures* figures) {
  constexpr double dt = 5e-4;  // strokeFigures' grid
  std::vector<std::pair<double, double>> samples;  // (time, torque ratio) of the raw stroke
  StrokeFigures f = sampledFigures(links, t, dt, [&](double time, const std::vector<double>& tau) {
    samples.emplace_back(time, ratioAt(tau, L));
  });
  const double ratio = peakOverLimit(f, L);
  if (!exceedsLimit(ratio, 1.0)) {
    if (figures) *figures = f;
    return t;
  }
  // The corrections read the slowed strokes' torques only where the raw stroke peaks (PeakWindows),
  // a few dozen samples instead of the whole stroke; the answer's figures are then sampled in full,
  // and where their peak is not the windows' (another hump came out higher) the corrections run
  // again on full samples. Either way the same samples as strokeFigures decide.
  const PeakWindows windows(samples, ratio, dt);
  double s = 1.0;
  const TailTrajectory fast = correctedSlowDown(
      t, L, ratio, [&](const TailTrajectory& u, double k) { return windows.peakIn(links, L, u, k, dt); }, &s);
  f = strokeFigures(links, fast, dt);
  if (peakOverLimit(f, L) == windows.peakIn(links, L, fast, s, dt)) {
    if (figures) *figures = f;
    return fast;
  }
  return slowedToTorqueLimitOnFullSamples(links, L, t, figures);
}

TailTrajectory slowedToTorqueLimitOnFullSamples(const std::vector<TailLink>& links, const StrokeLimits& L,
                                                const TailTrajectory& t, StrokeFigures* figures) {
  constexpr double dt = 5e-4;  // strokeFigures' grid
  auto ratioOf = [&](const TailTrajectory& u) { return peakOverLimit(strokeFigures(links, u, dt), L); };
  const double ratio = ratioOf(t);
  double s = 1.0;
  const TailTrajectory out = exceedsLimit(ratio, 1.0)
                                 ? correctedSlowDown(t, L, ratio, [&](const TailTrajectory& u, double) { return ratioOf(u); }, &s)
                                 : t;
  if (figures) *figures = strokeFigures(links, out, dt);
  return out;
}

std::vector<double> StrokeSpace::pointOf(const std::vector<SplitCycleParams>& joints) const {
  const StrokeLimits& L = limits;
  std::vector<double> x;
  for (int i = 0; i < n_links; ++i) {
    const SplitCycleParams& p = joints.at(static_cast<std::size_t>(i));
    const JointLimits J = L.joint(static_cast<std::size_t>(i));
    const double a = p.theta0_rad, b = p.theta0_rad + p.dtheta_rad;
    if (family == StrokeFamily::kSplitCycle) {
      const double speed = p.dT_s > 0 ? 2.0 * std::abs(p.dtheta_rad) / p.dT_s : J.thetadot_max_radps;
      const int dir = directions.empty() ? 0 : directions.at(static_cast<std::size_t>(i));
      const double u_end = dir > 0   ? unlerp(a, J.theta_max_rad, b)
                           : dir < 0 ? (a > J.theta_min_rad ? clamp01((a - b) / (a - J.theta_min_rad)) : 0.0)
                                     : unlerp(J.theta_min_rad, J.theta_max_rad, b);
      x.insert(x.end(), {unlerp(J.theta_min_rad, J.theta_max_rad, a), u_end,
                         unlerp(0.05, 1.0, speed / J.thetadot_max_radps), unlerp(L.w_ss_min, L.w_ss_max, p.w_ss),
                         unlerp(0.0, L.t0_max_s, p.t0_s)});
    } else {
      // The split-cycle stroke sampled at the knots (out and back when the tail must end at its start).
      const SplitCycleProfile prof(p);
      const int N = knots + 2;
      for (int k = 0; k < N - 1 + (L.end == StrokeEnd::kAtRest ? 1 : 0); ++k) {
        double frac = static_cast<double>(k) / (N - 1);
        if (L.end == StrokeEnd::kAtStart) frac = frac <= 0.5 ? 2 * frac : 2 - 2 * frac;
        x.push_back(unlerp(J.theta_min_rad, J.theta_max_rad, prof.at(p.t0_s + frac * p.dT_s).theta));
      }
      x.push_back(unlerp(L.dT_min_s, L.dT_max_s, L.end == StrokeEnd::kAtStart ? 2 * p.dT_s : p.dT_s));
      x.push_back(unlerp(0.0, L.t0_max_s, p.t0_s));
    }
  }
  return x;
}

void jointTorques(const std::vector<TailLink>& links, const std::vector<JointState>& joints, TailKinematics& kin,
                  std::vector<double>& tau) {
  tailKinematics(links, joints, kin);
  tau.resize(links.size());
  tailBaseLoad(links, kin, kin.a_L, tau.data());
}

std::vector<double> jointTorques(const std::vector<TailLink>& links, const std::vector<JointState>& joints) {
  TailKinematics kin;
  std::vector<double> tau;
  jointTorques(links, joints, kin, tau);
  return tau;
}

void StrokeFigures::addSample(const std::vector<JointState>& js, const std::vector<double>& tau) {
  if (joints.size() != js.size()) {
    joints.assign(js.size(), JointFigures{});
    for (std::size_t i = 0; i < js.size(); ++i) joints[i].theta_min_rad = joints[i].theta_max_rad = js[i].theta;
    if (!js.empty() && theta_min_rad > theta_max_rad) theta_min_rad = theta_max_rad = js[0].theta;
  }
  for (std::size_t i = 0; i < js.size(); ++i) {
    JointFigures& g = joints[i];
    g.theta_min_rad = std::min(g.theta_min_rad, js[i].theta);
    g.theta_max_rad = std::max(g.theta_max_rad, js[i].theta);
    g.peak_speed_radps = std::max(g.peak_speed_radps, std::abs(js[i].theta_dot));
    g.peak_torque_Nm = std::max(g.peak_torque_Nm, std::abs(tau[i]));
    theta_min_rad = std::min(theta_min_rad, js[i].theta);
    theta_max_rad = std::max(theta_max_rad, js[i].theta);
    peak_speed_radps = std::max(peak_speed_radps, g.peak_speed_radps);
    peak_torque_Nm = std::max(peak_torque_Nm, g.peak_torque_Nm);
  }
}

StrokeFigures strokeFigures(const std::vector<TailLink>& links, const TailTrajectory& traj, double dt) {
  return sampledFigures(links, traj, dt, [](double, const std::vector<double>&) {});
}

double limitViolation(const StrokeFigures& f, const StrokeLimits& L) {
  // An excess within the tolerance (exceedsLimit) is rounding, not a violation: a split-cycle
  // stroke at the box's speed-share bound (share 1) peaks at the speed limit measured 1 ulp over
  // it, and an end angle at the angle bound lands 1 ulp outside. Counted strictly, those points
  // were infeasible, so the search was pushed off the bounds the n = 3 optimum lies on
  // (docs/design-a-tail-stroke.md). checkLimitsOnSeries (the re-run's check) uses the same rule.
  auto excess = [](double value, double limit, double scale) { return exceedsLimit(value, limit) ? (value - limit) / scale : 0.0; };
  // Per kind of limit the worst joint's relative excess (with the same limits at every joint: the
  // excess of the figure over all joints), summed over the kinds.
  double hi = 0.0, lo = 0.0, speed = 0.0, torque = 0.0, widest = 1e-9;
  for (std::size_t i = 0; i < f.joints.size(); ++i) {
    const JointLimits J = L.joint(i);
    const JointFigures& g = f.joints[i];
    const double range = std::max(J.theta_max_rad - J.theta_min_rad, 1e-9);
    widest = std::max(widest, range);
    hi = std::max(hi, excess(g.theta_max_rad, J.theta_max_rad, range));
    lo = std::max(lo, excess(-g.theta_min_rad, -J.theta_min_rad, range));
    speed = std::max(speed, excess(g.peak_speed_radps, J.thetadot_max_radps, J.thetadot_max_radps));
    if (J.torque_max_Nm > 0) torque = std::max(torque, excess(g.peak_torque_Nm, J.torque_max_Nm, J.torque_max_Nm));
  }
  double v = hi + lo + speed + torque;
  if (L.end == StrokeEnd::kAtStart) v += f.end_offset_rad / widest;
  return v;
}

std::vector<std::string> bindingLimits(const StrokeFigures& f, const StrokeLimits& L, double share) {
  std::vector<std::pair<double, std::string>> used;  // (share of the limit used, text)
  auto num = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.4g", v);
    return std::string(b);
  };
  constexpr double kDeg = units::kDegPerRad;
  for (std::size_t i = 0; i < f.joints.size(); ++i) {
    const JointLimits J = L.joint(i);
    const JointFigures& g = f.joints[i];
    const std::string who = "joint " + std::to_string(i + 1) + " ";
    if (J.torque_max_Nm > 0 && g.peak_torque_Nm >= (1.0 - share) * J.torque_max_Nm)
      used.emplace_back(g.peak_torque_Nm / J.torque_max_Nm,
                        who + "torque " + num(g.peak_torque_Nm) + " N m (limit " + num(J.torque_max_Nm) + " N m)");
    if (g.peak_speed_radps >= (1.0 - share) * J.thetadot_max_radps)
      used.emplace_back(g.peak_speed_radps / J.thetadot_max_radps, who + "speed " + num(g.peak_speed_radps * kDeg) +
                                                                         " deg/s (limit " + num(J.thetadot_max_radps * kDeg) + " deg/s)");
    const double range = J.theta_max_rad - J.theta_min_rad;
    if (g.theta_max_rad >= J.theta_max_rad - share * range)
      used.emplace_back(1.0, who + "angle " + num(g.theta_max_rad * kDeg) + " deg (limit " + num(J.theta_max_rad * kDeg) + " deg)");
    if (g.theta_min_rad <= J.theta_min_rad + share * range)
      used.emplace_back(1.0, who + "angle " + num(g.theta_min_rad * kDeg) + " deg (limit " + num(J.theta_min_rad * kDeg) + " deg)");
  }
  std::stable_sort(used.begin(), used.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<std::string> out;
  for (auto& u : used) out.push_back(std::move(u.second));
  return out;
}

int mostLoadedJoint(const StrokeFigures& f, const StrokeLimits& L) {
  int best = -1;
  double top = -1.0;
  for (std::size_t i = 0; i < f.joints.size(); ++i) {
    const double lim = L.joint(i).torque_max_Nm;
    const double s = lim > 0 ? f.joints[i].peak_torque_Nm / lim : f.joints[i].peak_torque_Nm;
    if (s > top) {
      top = s;
      best = static_cast<int>(i);
    }
  }
  return best;
}

double objectiveValue(StrokeObjective o, double phi_net_rad, const StrokeFigures& f) {
  const double a = std::abs(phi_net_rad);
  switch (o) {
    case StrokeObjective::kPhiNet: return a;
    case StrokeObjective::kPhiNetPerTorque: return a / std::max(f.peak_torque_Nm, 1e-9);
    case StrokeObjective::kPhiNetPerEnergy: return a / std::max(f.energy_J, 1e-9);
  }
  return a;
}

const char* objectiveName(StrokeObjective o) {
  switch (o) {
    case StrokeObjective::kPhiNet: return "phi_net";
    case StrokeObjective::kPhiNetPerTorque: return "phi_net_per_torque";
    case StrokeObjective::kPhiNetPerEnergy: return "phi_net_per_energy";
  }
  return "?";
}
const char* objectiveModelName(ObjectiveModel m) {
  switch (m) {
    case ObjectiveModel::kAnalytic: return "analytic";
    case ObjectiveModel::kPerFoot: return "perfoot";
    case ObjectiveModel::kMujoco: return "mujoco";
  }
  return "analytic";
}

double signedObjectiveDeg(double objective, double phi_net_rad) {
  return (phi_net_rad < 0.0 ? -objective : objective) * units::kDegPerRad;
}

const char* objectiveUnit(StrokeObjective o) {
  switch (o) {
    case StrokeObjective::kPhiNet: return "deg";
    case StrokeObjective::kPhiNetPerTorque: return "deg/(N m)";
    case StrokeObjective::kPhiNetPerEnergy: return "deg/J";
  }
  return "deg";
}

const char* objectiveUnitSuffix(StrokeObjective o) {
  switch (o) {
    case StrokeObjective::kPhiNet: return "deg";
    case StrokeObjective::kPhiNetPerTorque: return "deg_per_Nm";
    case StrokeObjective::kPhiNetPerEnergy: return "deg_per_J";
  }
  return "deg";
}

const char* familyName(StrokeFamily f) { return f == StrokeFamily::kSplitCycle ? "split_cycle" : "spline"; }

}  // namespace tailsim
