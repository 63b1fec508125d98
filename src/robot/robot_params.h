// Robot parameters shared by the analytic and the MuJoCo model (paper Tables 1, 2).
#pragma once

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "settings/fields.h"
#include "common/units.h"

namespace tailsim {

// One rigid tail link (paper Table 2). Link i turns about joint i (a z hinge).
struct TailLink {
  double mass_kg = 0.0;       // m_L,i  [kg]
  double izz_kgm2 = 0.0;      // I_zz,L,i about the link COM  [kg m^2]
  double length_m = 0.0;      // L_L: joint i to joint i+1  [m]
  double com_offset_m = 0.0;  // joint i to link COM along the link  [m] (paper: 0.5 L_L)
  // Joint i's actuator and range (the design tool's limits; the simulations do not enforce them).
  // 0 = not given (a range is given when theta_min_rad < theta_max_rad).
  double torque_max_Nm = 0.0;       // peak joint torque |tau_i|  [N m]
  double thetadot_max_radps = 0.0;  // peak joint speed |thetadot_i|  [rad/s]
  double theta_min_rad = 0.0, theta_max_rad = 0.0;  // joint angle range  [rad]
  bool hasRange() const { return theta_min_rad < theta_max_rad; }
};

// The quadruped body with its legs fixed (paper Table 1).
struct QuadrupedParams {
  double mass_kg = 8.458;   // m_Q  [kg]
  double izz_kgm2 = 0.1916; // I_zz,Q about the quadruped COM  [kg m^2]
  double d_Q2C_m = -0.0155; // x offset, quadruped COM -> foot centroid, body frame  [m]
  double d_Q2B_m = 0.125;   // distance quadruped COM -> tail base, behind (-x)  [m]
  double l_F_m = 0.3;       // foot spacing along body x  [m]
  double w_F_m = 0.26;      // foot spacing along body y  [m]
  // Height of the COM above the foot contacts  [m]: the per-foot model's load transfer and the
  // MuJoCo body height (the one COM-height key); the paper's models ignore it.
  double com_height_m = 0.15;
};

// A quadruped given by its size (docs/experiment-format.md "A robot given by its size"): a uniform
// box l x w x h (x forward, z up) standing on four feet at the corners of its footprint, each foot
// inset foot_inset_m from the box's edges in x and y. quadrupedFromBox turns it into QuadrupedParams.
struct QuadrupedBox {
  double mass_kg = 0.0;                // m_Q  [kg]
  std::array<double, 3> size_m{};      // [l, w, h]: length (x), width (y), height (z)  [m]
  double foot_inset_m = 0.02;          // feet this far inside the footprint's edges, in x and y  [m]
};

// I_zz = m (l^2 + w^2) / 12 (uniform box about its centre), l_F = l - 2 inset, w_F = w - 2 inset,
// d_Q2C = 0 (feet centred under the COM), d_Q2B = l / 2 (tail base at the middle of the rear face),
// com_height = h / 2 (the box's centre, its bottom face at the foot contacts). Throws
// std::invalid_argument naming the key when the box has no footprint left after the inset.
QuadrupedParams quadrupedFromBox(const QuadrupedBox& b);

// Foot-ground friction (paper Table 1, Fig. 4; paper-notes points 1 and 6).
struct FrictionParams {
  double mu_s = 0.25;            // static coefficient (as printed in Table 1)
  double mu_d = 0.30;            // dynamic coefficient (as printed in Table 1)
  double phidot_s_radps = 0.05;  // continuous law: mu reaches mu_s at this yaw rate  [rad/s]
  double phidot_d_radps = 0.5;   // continuous law: mu reaches mu_d at this yaw rate  [rad/s]
  double v_s_mps = 0.05;         // continuous law, translation: same numbers in m/s (a choice)
  double v_d_mps = 0.5;          // [m/s]
};

struct RobotParams {
  QuadrupedParams quadruped;
  std::vector<TailLink> tail;  // link 1 (at the base) .. link n (the tip)
  FrictionParams friction;
  double gravity_mps2 = 9.81;  // g  [m/s^2]

  int numLinks() const { return static_cast<int>(tail.size()); }
  double tailMass() const;
  double systemMass() const { return quadruped.mass_kg + tailMass(); }  // Eq. (10)
};

// The YAML/JSON keys of the robot's parts (settings/fields.h), declared once. Ranges: those of
// validate(); the masses' work limits [kMinMassKg, kMaxMassKg] are checked by the loader.
template <class V, class S>
settings::For<S, QuadrupedParams> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  v.number(Field{"mass_kg", "m_Q, quadruped mass [kg]"}, s.mass_kg, Limits::positive());
  v.number(Field{"izz_kgm2", "I_zz,Q about the quadruped COM [kg m^2]"}, s.izz_kgm2, Limits::positive());
  v.number(Field{"d_Q2C_m", "x offset quadruped COM -> foot centroid, body frame [m]"}, s.d_Q2C_m, Limits::any());
  v.number(Field{"d_Q2B_m", "distance quadruped COM -> tail base, behind (-x) [m]"}, s.d_Q2B_m, Limits::nonNegative());
  v.number(Field{"l_F_m", "foot spacing along body x [m]"}, s.l_F_m, Limits::positive());
  v.number(Field{"w_F_m", "foot spacing along body y [m]"}, s.w_F_m, Limits::positive());
  v.number(Field{"com_height_m", "COM height above the foot contacts [m]: per-foot load transfer, MuJoCo body "
                                 "height (optional in a robot file; default 0.15)"},
           s.com_height_m, Limits::positive());
}
// The keys of the size form `quadruped: {mass_kg, size_m, foot_inset_m}` (mass_kg shared with the
// explicit form above).
template <class V, class S>
settings::For<S, QuadrupedBox> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  v.number(Field{"mass_kg", "m_Q, quadruped mass [kg]"}, s.mass_kg, Limits::positive());
  v.numbers(Field{"size_m", "[l, w, h]: a uniform box on feet at its footprint's corners; sets izz_kgm2, l_F_m, "
                            "w_F_m, d_Q2C_m = 0, d_Q2B_m = l/2, com_height_m = h/2 [m]"},
            s.size_m);
  v.number(Field{"foot_inset_m", "size_m only: feet this far inside the footprint's edges in x and y [m]"},
           s.foot_inset_m, Limits::nonNegative());
}
template <class V, class S>
settings::For<S, FrictionParams> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  v.number(Field{"mu_s", "static coefficient (Table 1)"}, s.mu_s, Limits::nonNegative());
  v.number(Field{"mu_d", "dynamic coefficient (Table 1)"}, s.mu_d, Limits::nonNegative());
  v.number(Field{"phidot_s_radps", "continuous law: mu reaches mu_s at this yaw rate; required only with "
                                   "effects.friction: continuous [rad/s]"}, s.phidot_s_radps,
           Limits::positive());
  v.number(Field{"phidot_d_radps", "continuous law: mu reaches mu_d at this yaw rate (> phidot_s_radps) [rad/s]"},
           s.phidot_d_radps, Limits::positive());
  v.number(Field{"v_s_mps", "continuous law, translation: mu_s at this slip speed [m/s]"}, s.v_s_mps,
           Limits::positive());
  v.number(Field{"v_d_mps", "continuous law, translation: mu_d at this slip speed (> v_s_mps) [m/s]"}, s.v_d_mps,
           Limits::positive());
}
template <class V, class S>
settings::For<S, TailLink> declareFields(V& v, S& s) {
  using settings::Field;
  using settings::Limits;
  v.number(Field{"mass_kg", "m_L,i, link mass [kg]"}, s.mass_kg, Limits::positive());
  v.number(Field{"izz_kgm2", "I_zz,L,i about the link COM [kg m^2]"}, s.izz_kgm2, Limits::positive());
  v.number(Field{"length_m", "joint i to joint i+1 [m]"}, s.length_m, Limits::positive());
  v.number(Field{"com_offset_m", "joint i to the link COM along the link; absent = 0.5 length_m [m]"}, s.com_offset_m,
           Limits::nonNegative());
  constexpr double kRad = units::kRadPerDeg;
  v.number(Field{"torque_max_Nm", "joint i's actuator: peak torque [N m]; 0 or absent = not given (the design "
                                  "tool then needs a limit in its file)"},
           s.torque_max_Nm, Limits::nonNegative());
  v.number(Field{"thetadot_max_dps", "joint i's actuator: peak speed [deg/s]; 0 or absent = not given", kRad,
                 "thetadot_max_radps"},
           s.thetadot_max_radps, Limits::nonNegative());
  v.number(Field{"theta_min_deg", "joint i's angle range, lower end [deg] (a range is given when min < max)", kRad,
                 "theta_min_rad"},
           s.theta_min_rad, Limits::any());
  v.number(Field{"theta_max_deg", "joint i's angle range, upper end [deg]", kRad, "theta_max_rad"}, s.theta_max_rad,
           Limits::any());
}
// Paper Table 2: the n-link tail (n = 1..6), 300 mm and 2.4 kg in all.
TailLink paperTailLink(int n);

// Throws std::invalid_argument naming the offending field when a value is out of range.
void validate(const RobotParams& p);

}  // namespace tailsim
