#include "models/planar/system_loads.h"

#include <stdexcept>

namespace tailsim {

void systemMassProperties(const RobotParams& robot, const TailKinematics& kin, SystemLoads& s) {
  // In scalars, in Eigen's order (element-wise, then x^2 + y^2): Vec2 temporaries went through the
  // stack as two 8-byte stores read back as one 16-byte load (a store-forwarding stall each).
  const QuadrupedParams& q = robot.quadruped;
  const double bx = -q.d_Q2B_m, by = 0.0;  // p_QB
  double sx = 0.0, sy = 0.0;
  double tail_mass = 0.0;  // robot.tailMass(), summed in the same order
  const size_t n = kin.p_L.size();
  const TailLink* links = robot.tail.data();
  const Vec2* p_L = kin.p_L.data();
  for (size_t i = 0; i < n; ++i) {
    const double m = links[i].mass_kg;
    sx += m * (bx - p_L[i].x());
    sy += m * (by - p_L[i].y());
    tail_mass += m;
  }
  const double mass = q.mass_kg + tail_mass;  // Eq. (10), robot.systemMass()
  // Eq. (10), quadruped COM at the origin of Q; R_Z(180 deg) v = -v
  const double cx = sx / mass, cy = sy / mass;
  double I = q.izz_kgm2 + q.mass_kg * (cx * cx + cy * cy);  // Eqs. (11)-(12)
  for (size_t i = 0; i < n; ++i) {
    const double dx = (bx - p_L[i].x()) - cx, dy = (by - p_L[i].y()) - cy;
    I += links[i].izz_kgm2 + links[i].mass_kg * (dx * dx + dy * dy);
  }
  s.mass_kg = mass;
  s.p_QC = Vec2(cx, cy);
  s.p_QB = Vec2(bx, by);
  s.Izz_kgm2 = I;
}

namespace {
// Eq. (8) and (13) from a base-frame load: F_B in Q, and M_z,T about the system COM.
void netTailLoad(const TailLoad& l, const Vec2& p_CB, Vec2& F_Q, double& MzT) {
  F_Q = -(-l.F_J1_B);  // F_B = -R_B F_J,1 with R_B = R_Q R_Z(180 deg): in Q, -R_Z(180) F = F
  const double MzB = -l.M_J1;  // M_B = -R_B M_J,1; a z rotation keeps the z component
  MzT = MzB + cross2(p_CB, F_Q);  // Eq. (13)
}
}  // namespace

SystemLoads systemLoads(const RobotParams& robot, const std::vector<JointState>& joints, bool decompose) {
  SystemLoads s;
  LoadScratch scratch;
  systemLoads(robot, joints, decompose, s, scratch);
  return s;
}

void systemLoads(const RobotParams& robot, const std::vector<JointState>& joints, bool decompose, SystemLoads& s,
                 LoadScratch& scratch) {
  TailKinematics& kin = scratch.kin;
  tailKinematics(robot.tail, joints, kin, decompose);
  systemMassProperties(robot, kin, s);
  // p_B - p_COM, from scalar reads: systemMassProperties stored p_QB and p_QC one double at a time,
  // and a packed read of them stalled on store forwarding.
  const Vec2 p_CB(s.p_QB.x() - s.p_QC.x(), s.p_QB.y() - s.p_QC.y());
  netTailLoad(tailBaseLoad(robot.tail, kin), p_CB, s.F_T_Q, s.MzT);
  if (decompose) {
    Vec2 F_acc, F_speed;
    netTailLoad(tailBaseLoad(robot.tail, kin, kin.a_L_acc), p_CB, F_acc, s.MzT_acc);  // acceleration-driven
    // Speed-driven: the rest. The planar Newton-Euler loads are linear in the joint accelerations
    // and carry no other term (no gravity in the plane), so total = acceleration- + speed-driven
    // to round-off (test SystemLoads.DecompositionPartsSumToTheTotal): one recursion, not two.
    F_speed = s.F_T_Q - F_acc;
    s.MzT_speed = s.MzT - s.MzT_acc;
    const double mQ_over_m = robot.quadruped.mass_kg / s.mass_kg;
    // p_B - p_COM = (m_Q/m)(p_B - p_Q) + sum (m_i/m)(p_B - p_L,i): the first part carries d_Q2B.
    s.MzT_tan = mQ_over_m * cross2(s.p_QB, F_acc);
    s.MzT_cen = mQ_over_m * cross2(s.p_QB, F_speed);
  }
}

Eq24Terms eq24OneLinkMoment(const RobotParams& robot, double theta, double theta_dot, double theta_ddot) {
  if (robot.tail.size() != 1) throw std::invalid_argument("Eq. (24) is for a one-link tail");
  const TailLink& l = robot.tail[0];
  const double mQ = robot.quadruped.mass_kg, m = robot.systemMass();
  const double L = l.length_m;
  const double Ieff = mQ * l.mass_kg / (2.0 * m) * L * robot.quadruped.d_Q2B_m;
  return {-(l.izz_kgm2 + 0.25 * l.mass_kg * L * L * mQ / m) * theta_ddot,
          -Ieff * theta_ddot * std::cos(theta), Ieff * theta_dot * theta_dot * std::sin(theta)};
}

}  // namespace tailsim
