// Seeded random quadrupeds with planar tails and tail strokes of the paper's kinds: the test bed of
// the MuJoCo contact settings on robots other than the paper's (docs/mujoco-model.md "Contact
// settings: the rule and its evidence"). Every draw is a function of (seed, index) alone.
#pragma once

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "robot/robot_params.h"
#include "trajectory/split_cycle_profile.h"

namespace tailsim::testing {

// The two corpora of the generator: kMixed, the test bed of the contact settings; kTippy, robots
// near tipping over, the test bed of the fall signal (docs/mujoco-model.md "Tipping over").
enum class RandomCorpus { kMixed, kTippy };

struct RandomRobotCase {
  RobotParams robot;
  TailTrajectory trajectory;
  double body_length_m = 0.0;  // foot spacing along x (= l_F_m)
  const char* stroke = "";      // "eq25", "sweep" or "flick"
};

// Robot k / 3 of the corpus with stroke k % 3:
//  * whole robot 3..60 kg (log-uniform), tail 10..30 % of it, 1..6 equal links;
//  * body (foot spacing) length L 0.25..1 m, width 0.5..0.9 L; I_zz,Q of a uniform plate times
//    0.6..1.2; the foot centroid 0..5 % of L ahead or behind the COM; tail base 0.4..0.55 L behind;
//  * COM height 0.15..0.6 L; mu_s 0.2..0.9, mu_d 0.9..1.2 mu_s;
//  * tail 0.5..1.2 L long, links of I_zz = m l^2 / 12, COM at mid-link;
//  * strokes: eq25 (Eq. 25, peak joint speed 300..900 deg/s, w_ss 0.25), sweep (every joint
//    +-(180..360 deg) / (n + 1) in 0.15..0.5 s, w_ss 0.2..0.5, from 0), flick (every joint
//    +-(120..360 deg) / (n + 1) in 0.08..0.25 s, w_ss 0.1..0.3, centred on 0).
// kTippy: robot k / 2 with stroke k % 2, the same draws with a high COM (0.45..0.6 L), a narrow
// stance (W 0.3..0.5 L), a heavy tail (25..40 %) and fast strokes only: eq25 at 600..900 deg/s
// and flick in 0.08..0.15 s. Seeds 31-33, 90 cases each: 55 % fall in the converged reference,
// 87 % tip in the per-foot model with load transfer (docs/mujoco-model.md "Tipping over").
inline RandomRobotCase randomRobotCase(unsigned seed, int k, RandomCorpus corpus = RandomCorpus::kMixed) {
  const bool tippy = corpus == RandomCorpus::kTippy;
  const int strokes = tippy ? 2 : 3;
  std::mt19937 rng(seed * 7919u + static_cast<unsigned>(k / strokes));
  std::uniform_real_distribution<double> U(0.0, 1.0);
  auto u = [&](double a, double b) { return a + (b - a) * U(rng); };
  RandomRobotCase c;
  RobotParams& r = c.robot;
  const double M = std::exp(u(std::log(3.0), std::log(60.0)));
  const double tail_share = tippy ? u(0.25, 0.4) : u(0.1, 0.3);
  const int n = 1 + static_cast<int>(u(0.0, 6.0)) % 6;
  const double L = u(0.25, 1.0), W = (tippy ? u(0.3, 0.5) : u(0.5, 0.9)) * L;
  c.body_length_m = L;
  QuadrupedParams& q = r.quadruped;
  q.mass_kg = M * (1.0 - tail_share);
  q.izz_kgm2 = q.mass_kg * (L * L + W * W) / 12.0 * u(0.6, 1.2);
  q.l_F_m = L;
  q.w_F_m = W;
  q.d_Q2C_m = u(-0.05, 0.05) * L;
  q.d_Q2B_m = u(0.4, 0.55) * L;
  q.com_height_m = (tippy ? u(0.45, 0.6) : u(0.15, 0.6)) * L;
  r.friction.mu_s = u(0.2, 0.9);
  r.friction.mu_d = r.friction.mu_s * u(0.9, 1.2);
  const double tail_len = u(0.5, 1.2) * L;
  for (int i = 0; i < n; ++i) {
    TailLink l;
    l.mass_kg = M * tail_share / n;
    l.length_m = tail_len / n;
    l.izz_kgm2 = l.mass_kg * l.length_m * l.length_m / 12.0;
    l.com_offset_m = 0.5 * l.length_m;
    r.tail.push_back(l);
  }
  // The stroke: its own stream, so the three strokes of a robot share the robot.
  std::mt19937 srng(seed * 104729u + static_cast<unsigned>(k));
  std::uniform_real_distribution<double> S(0.0, 1.0);
  auto s = [&](double a, double b) { return a + (b - a) * S(srng); };
  const double sign = S(srng) < 0.5 ? -1.0 : 1.0;
  const double kDeg = M_PI / 180.0;
  switch (tippy ? 2 * (k % 2) : k % 3) {  // tippy: eq25 or flick
    case 0: {
      c.stroke = "eq25";
      const SplitCycleParams p = equalPeakSpeedParams(n, (tippy ? s(600.0, 900.0) : s(300.0, 900.0)) * kDeg, 0.25);
      for (int i = 0; i < n; ++i) c.trajectory.joints.emplace_back(p);
      break;
    }
    case 1: {
      c.stroke = "sweep";
      const SplitCycleParams p{0.0, sign * s(180.0, 360.0) / (n + 1) * kDeg, s(0.15, 0.5), s(0.2, 0.5), 0.0};
      for (int i = 0; i < n; ++i) c.trajectory.joints.emplace_back(p);
      break;
    }
    default: {
      c.stroke = "flick";
      const double dth = sign * s(120.0, 360.0) / (n + 1) * kDeg;
      const SplitCycleParams p{-0.5 * dth, dth, tippy ? s(0.08, 0.15) : s(0.08, 0.25), s(0.1, 0.3), 0.0};
      for (int i = 0; i < n; ++i) c.trajectory.joints.emplace_back(p);
      break;
    }
  }
  return c;
}

// One line a person can rebuild the case from.
inline std::string describe(const RandomRobotCase& c) {
  const RobotParams& r = c.robot;
  const SplitCycleParams& p = c.trajectory.joints.front().params();
  char b[320];
  std::snprintf(b, sizeof b,
                "m=%.2f kg L=%.3f W=%.3f h=%.3f mu=%.2f n=%d tail=%.3f m %.2f kg %s dtheta=%.1f deg dT=%.3f w_ss=%.2f",
                r.systemMass(), r.quadruped.l_F_m, r.quadruped.w_F_m, r.quadruped.com_height_m, r.friction.mu_s,
                r.numLinks(), r.tail.front().length_m * r.numLinks(), r.tailMass(), c.stroke,
                p.dtheta_rad * 180.0 / M_PI, p.dT_s, p.w_ss);
  return b;
}

}  // namespace tailsim::testing
