// Robot parameters shared by the analytic and the MuJoCo model (paper Tables 1, 2).
#pragma once

#include <string>
#include <vector>

namespace tailsim {

// One rigid tail link (paper Table 2). Link i turns about joint i (a z hinge).
struct TailLink {
  double mass_kg = 0.0;       // m_L,i  [kg]
  double izz_kgm2 = 0.0;      // I_zz,L,i about the link COM  [kg m^2]
  double length_m = 0.0;      // L_L: joint i to joint i+1  [m]
  double com_offset_m = 0.0;  // joint i to link COM along the link  [m] (paper: 0.5 L_L)
};

// The quadruped body with its legs fixed (paper Table 1).
struct QuadrupedParams {
  double mass_kg = 8.458;   // m_Q  [kg]
  double izz_kgm2 = 0.1916; // I_zz,Q about the quadruped COM  [kg m^2]
  double d_Q2C_m = -0.0155; // x offset, quadruped COM -> foot centroid, body frame  [m]
  double d_Q2B_m = 0.125;   // distance quadruped COM -> tail base, behind (-x)  [m]
  double l_F_m = 0.3;       // foot spacing along body x  [m]
  double w_F_m = 0.26;      // foot spacing along body y  [m]
};

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

// Paper Table 2: the n-link tail (n = 1..6), 300 mm and 2.4 kg in all.
TailLink paperTailLink(int n);

// Throws std::invalid_argument naming the offending field when a value is out of range.
void validate(const RobotParams& p);

}  // namespace tailsim
