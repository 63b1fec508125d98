#include "trajectory/split_cycle_profile.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "numerics/sin_cos.h"

namespace tailsim {

JointProfile::JointProfile(const SplitCycleParams& p) : p_(p) {
  if (!std::isfinite(p.dT_s) || p.dT_s <= 0.0)
    throw std::invalid_argument("dT_s must be > 0, got " + std::to_string(p.dT_s));
  if (!std::isfinite(p.w_ss) || p.w_ss <= 0.0 || p.w_ss >= 1.0)
    throw std::invalid_argument("w_ss must lie in (0, 1), got " + std::to_string(p.w_ss));
  if (!std::isfinite(p.theta0_rad) || !std::isfinite(p.dtheta_rad) || !std::isfinite(p.t0_s))
    throw std::invalid_argument("theta0, dtheta and t0 must be finite");
  da_ = p.w_ss * p.dT_s;  // Eq. (21)
  dd_ = p.dT_s - da_;
  const double T2 = p.dT_s * p.dT_s;
  A_ = M_PI * p.dtheta_rad / (p.w_ss * T2);          // Eq. (23)
  B_ = M_PI * p.dtheta_rad / ((1.0 - p.w_ss) * T2);  // Eq. (23); A Delta_a = B Delta_d
  // Constants of at() (the same expressions it would evaluate per call, so the same bits).
  ka_ = M_PI / da_;
  kd_ = M_PI / dd_;
  A_over_ka_ = A_ / ka_;
  B_over_kd_ = B_ / kd_;
  w1_ = 2.0 * A_ / ka_;
  th1_ = p_.theta0_rad + A_ * da_ * da_ / M_PI;
}

JointProfile::JointProfile(const SplineParams& s) : s_(s) {
  const std::size_t N = s.knots_rad.size();
  if (N < 2) throw std::invalid_argument("a spline needs at least 2 knots (start and end), got " + std::to_string(N));
  if (!std::isfinite(s.dT_s) || s.dT_s <= 0.0)
    throw std::invalid_argument("dT_s must be > 0, got " + std::to_string(s.dT_s));
  if (!std::isfinite(s.t0_s)) throw std::invalid_argument("t0 must be finite");
  for (double y : s.knots_rad)
    if (!std::isfinite(y)) throw std::invalid_argument("spline knots must be finite");
  knots_ = s.knots_rad;
  h_ = s.dT_s / static_cast<double>(N - 1);
  // Clamped cubic spline (zero slope at both ends): tridiagonal system for the second
  // derivatives m_k, solved by the Thomas algorithm.
  std::vector<double> a(N, 1.0), b(N, 4.0), c(N, 1.0), d(N, 0.0);
  b[0] = 2.0;
  b[N - 1] = 2.0;
  d[0] = 6.0 / (h_ * h_) * (knots_[1] - knots_[0]);
  d[N - 1] = -6.0 / (h_ * h_) * (knots_[N - 1] - knots_[N - 2]);
  for (std::size_t k = 1; k + 1 < N; ++k) d[k] = 6.0 / (h_ * h_) * (knots_[k + 1] - 2.0 * knots_[k] + knots_[k - 1]);
  for (std::size_t k = 1; k < N; ++k) {
    const double w = a[k] / b[k - 1];
    b[k] -= w * c[k - 1];
    d[k] -= w * d[k - 1];
  }
  m_.assign(N, 0.0);
  m_[N - 1] = d[N - 1] / b[N - 1];
  for (std::size_t k = N - 1; k-- > 0;) m_[k] = (d[k] - c[k] * m_[k + 1]) / b[k];
  p_.theta0_rad = knots_.front();
  p_.dtheta_rad = knots_.back() - knots_.front();
  p_.dT_s = s.dT_s;
  // The knot spacing; a single piece (2 knots) counts as two halves, so that min(w_ss, 1 - w_ss) dT
  // (the analytic model's step bound and the loader's work estimate) is never 0.
  p_.w_ss = N > 2 ? 1.0 / static_cast<double>(N - 1) : 0.5;
  p_.t0_s = s.t0_s;
  // Peak |speed|: the speed is quadratic on each piece, so its extremes are at knots or at the
  // piece's vertex (where the acceleration, linear on the piece, is zero).
  double best_t = s.t0_s;
  for (std::size_t k = 0; k + 1 < N; ++k) {
    std::vector<double> cand{s.t0_s + h_ * static_cast<double>(k)};
    if ((m_[k] > 0) != (m_[k + 1] > 0) && m_[k] != m_[k + 1]) cand.push_back(cand[0] + h_ * m_[k] / (m_[k] - m_[k + 1]));
    for (double t : cand) {
      const double v = splineAt(t).theta_dot;
      if (std::abs(v) > std::abs(peak_)) {
        peak_ = v;
        best_t = t;
      }
    }
  }
  da_ = best_t - s.t0_s;
  dd_ = s.dT_s - da_;
}

JointState JointProfile::splineAt(double t) const {
  const std::size_t N = knots_.size();
  const double tau = t - p_.t0_s;
  if (tau <= 0.0) return {knots_.front(), 0.0, 0.0};
  if (tau >= p_.dT_s) return {knots_.back(), 0.0, 0.0};
  std::size_t k = std::min(static_cast<std::size_t>(tau / h_), N - 2);
  const double b = tau - h_ * static_cast<double>(k), a = h_ - b;
  const double ya = knots_[k] - m_[k] * h_ * h_ / 6.0, yb = knots_[k + 1] - m_[k + 1] * h_ * h_ / 6.0;
  return {m_[k] * a * a * a / (6.0 * h_) + m_[k + 1] * b * b * b / (6.0 * h_) + (ya * a + yb * b) / h_,
          -m_[k] * a * a / (2.0 * h_) + m_[k + 1] * b * b / (2.0 * h_) + (yb - ya) / h_,
          (m_[k] * a + m_[k + 1] * b) / h_};
}

void JointProfile::breakpoints(std::vector<double>& out) const {
  if (!isSpline()) {
    out.push_back(p_.t0_s);
    out.push_back(t1());
    out.push_back(t2());
    return;
  }
  for (std::size_t k = 0; k < knots_.size(); ++k) out.push_back(p_.t0_s + h_ * static_cast<double>(k));
}

double JointProfile::peakAcceleration() const {
  if (!isSpline()) return std::max(std::abs(A_), std::abs(B_));
  double a = 0.0;
  for (double m : m_) a = std::max(a, std::abs(m));
  return a;
}

JointState JointProfile::at(double t) const {
  if (isSpline()) return splineAt(t);
  const double tau = t - p_.t0_s;
  if (tau <= 0.0) return {p_.theta0_rad, 0.0, 0.0};
  if (tau >= p_.dT_s) return {p_.theta0_rad + p_.dtheta_rad, 0.0, 0.0};
  // Eq. (20) integrated twice with Eq. (22)'s conditions at t0.
  if (tau <= da_) {
    const auto [s, c] = sinCos(ka_ * tau);
    return {p_.theta0_rad + A_over_ka_ * (tau - s / ka_), A_over_ka_ * (1.0 - c), A_ * s};
  }
  const double sigma = tau - da_;  // w1_: peak speed at t1; th1_: angle at t1
  const auto [s, c] = sinCos(kd_ * sigma);
  return {th1_ + w1_ * sigma - B_over_kd_ * (sigma - s / kd_), w1_ - B_over_kd_ * (1.0 - c), -B_ * s};
}

void TailTrajectory::evaluate(double t, std::vector<JointState>& out) const {
  // Sizes and pointers read once: at() is out of line, so the loop would reload them per joint.
  const size_t n = joints.size();
  if (out.size() != n) out.resize(n);
  JointState* o = out.data();
  const JointProfile* j = joints.data();
  for (size_t i = 0; i < n; ++i) o[i] = j[i].at(t);
}

bool TailTrajectory::finished(double t) const {
  for (const JointProfile& j : joints)
    if (!j.finished(t)) return false;
  return true;
}

double TailTrajectory::startTime() const {
  double t = joints.empty() ? 0.0 : joints[0].params().t0_s;
  for (const auto& j : joints) t = std::min(t, j.params().t0_s);
  return t;
}

double TailTrajectory::endTime() const {
  double t = 0.0;
  for (const auto& j : joints) t = std::max(t, j.t2());
  return t;
}

std::vector<double> TailTrajectory::breakpoints() const {
  std::vector<double> b;
  for (const auto& j : joints) j.breakpoints(b);
  std::sort(b.begin(), b.end());
  b.erase(std::unique(b.begin(), b.end()), b.end());
  return b;
}

double TailTrajectory::shortestPhase() const {
  double shortest = std::numeric_limits<double>::infinity();
  for (const JointProfile& j : joints)
    shortest = std::min({shortest, j.params().w_ss * j.params().dT_s, (1 - j.params().w_ss) * j.params().dT_s});
  return shortest;
}

double TailTrajectory::shortestActivePhase(double t) const {
  double shortest = std::numeric_limits<double>::infinity();
  for (const JointProfile& j : joints) {
    const SplitCycleParams& p = j.params();
    if (!(t > p.t0_s && t < j.t2())) continue;  // at rest
    shortest = std::min(shortest, j.isSpline() || t < j.t1() ? p.w_ss * p.dT_s : (1.0 - p.w_ss) * p.dT_s);
  }
  return shortest;
}

SplitCycleParams equalPeakSpeedParams(int n_links, double thetadot_max_radps, double w_ss, double t0_s) {
  if (n_links < 1) throw std::invalid_argument("Eq. 25 needs n >= 1");
  if (!(thetadot_max_radps > 0.0)) throw std::invalid_argument("thetadot_max must be > 0");
  SplitCycleParams p;
  p.dtheta_rad = -2.0 * M_PI / (n_links + 1);              // -360 deg / (n+1)
  p.dT_s = 2.0 * std::abs(p.dtheta_rad) / thetadot_max_radps;  // sign fix: a duration is positive
  p.theta0_rad = -0.5 * p.dtheta_rad;                      // sign fix: start at +180/(n+1) deg
  p.w_ss = w_ss;
  p.t0_s = t0_s;
  return p;
}

}  // namespace tailsim
