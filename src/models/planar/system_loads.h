// The tail's net load on the quadruped about the system COM (paper Eqs. 10-13, 24), in the
// quadruped frame Q (origin at the quadruped COM, x forward). Everything here depends on the
// tail state only, not on x, y or phi: the paper's model is body-frame invariant.
#pragma once

#include "models/planar/tail_dynamics.h"

namespace tailsim {

struct SystemLoads {
  double mass_kg = 0;     // m, Eq. (10)
  double Izz_kgm2 = 0;    // I_zz about the system COM, Eq. (11)
  Vec2 p_QC = Vec2::Zero();  // system COM relative to the quadruped COM, in Q  [m] (Eq. 10)
  Vec2 p_QB = Vec2::Zero();  // tail base relative to the quadruped COM, in Q  [m]
  Vec2 F_T_Q = Vec2::Zero(); // F_T = F_B, tail force on the quadruped, in Q  [N] (Eqs. 8, 13)
  double MzT = 0;         // M_z,T about the system COM  [N m] (Eq. 13)
  // Decomposition (exact: the recursion is linear in theta_ddot, quadratic in theta_dot).
  double MzT_acc = 0;     // driven by joint accelerations alone (rotational + tangential)  [N m]
  double MzT_speed = 0;   // driven by joint speeds alone (centripetal)  [N m]
  double MzT_tan = 0;     // (m_Q/m) p_QB x F_B,acc: Eq. (24)'s tangential term, for any n  [N m]
  double MzT_cen = 0;     // (m_Q/m) p_QB x F_B,speed: Eq. (24)'s centripetal term, for any n  [N m]
};

// Mass properties only (Eqs. 10-12): no velocities needed.
void systemMassProperties(const RobotParams& robot, const TailKinematics& kin, SystemLoads& out);

// Eqs. (10)-(13). With `decompose`, also the acceleration- and speed-driven parts.
SystemLoads systemLoads(const RobotParams& robot, const std::vector<JointState>& joints, bool decompose = true);

// The same, reusing `scratch` between calls (no allocation in a hot loop).
struct LoadScratch {
  TailKinematics kin;
};
void systemLoads(const RobotParams& robot, const std::vector<JointState>& joints, bool decompose, SystemLoads& out,
                 LoadScratch& scratch);

// Eq. (24), the paper's closed form for n = 1 (used to test the recursion).
struct Eq24Terms {
  double rotational, tangential, centripetal;
  double total() const { return rotational + tangential + centripetal; }
};
Eq24Terms eq24OneLinkMoment(const RobotParams& robot, double theta, double theta_dot, double theta_ddot);

}  // namespace tailsim
