// Friction and stick/slip event logic of the analytic model (Eqs. 14-16, the ADAMS law), free
// of the tail dynamics: the friction loads of sliding DOFs, which DOF switches when margins
// reach zero, and locating that time inside a step (tests/test_stick_slip.cc).
//
// A margin g > 0 means no switch; a switch happens where g reaches 0 from above (stuck DOF:
// static limit minus the load it needs; sliding rotation: rot_dir * phi_dot).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "models/planar/tail_dynamics.h"
#include "robot/robot_params.h"
#include "robot/scene_effects.h"

namespace tailsim {

// The two frictional DOFs of the body: rotation (yaw) and translation.
constexpr int kRot = 0, kTrans = 1;
using Margins = std::array<double, 2>;  // event margins g of rotation, translation

struct Modes {
  bool stuck[2] = {false, false};  // rotation, translation (stiction law only)
  double rot_dir = 0.0;            // sign of phi_dot while slipping (friction opposes it)
};

// Breakaway uses the larger of mu_s and mu_d (paper-notes point 1): with mu_s < mu_d, a body
// that broke away at mu_s would feel mu_d > load and re-stick at once, forever.
inline double breakawayCoefficient(const FrictionParams& f) { return f.mu_s > f.mu_d ? f.mu_s : f.mu_d; }

// Friction loads on the DOFs that slide (stuck DOFs get theirs from the equations of motion).
struct SlidingFriction {
  double MzF = 0.0;           // friction moment about the system COM  [N m]
  Vec2 FF = Vec2::Zero();     // friction force, world  [N]
};

// law kStiction: Eq. (16) sliding, M = -mu_d W L_F rot_dir, with the slip mode's direction (fixed
// until the mode ends at a located event, so trial steps overshooting phi_dot = 0 do not make the
// right-hand side jump); Eq. (15) sliding, F = -mu_d W v / max(|v|, v_reg) (regularized inside
// |v| < v_reg so a creeping body does not chatter in direction; v_reg = 0: plain Coulomb).
// law kContinuous: the ADAMS law, mu from the slip speed, direction from the sign of the rate.
// law kNone, or no arm: no friction.  W: weight [N]; phi_dot [rad/s]; (vx, vy): body velocity [m/s].
// (The velocity as two doubles: the state's vx, vy are stored one by one, and a Vec2 of them read
// back as one 16-byte load stalled on store forwarding.)
SlidingFriction slidingFriction(FrictionLaw law, const FrictionParams& fp, double weight, double L_F,
                                double rot_dir, double phi_dot, double vx, double vy, double v_reg);
inline SlidingFriction slidingFriction(FrictionLaw law, const FrictionParams& fp, double weight, double L_F,
                                       double rot_dir, double phi_dot, const Vec2& v, double v_reg) {
  return slidingFriction(law, fp, weight, L_F, rot_dir, phi_dot, v.x(), v.y(), v_reg);
}

// The DOF to switch for margins g (or -1 for none): a stuck DOF at or below zero breaks away
// first (translation before rotation when both), then a sliding translation below zero sticks,
// then a sliding rotation below zero stops.
int dofToSwitch(const Modes& m, const Margins& g, bool translation);

// Illinois (modified regula falsi) on g over [a, b] with g(a) > 0 >= g(b); returns the first time
// known to be at or past the switch (b side), within tol.
template <class G>
double illinois(const G& g, double a, double b, double ga, double gb, double tol) {
  if (!(ga > 0)) return a + std::min(tol, b - a);  // the switch is at a itself
  int side = 0;
  for (int it = 0; it < 100 && b - a > tol; ++it) {
    double c = (a * gb - b * ga) / (gb - ga);
    if (!(c > a && c < b)) c = 0.5 * (a + b);
    const double gc = g(c);
    if (gc > 0) {
      a = c; ga = gc;
      if (side == -1) gb *= 0.5;
      side = -1;
    } else {
      b = c; gb = gc;
      if (side == +1) ga *= 0.5;
      side = +1;
    }
  }
  return b;
}

// Golden-section minimum of g on [a, b]: (t, g(t)).
template <class G>
std::pair<double, double> goldenMin(const G& g, double a, double b, double tol) {
  const double r = 0.5 * (std::sqrt(5.0) - 1.0);
  double c = b - r * (b - a), d = a + r * (b - a);
  double gc = g(c), gd = g(d);
  for (int it = 0; it < 60 && b - a > tol; ++it) {
    if (gc < gd) { b = d; d = c; gd = gc; c = b - r * (b - a); gc = g(c); }
    else { a = c; c = d; gc = gd; d = a + r * (b - a); gd = g(d); }
  }
  return gc < gd ? std::make_pair(c, gc) : std::make_pair(d, gd);
}

struct Found {
  bool hit = false;
  double t = 0;
  int which = 0;
};

// The last two margin samples of a scan that found no switch: a dip whose lowest sample is the
// scan's last one (g_end below g_before) can only be seen by the next scan.
struct ScanEnd {
  double t_before = 0;  // the sample before the last  [s]
  Margins g_before{};   // the margins there
  Margins g_end{};      // the margins at the scan's end (tb)
};

// A stuck DOF's margin still falling at the scan's end (and above zero): its dip, if any, may lie
// across the boundary, so the next scan must start from these two samples.
inline bool dipMayCross(const Modes& m, const ScanEnd& e) {
  for (int w : {kRot, kTrans})
    if (m.stuck[w] && e.g_end[w] < e.g_before[w] && e.g_end[w] > 0) return true;
  return false;
}

// Searches [ta, tb] for the first switch of either DOF, with gAt(t) -> Margins. Both margins are
// sampled together every h_scan (so a short load peak between two solver steps is not stepped
// over: paper-notes point 4); in the first sample interval where any margin reaches zero, every
// DOF that crosses there is located and the earliest wins, so no DOF's switch can hide behind
// another's. A dip of a stuck DOF's margin between samples (all samples positive, the lowest
// between two higher ones) is refined by golden section. `prev`: the previous scan's end, same
// modes, when the caller has it (saves the evaluation at ta); with `across` also its sample
// before ta, so a dip whose lowest sample is ta is refined over [prev->t_before, ta + h]: gAt
// must then answer there too, and a switch may be found before ta. `end`: set when nothing
// switches.
template <class GAt>
Found findSwitch(const GAt& gAt, const Modes& m, double ta, double tb, double h_scan, double tol,
                 const ScanEnd* prev = nullptr, ScanEnd* end = nullptr, bool across = false) {
  const int k = std::max(2, static_cast<int>(std::ceil((tb - ta) / h_scan)));
  // A stuck margin reaching 0 from above, or a sliding one turning negative (a stop).
  auto crosses = [&](int w, double g0, double g1) { return (g0 > 0 && g1 <= 0) || (!m.stuck[w] && g0 >= 0 && g1 < 0); };
  Margins g_prev = prev ? prev->g_end : gAt(ta);
  for (int w : {kRot, kTrans})  // already past the switch (settleModes normally resolves this)
    if ((m.stuck[w] && g_prev[w] <= 0) || (!m.stuck[w] && g_prev[w] < 0)) return {true, ta, w};
  const bool before = prev && across && prev->t_before < ta;
  double t_prev = ta, t_prev2 = before ? prev->t_before : ta;
  Margins g_prev2 = before ? prev->g_before : g_prev;
  for (int i = 1; i <= k; ++i) {
    const double t = ta + (tb - ta) * i / k;
    const Margins gt = gAt(t);
    Found best;
    for (int w : {kRot, kTrans}) {
      auto gw = [&](double tt) { return gAt(tt)[w]; };
      double ts = 0;
      bool hit = false;
      if (crosses(w, g_prev[w], gt[w])) {
        double a = t_prev, ga = g_prev[w];
        if (!(ga > 0)) {  // a slide that has just begun (margin 0) may rise and fall back inside
          const auto [tm, neg_gm] = goldenMin([&](double tt) { return -gw(tt); }, t_prev, t, tol * 1e3);
          if (-neg_gm > 0) a = tm, ga = -neg_gm;  // it did: its stop is the root after the peak
        }
        ts = illinois(gw, a, t, ga, gt[w], tol);
        hit = true;
      } else if (m.stuck[w] && t_prev2 < t_prev && g_prev[w] < g_prev2[w] && g_prev[w] < gt[w] && g_prev[w] > 0) {
        const auto [tm, gm] = goldenMin(gw, t_prev2, t, tol * 1e3);
        if (gm <= 0) {
          ts = illinois(gw, t_prev2, tm, g_prev2[w], gm, tol);
          hit = true;
        }
      }
      if (hit && (!best.hit || ts < best.t)) best = {true, ts, w};
    }
    if (best.hit) return best;
    t_prev2 = t_prev; g_prev2 = g_prev;
    t_prev = t; g_prev = gt;
  }
  if (end) *end = {t_prev2, g_prev2, g_prev};
  return {};
}

}  // namespace tailsim
