// Seeded random analytic cases over the valid parameter ranges: the tail of the distribution
// (worst-case work, failures, NaN) that hand-picked hard cases miss.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "models/planar/stick_slip.h"
#include "analytic_test_util.h"

namespace tailsim::testing {

struct RandomCase {
  RobotParams robot;
  TailTrajectory trajectory;
  AnalyticSettings settings;
  Effects effects;
};

// Case k of the sweep with this seed: n = 1..6 links, d_Q2B 0..0.15 m, mu_s and mu_d 0..1,
// dT 0.05..1 s, w_ss 0.02..0.98, per-joint theta0 -90..90 deg, dtheta -180..180 deg, start delay
// 0..0.1 s; 80 % stiction, 10 % the continuous law, 10 % no friction; 30 % exact coupling.
// One line a person can rebuild the case from.
inline std::string describe(const RandomCase& c) {
  char b[256];
  const SplitCycleParams& p = c.trajectory.joints.front().params();
  const char* law = c.effects.friction == FrictionLaw::kStiction ? "stiction"
                    : c.effects.friction == FrictionLaw::kContinuous ? "continuous" : "none";
  std::snprintf(b, sizeof b, "n=%d d_Q2B=%.4f mu_s=%.3f mu_d=%.3f dT=%.3f w_ss=%.3f theta0_1=%.1f dtheta_1=%.1f %s %s",
                c.robot.numLinks(), c.robot.quadruped.d_Q2B_m, c.robot.friction.mu_s, c.robot.friction.mu_d, p.dT_s,
                p.w_ss, p.theta0_rad * 180 / M_PI, p.dtheta_rad * 180 / M_PI, law,
                c.settings.coupling == Coupling::kExact ? "exact" : "paper");
  return b;
}

class RandomCases {
 public:
  explicit RandomCases(unsigned seed) : rng_(seed) {}
  RandomCase next() {
    RandomCase c;
    const int n = 1 + static_cast<int>(u() * 6) % 6;
    c.robot = paperRobot(n, 0.15 * u());
    c.robot.friction.mu_s = u();
    c.robot.friction.mu_d = u();
    const double dT = 0.05 + 0.95 * u(), w = 0.02 + 0.96 * u();
    for (int i = 0; i < n; ++i)
      c.trajectory.joints.emplace_back(SplitCycleParams{deg(-90 + 180 * u()), deg(-180 + 360 * u()), dT, w, 0.1 * u()});
    const double law = u();
    c.effects.friction = law < 0.8 ? FrictionLaw::kStiction : (law < 0.9 ? FrictionLaw::kContinuous : FrictionLaw::kNone);
    if (u() < 0.3) c.settings.coupling = Coupling::kExact;
    return c;
  }

 private:
  double u() { return dist_(rng_); }
  std::mt19937 rng_;
  std::uniform_real_distribution<double> dist_{0.0, 1.0};
};

// The largest value of a load measure over a stroke, found without a simulator (the critical
// friction coefficient of the edge-of-stiction tests): samples every h from 0 to the tail's end,
// both sides of every breakpoint, and golden section around the five highest local maxima of the
// samples. `many(times)` gives the measure at many times at once, `one(t)` at one.
template <class One, class Many>
double strokeMaximum(const TailTrajectory& tr, double h, const One& one, const Many& many) {
  std::vector<double> times;
  for (long i = 0; i * h <= tr.endTime() + h; ++i) times.push_back(i * h);
  const std::vector<double> v = many(times);
  std::vector<std::pair<double, double>> peaks;  // (value, t) of local maxima of the samples
  for (size_t i = 1; i + 1 < v.size(); ++i)
    if (v[i] >= v[i - 1] && v[i] >= v[i + 1]) peaks.emplace_back(v[i], times[i]);
  double best = std::max(v.front(), v.back());
  for (double b : tr.breakpoints())
    for (double t : {b, std::nextafter(b, 0.0), b - 1e-12}) best = std::max(best, one(t));
  std::sort(peaks.rbegin(), peaks.rend());
  for (size_t p = 0; p < std::min<size_t>(5, peaks.size()); ++p) {
    const auto [tm, neg] = goldenMin([&](double t) { return -one(t); }, std::max(0.0, peaks[p].second - h),
                                     peaks[p].second + h, 1e-13);
    best = std::max({best, peaks[p].first, -neg});
  }
  return best;
}

}  // namespace tailsim::testing
