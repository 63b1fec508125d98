#include "trajectory/split_cycle_profile.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace tailsim {

SplitCycleProfile::SplitCycleProfile(const SplitCycleParams& p) : p_(p) {
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
}

JointState SplitCycleProfile::at(double t) const {
  const double tau = t - p_.t0_s;
  if (tau <= 0.0) return {p_.theta0_rad, 0.0, 0.0};
  if (tau >= p_.dT_s) return {p_.theta0_rad + p_.dtheta_rad, 0.0, 0.0};
  // Eq. (20) integrated twice with Eq. (22)'s conditions at t0.
  const double ka = M_PI / da_;
  if (tau <= da_) {
    const double s = std::sin(ka * tau), c = std::cos(ka * tau);
    return {p_.theta0_rad + A_ / ka * (tau - s / ka), A_ / ka * (1.0 - c), A_ * s};
  }
  const double sigma = tau - da_;
  const double kd = M_PI / dd_;
  const double w1 = 2.0 * A_ / ka;                       // peak speed at t1
  const double th1 = p_.theta0_rad + A_ * da_ * da_ / M_PI;  // angle at t1
  const double s = std::sin(kd * sigma), c = std::cos(kd * sigma);
  return {th1 + w1 * sigma - B_ / kd * (sigma - s / kd), w1 - B_ / kd * (1.0 - c), -B_ * s};
}

void TailTrajectory::evaluate(double t, std::vector<JointState>& out) const {
  out.resize(joints.size());
  for (size_t i = 0; i < joints.size(); ++i) out[i] = joints[i].at(t);
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
  for (const auto& j : joints) {
    b.push_back(j.params().t0_s);
    b.push_back(j.t1());
    b.push_back(j.t2());
  }
  std::sort(b.begin(), b.end());
  b.erase(std::unique(b.begin(), b.end()), b.end());
  return b;
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
