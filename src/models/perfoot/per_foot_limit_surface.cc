// The planar limit surface of four friction discs (per_foot_model.h; docs/per-foot-model.md).
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "models/perfoot/per_foot_model.h"

namespace tailsim {

double limitSupport(const FootDiscs& d, const Twist2& xi) {
  double h = 0.0;
  for (int i = 0; i < 4; ++i) h += d.c[i] * (xi.v + xi.w * perp(d.r[i])).norm();
  return h;
}

Wrench2 maxDissipationWrench(const FootDiscs& d, const Twist2& xi) {
  Wrench2 W;
  for (int i = 0; i < 4; ++i) {
    const Vec2 vi = xi.v + xi.w * perp(d.r[i]);
    const double s = vi.norm();
    if (!(s > 0.0)) continue;
    const Vec2 f = d.c[i] * vi / s;
    W.F += f;
    W.M += cross2(d.r[i], f);
  }
  return W;
}

namespace {

// A rotation about the instantaneous centre p, w = sigma: v of the reference point = -w z x p.
Twist2 rotationAbout(const Vec2& p, double sigma) { return {-sigma * perp(p), sigma}; }

// D(p) = sum c_i |r_i - p|: the support of a unit-rate rotation about p.
double weberSum(const FootDiscs& d, const Vec2& p) {
  double D = 0.0;
  for (int i = 0; i < 4; ++i) D += d.c[i] * (d.r[i] - p).norm();
  return D;
}

// Phi(q) = s D(q) + sigma cross2(q, F): minimizePhi's objective, less its constant term.
inline double phiAt(const FootDiscs& d, const Wrench2& W, double sigma, double s, const Vec2& q) {
  return s * weberSum(d, q) + sigma * cross2(q, W.F);
}

// Whether a foot is Phi's minimizer (then p and pivot are set): foot j is iff the other terms'
// gradient there lies in its disc s c_j.
inline bool footIsMinimizer(const FootDiscs& d, const Vec2& gradLin, double s, Vec2& p, int& pivot) {
  for (int j = 0; j < 4; ++j) {
    Vec2 g = gradLin;
    bool coincident = false;
    for (int i = 0; i < 4; ++i) {
      if (i == j) continue;
      const Vec2 u = d.r[j] - d.r[i];
      const double n = u.norm();
      if (n == 0.0) { coincident = true; break; }
      g += s * d.c[i] * u / n;
    }
    if (!coincident && g.norm() <= s * d.c[j]) {
      p = d.r[j];
      pivot = j;
      return true;
    }
  }
  return false;
}

// The minimizer is no foot: a start p near a foot moves to the discs' weighted centroid (near a
// foot that is not optimal the Hessian is huge across it and Newton crawls), nudged off any foot.
inline void startAwayFromFeet(const FootDiscs& d, double scale, Vec2& p) {
  for (int i = 0; i < 4; ++i)
    if ((p - d.r[i]).norm() < 1e-3 * scale) {
      double C = 0.0;
      Vec2 m = Vec2::Zero();
      for (int k = 0; k < 4; ++k) C += d.c[k], m += d.c[k] * d.r[k];
      p = m / C;
      for (int k = 0; k < 4; ++k)
        if ((p - d.r[k]).norm() < 1e-3 * scale) p += Vec2(0.05 * scale, 0.03 * scale);
      break;
    }
}

// The foot p lies next to (within 1e-4 scale; the last such), or -1.
inline int footNear(const FootDiscs& d, double scale, const Vec2& p) {
  int near = -1;
  for (int i = 0; i < 4; ++i)
    if (d.c[i] > 0 && (p - d.r[i]).norm() < 1e-4 * scale) near = i;
  return near;
}

// Phi's gradient g and Hessian H at p; next to foot `near`, those of the other feet's terms at it.
inline void phiGradient(const FootDiscs& d, const Vec2& gradLin, double s, const Vec2& p, int near, Vec2& g,
                        Eigen::Matrix2d& H) {
  g = gradLin;
  H = Eigen::Matrix2d::Zero();
  for (int i = 0; i < 4; ++i) {
    const Vec2 u = (near >= 0 ? d.r[near] : p) - d.r[i];
    const double n = u.norm();
    if (n == 0.0 || i == near) continue;
    const Vec2 e = u / n;
    g += s * d.c[i] * e;
    H += s * d.c[i] / n * (Eigen::Matrix2d::Identity() - e * e.transpose());
  }
}

// One step of minimizePhi's descent: go on, stop (p is the minimizer to round-off), or Phi runs off
// to infinity.
enum class PhiStep { kOn, kDone, kUnbounded };

// Next to foot `near` (not the minimizer), gradient steps zigzag across its kink: a step off it
// along minus the other feet's gradient g (the minimal subgradient there), backtracking.
inline PhiStep stepOffFoot(const FootDiscs& d, const Wrench2& W, double sigma, double s, double scale, int near,
                           const Vec2& g, Vec2& p, double& f) {
  const double excess = g.norm() - s * d.c[near];
  if (!(excess > 0)) return PhiStep::kDone;  // it is the minimizer after all (round-off at the check)
  const Vec2 dir = -g / g.norm();
  double len = 0.1 * scale;
  Vec2 q = d.r[near] + len * dir;
  double fq = phiAt(d, W, sigma, s, q);
  const double f0 = phiAt(d, W, sigma, s, d.r[near]);
  while (!(fq < f0 - 1e-4 * len * excess) && len > 1e-12 * scale) {
    len *= 0.5;
    q = d.r[near] + len * dir;
    fq = phiAt(d, W, sigma, s, q);
  }
  if (!(fq < f0)) return PhiStep::kDone;
  p = q;
  f = fq;
  return PhiStep::kOn;
}

// A Newton step on Phi (a gradient step where Newton's does not descend), its length capped, with
// a backtracking line search.
inline PhiStep newtonStep(const FootDiscs& d, const Wrench2& W, double sigma, double s, double scale, const Vec2& g,
                          const Eigen::Matrix2d& H, Vec2& p, double& f) {
  const double gscale = s * (d.c[0] + d.c[1] + d.c[2] + d.c[3]) + W.F.norm();
  if (g.norm() <= 1e-14 * gscale) return PhiStep::kDone;
  Vec2 step = -H.ldlt().solve(g);
  if (!step.allFinite() || step.dot(g) >= 0) step = -g * scale / gscale;  // gradient step
  const double cap = std::max(scale, p.norm());  // far out, grow geometrically at most
  if (step.norm() > cap) step *= cap / step.norm();
  double a = 1.0;
  Vec2 q = p + step;
  double fq = phiAt(d, W, sigma, s, q);
  while (!(fq <= f + 1e-4 * a * step.dot(g)) && a > 1e-12) {
    a *= 0.5;
    q = p + a * step;
    fq = phiAt(d, W, sigma, s, q);
  }
  if (!(fq <= f)) return PhiStep::kDone;  // no further descent in floating point
  const double moved = (q - p).norm();
  p = q;
  f = fq;
  if (p.norm() > 1e6 * scale) return PhiStep::kUnbounded;
  if (moved <= 1e-15 * scale) return PhiStep::kDone;
  return PhiStep::kOn;
}

// Minimizes Phi(p) = s D(p) - sigma (M - cross2(p, F)) (convex). Returns false if it runs off to
// infinity (s C = |F|: the supremum is the pure translation). `pivot`: the minimizer is foot j.
// Stages: a foot as the minimizer, else a start away from the feet, then up to 500 descent steps.
bool minimizePhi(const FootDiscs& d, const Wrench2& W, double sigma, double s, double scale, Vec2& p, int& pivot) {
  const Vec2 gradLin = sigma * Vec2(W.F.y(), -W.F.x());  // gradient of sigma cross2(p, F)
  pivot = -1;
  if (footIsMinimizer(d, gradLin, s, p, pivot)) return true;
  startAwayFromFeet(d, scale, p);
  double f = phiAt(d, W, sigma, s, p);
  for (int it = 0; it < 500; ++it) {
    const int near = footNear(d, scale, p);
    Vec2 g;
    Eigen::Matrix2d H;
    phiGradient(d, gradLin, s, p, near, g, H);
    const PhiStep r = near >= 0 ? stepOffFoot(d, W, sigma, s, scale, near, g, p, f)
                                : newtonStep(d, W, sigma, s, scale, g, H, p, f);
    if (r == PhiStep::kUnbounded) return false;
    if (r == PhiStep::kDone) break;
  }
  return true;
}

// The start rings' directions (cos, sin)(a pi / 12), the same libm values computed once: these
// 288 sincos calls a call were 12 % of a per-foot run.
const std::array<Vec2, 24>& startRing() {
  static const std::array<Vec2, 24> kRing = [] {
    std::array<Vec2, 24> r;
    for (int a = 0; a < 24; ++a) r[a] = Vec2(std::cos(a * M_PI / 12), std::sin(a * M_PI / 12));
    return r;
  }();
  return kRing;
}

// R(p) = L(p) / D(p), L(p) = sigma (M - cross2(p, F)): the load factor a rotation of sense sigma
// about p needs (infinite where D vanishes and L > 0).
inline double rotationLoadFactor(const FootDiscs& d, const Wrench2& W, double sigma, const Vec2& p) {
  const double D = weberSum(d, p);
  return D > 0 ? sigma * (W.M - cross2(p, W.F)) / D
               : (sigma * (W.M - cross2(p, W.F)) > 0 ? std::numeric_limits<double>::infinity() : 0.0);
}

// The start scan: the best of the reference point (p, s on entry), the feet, and instantaneous
// centres on rings out to 16 foot spans (a far centre is nearly the translation).
inline void scanStartCentres(const FootDiscs& d, const Wrench2& W, double sigma, double scale, Vec2& p, double& s) {
  const std::array<Vec2, 24>& ring = startRing();
  for (int j = 0; j < 4; ++j)
    if (rotationLoadFactor(d, W, sigma, d.r[j]) > s) {
      s = rotationLoadFactor(d, W, sigma, d.r[j]);
      p = d.r[j];
    }
  for (double rad : {0.5, 1.0, 2.0, 4.0, 8.0, 16.0})
    for (int a = 0; a < 24; ++a) {
      const Vec2 q = rad * scale * ring[a];
      if (rotationLoadFactor(d, W, sigma, q) > s) {
        s = rotationLoadFactor(d, W, sigma, q);
        p = q;
      }
    }
}

// Dinkelbach from (p, s): s_k -> max_p L - s_k D (its argmin of Phi) -> s_k+1 = L/D there; s_k
// increases to the maximum of L/D, superlinearly. Returns whether a centre reaching s was found
// (the start is a valid lower bound when it is not the translation's value): s, its centre p_best
// and pivot foot pivot_best (or -1).
inline bool dinkelbach(const FootDiscs& d, const Wrench2& W, double sigma, double scale, Vec2& p, double& s,
                       Vec2& p_best, int& pivot_best) {
  p_best = p;
  pivot_best = -1;
  for (int j = 0; j < 4; ++j)
    if (p == d.r[j]) pivot_best = j;
  bool found = rotationLoadFactor(d, W, sigma, p) >= s;
  for (int k = 0; k < 60; ++k) {
    int pivot = -1;
    if (!minimizePhi(d, W, sigma, s, scale, p, pivot)) break;
    const double s_new = rotationLoadFactor(d, W, sigma, p);
    if (!(s_new > s * (1.0 + 1e-15))) {
      if (s_new >= s) { p_best = p; pivot_best = pivot; found = true; s = s_new; }
      break;
    }
    s = s_new;
    p_best = p;
    pivot_best = pivot;
    found = true;
  }
  return found;
}

}  // namespace

// Stages: the pure translation's value, then per sense of rotation a start (the warm centre or the
// start scan) and Dinkelbach's iteration from it; the best, its twist of unit size.
LoadFactor loadFactor(const FootDiscs& d, const Wrench2& W, const LoadFactor* warm) {
  LoadFactor best;
  const double C = d.c[0] + d.c[1] + d.c[2] + d.c[3];
  const double Fn = W.F.norm();
  double scale = 0.0;
  for (const Vec2& r : d.r) scale = std::max(scale, r.norm());
  if (scale == 0.0) scale = 1.0;
  // Pure translation (the supremum as the instantaneous centre goes to infinity).
  best.direction = {Fn > 0 ? Vec2(W.F / Fn) : Vec2(1.0, 0.0), 0.0};
  if (!(C > 0.0)) {
    best.s = (Fn == 0.0 && W.M == 0.0) ? 0.0 : std::numeric_limits<double>::infinity();
    if (Fn == 0.0 && W.M != 0.0) best.direction = {Vec2::Zero(), W.M > 0 ? 1.0 : -1.0};
    return best;
  }
  best.s = Fn / C;
  // A warm start (a rotation's centre from a nearby wrench) replaces the start scan: that sense
  // of rotation first, from its centre; the other from the reference point, at the first's value.
  const bool warm_start = warm && warm->sigma != 0.0 && std::isfinite(warm->s) && warm->centre.allFinite();
  const double first = warm_start ? warm->sigma : 1.0;
  best.start_scan = !warm_start;
  for (double sigma : {first, -first}) {
    Vec2 p = Vec2::Zero();
    double s = rotationLoadFactor(d, W, sigma, p);
    if (warm_start) {
      if (sigma == first) {
        p = warm->centre;
        s = rotationLoadFactor(d, W, sigma, p);
      }
    } else {
      scanStartCentres(d, W, sigma, scale, p, s);
    }
    if (!std::isfinite(s)) return {s, rotationAbout(p, sigma), -1, p, sigma, !warm_start};
    if (!(s > 0.0) && !(best.s > 0.0)) continue;
    // Phi must grow at infinity (s C > |F|) for its minimum to be finite: start just above the
    // translation's value when that is the best so far (an optimum closer to it than 1e-12 is
    // the translation up to round-off).
    if (s < best.s * (1.0 + 1e-12)) s = best.s * (1.0 + 1e-12);
    Vec2 p_best;
    int pivot_best;
    if (dinkelbach(d, W, sigma, scale, p, s, p_best, pivot_best) && s > best.s) {
      best.s = s;
      best.direction = rotationAbout(p_best, sigma);
      best.pivot_foot = pivot_best;
      best.centre = p_best;
      best.sigma = sigma;
    }
  }
  // Unit twist: |v|^2 + (w scale)^2 = 1.
  const double n = std::hypot(best.direction.v.norm(), best.direction.w * scale);
  if (n > 0) {
    best.direction.v /= n;
    best.direction.w /= n;
  }
  return best;
}

std::array<Vec2, 4> heldFootForces(const FootDiscs& d, const Wrench2& W) {
  // F_i = c_i (a + b perp(r_i)):  [C I, sum c perp r; (sum c perp r)^T, sum c |r|^2] (a, b) = (F, M).
  Eigen::Matrix3d K = Eigen::Matrix3d::Zero();
  for (int i = 0; i < 4; ++i) {
    const Vec2 q = perp(d.r[i]);
    K(0, 0) += d.c[i];
    K(1, 1) += d.c[i];
    K(0, 2) += d.c[i] * q.x();
    K(1, 2) += d.c[i] * q.y();
    K(2, 2) += d.c[i] * d.r[i].squaredNorm();
  }
  K(2, 0) = K(0, 2);
  K(2, 1) = K(1, 2);
  std::array<Vec2, 4> out = zeros4();
  if (!(K(0, 0) > 0)) return out;
  const Eigen::Vector3d ab = K.ldlt().solve(Eigen::Vector3d(W.F.x(), W.F.y(), W.M));
  for (int i = 0; i < 4; ++i) out[i] = d.c[i] * (Vec2(ab[0], ab[1]) + ab[2] * perp(d.r[i]));
  return out;
}

}  // namespace tailsim
