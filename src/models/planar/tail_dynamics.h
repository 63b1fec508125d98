// Tail kinematics (paper Eqs. 1-4) and recursive Newton-Euler base load (Eqs. 5-8), all in
// the tail base frame B, which the paper's model treats as inertial.
//
// Frame B: origin at the tail base (joint 1), x along the body's -x (R_B = R_Q R_Z(180 deg)).
// Link i's absolute angle in B is psi_i = theta_1 + ... + theta_i.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "numerics/sin_cos.h"
#include "robot/robot_params.h"
#include "trajectory/split_cycle_profile.h"

namespace tailsim {

using Vec2 = Eigen::Vector2d;

inline double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }
inline Vec2 perp(const Vec2& a) { return Vec2(-a.y(), a.x()); }  // z x a
// By the angle whose cosine and sine are c and s.
inline Vec2 rotate(double c, double s, const Vec2& a) { return Vec2(c * a.x() - s * a.y(), s * a.x() + c * a.y()); }
inline Vec2 rotate(double angle, const Vec2& a) {
  const SinCos sc = sinCos(angle);
  return rotate(sc.c, sc.s, a);
}

// Throws std::invalid_argument unless there is one joint state (or profile) per tail link: the
// recursions read joint i for link i.
void requireOneJointPerLink(std::size_t joints, std::size_t links);

// Link-by-link kinematics in frame B.
struct TailKinematics {
  std::vector<double> psi, omega, alpha;  // link angle, angular velocity, angular acceleration (Eq. 4)
  std::vector<Vec2> p_J;                  // joint i position (Eq. 3, with the paper-notes misprint fix)
  std::vector<Vec2> p_L, v_L, a_L;        // link i COM position, velocity, acceleration
  // Link i COM acceleration from the joint accelerations alone (joint speeds zeroed): filled
  // only when tailKinematics is asked for it (the acceleration-driven part of M_z,T).
  std::vector<Vec2> a_L_acc;
};

TailKinematics tailKinematics(const std::vector<TailLink>& links, const std::vector<JointState>& joints);
// The same into `out`, reusing its storage (no allocation once sized): for hot loops. With
// `acceleration_part`, also out.a_L_acc, in the same pass (the same angles, no second sin/cos).
void tailKinematics(const std::vector<TailLink>& links, const std::vector<JointState>& joints, TailKinematics& out,
                    bool acceleration_part = false);

// Load of link 1 on the base, as the paper writes it: F_J,1 and M_J,1 (Eqs. 5-6) in B.
// The quadruped feels F_B = -R_B F_J,1, M_B = -M_J,1 (Eq. 8).
struct TailLoad {
  Vec2 F_J1_B = Vec2::Zero();  // [N] force link 1 needs from the base, in B
  double M_J1 = 0.0;           // [N m] z moment link 1 needs from the base, about joint 1
};

// Recursive Newton-Euler from link n to link 1 (Eqs. 5-7).
TailLoad tailBaseLoad(const std::vector<TailLink>& links, const TailKinematics& kin);
// The same with the link COM accelerations a_L given (e.g. kin.a_L_acc: the load of the joint
// accelerations alone); positions and angular accelerations from kin. With `joint_moments` (one
// value per link), also every joint's moment M_J,i: the torque joint i's motor gives, the tail
// base held still (the one recursion of the tail's loads).
TailLoad tailBaseLoad(const std::vector<TailLink>& links, const TailKinematics& kin, const std::vector<Vec2>& a_L,
                      double* joint_moments = nullptr);
TailLoad tailBaseLoad(const std::vector<TailLink>& links, const std::vector<JointState>& joints);

// Distance from the tail base to link i's COM (used for the Sec. 4.7 check).
double linkComDistance(const std::vector<TailLink>& links, const std::vector<double>& theta, int link_index);

}  // namespace tailsim
