// The keys of an experiment's `trajectory:` section, declared once (fields.h style): the
// split-cycle form (the default family, Eqs. 20-23, or Eq. 25's rule) and the spline form
// (family: spline). The JSON Schema, the key tables of docs/experiment-format.md
// (experiments/settings_schema.cc) and the loader's lists of allowed keys
// (experiments/trajectory_reader.cc, case_reader.cc) derive from these declarations. The loader reads the values
// itself: a per-joint value is a number for every joint or a list of one per joint, and some keys
// exclude others (dT_s or peak_speed_dps; rule: eq25 sets the angles and durations).
//
// Besides fields.h's visitor methods, these use
//   perJoint(const Field&, double& x, Limits)   a number within Limits, or a list of one per joint
//                                               (x: the default; NaN: no default)
//   knotLists(const Field&, Limits, int max)    a list of 2..max knots within Limits, or one list per joint
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "common/work_limits.h"
#include "settings/fields.h"

namespace tailsim {

enum class TrajectoryFamily { kSplitCycle, kSpline };

inline const settings::EnumNames<TrajectoryFamily>& trajectoryFamilyNames() {
  static const settings::EnumNames<TrajectoryFamily> kNames = {{TrajectoryFamily::kSplitCycle, "split_cycle"},
                                                               {TrajectoryFamily::kSpline, "spline"}};
  return kNames;
}

// Declaration carriers: the member initializers are the defaults the loader applies.
struct SplitCycleSection {
  TrajectoryFamily family = TrajectoryFamily::kSplitCycle;
  double theta0_deg = 0.0;
  double dtheta_deg = std::numeric_limits<double>::quiet_NaN();  // required (without rule: eq25)
  double dT_s = std::numeric_limits<double>::quiet_NaN();        // this or peak_speed_dps
  double peak_speed_dps = std::numeric_limits<double>::quiet_NaN();
  double w_ss = 0.25;
  double t0_s = 0.0;
  std::string rule;  // "" or eq25
  double thetadot_max_dps = std::numeric_limits<double>::quiet_NaN();    // rule: eq25, this or _radps
  double thetadot_max_radps = std::numeric_limits<double>::quiet_NaN();
};

struct SplineSection {
  TrajectoryFamily family = TrajectoryFamily::kSpline;
  double dT_s = std::numeric_limits<double>::quiet_NaN();  // required
  double t0_s = 0.0;
};

template <class V, class S>
settings::For<S, SplitCycleSection> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  v.perJoint(Field{"theta0_deg", "start angle theta_0 [deg]"}, s.theta0_deg,
             Limits::closed(-limits::kMaxAbsTheta0Deg, limits::kMaxAbsTheta0Deg));
  v.perJoint(Field{"dtheta_deg", "required (but with rule: eq25): displacement Delta theta [deg]"}, s.dtheta_deg,
             Limits::closed(-limits::kMaxAbsDthetaDeg, limits::kMaxAbsDthetaDeg));
  v.perJoint(Field{"dT_s", "duration Delta T; exactly one of dT_s, peak_speed_dps [s]"}, s.dT_s,
             Limits::atLeast(limits::kMinDT_s));
  v.perJoint(Field{"peak_speed_dps", "peak joint speed; sets dT = 2 abs(dtheta) / peak [deg/s]"}, s.peak_speed_dps,
             Limits::positive());
  v.perJoint(Field{"w_ss", "split-cycle parameter"}, s.w_ss, Limits::closed(limits::kMinWss, limits::kMaxWss));
  v.perJoint(Field{"t0_s", "start time [s]"}, s.t0_s, Limits::nonNegative());
  v.text(Field{"rule", "eq25: the equal-peak-speed rule of Sec. 4.7, Eq. (25), sets theta0, dtheta and dT"}, s.rule,
         settings::TextRule{false, {"eq25"}});
  v.number(Field{"thetadot_max_dps", "rule: eq25: the peak joint speed [deg/s] (or thetadot_max_radps)"},
           s.thetadot_max_dps, Limits::positive());
  v.number(Field{"thetadot_max_radps", "rule: eq25: the peak joint speed [rad/s] (or thetadot_max_dps)"},
           s.thetadot_max_radps, Limits::positive());
  v.choice(Field{"family", "split_cycle (this table) or spline (the next)"}, s.family, trajectoryFamilyNames());
}

template <class V, class S>
settings::For<S, SplineSection> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  v.knotLists(Field{"knots_deg", "required: the knot angles, one list for every joint or one list per joint (the "
                                 "joints may have different knot counts) [deg]"},
              Limits::closed(-limits::kMaxAbsTheta0Deg, limits::kMaxAbsTheta0Deg),
              static_cast<int>(limits::kMaxSplineKnots));
  v.perJoint(Field{"dT_s", "required: stroke duration [s]"}, s.dT_s, Limits::atLeast(limits::kMinDT_s));
  v.perJoint(Field{"t0_s", "start time [s]"}, s.t0_s, Limits::nonNegative());
  v.choice(Field{"family", "spline: per joint a clamped cubic spline through equally spaced knots"}, s.family,
           trajectoryFamilyNames());
}

}  // namespace tailsim
