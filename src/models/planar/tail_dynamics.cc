#include "models/planar/tail_dynamics.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "numerics/sin_cos.h"

namespace tailsim {

void requireOneJointPerLink(std::size_t joints, std::size_t links) {
  if (joints != links)
    throw std::invalid_argument("the trajectory has " + std::to_string(joints) + " joint profiles for a tail of " +
                                std::to_string(links) + " links");
}

TailKinematics tailKinematics(const std::vector<TailLink>& links, const std::vector<JointState>& joints) {
  TailKinematics k;
  tailKinematics(links, joints, k);
  return k;
}

void tailKinematics(const std::vector<TailLink>& links, const std::vector<JointState>& joints, TailKinematics& k,
                    bool acceleration_part) {
  const size_t n = links.size();
  if (k.psi.size() != n) {  // sized once for a hot loop's scratch
    k.psi.resize(n); k.omega.resize(n); k.alpha.resize(n);
    k.p_J.resize(n); k.p_L.resize(n); k.v_L.resize(n); k.a_L.resize(n);
  }
  if (acceleration_part && k.a_L_acc.size() != n) k.a_L_acc.resize(n);
  double psi = 0, omega = 0, alpha = 0;
  Vec2 p_J = Vec2::Zero(), v_J = Vec2::Zero(), a_J = Vec2::Zero();  // joint 1 at the origin of B
  Vec2 a_J_acc = Vec2::Zero();  // a_J with every joint speed zeroed
  for (size_t i = 0; i < n; ++i) {
    // Eq. (1), (4) and their derivative: angles, rates and accelerations add along the chain.
    psi += joints[i].theta;
    omega += joints[i].theta_dot;
    alpha += joints[i].theta_ddot;
    const SinCos sc = sinCos(psi);
    const Vec2 e(sc.c, sc.s);  // R_T,i x
    const Vec2 r = links[i].com_offset_m * e;   // joint i -> COM i (paper: 0.5 L_L)
    k.psi[i] = psi; k.omega[i] = omega; k.alpha[i] = alpha;
    k.p_J[i] = p_J;
    k.p_L[i] = p_J + r;                                            // Eq. (3)
    k.v_L[i] = v_J + omega * perp(r);
    k.a_L[i] = a_J + alpha * perp(r) - omega * omega * r;
    // Eq. (3) (typo fixed: p_J,i+1 = p_J,i + L_L R_T,i x) and its derivatives.
    const Vec2 l = links[i].length_m * e;
    p_J += l;
    a_J += alpha * perp(l) - omega * omega * l;
    v_J += omega * perp(l);
    if (acceleration_part) {  // the same with omega = 0: no centripetal terms
      k.a_L_acc[i] = a_J_acc + alpha * perp(r);
      a_J_acc += alpha * perp(l);
    }
  }
}

TailLoad tailBaseLoad(const std::vector<TailLink>& links, const TailKinematics& k) {
  return tailBaseLoad(links, k, k.a_L);
}

TailLoad tailBaseLoad(const std::vector<TailLink>& links, const TailKinematics& k, const std::vector<Vec2>& a_L,
                      double* joint_moments) {
  const int n = static_cast<int>(links.size());
  Vec2 F_next = Vec2::Zero();  // F_J,i+1
  double M_next = 0.0;         // M_J,i+1
  for (int i = n - 1; i >= 0; --i) {
    const Vec2 F = F_next + links[i].mass_kg * a_L[i];  // Eq. (5)
    // Eq. (6) with p_L2J,i,j = p_J,j - p_L,i (Eq. 7); no joint i+1 for the tip link.
    double M = M_next + links[i].izz_kgm2 * k.alpha[i] - cross2(k.p_J[i] - k.p_L[i], F);
    if (i + 1 < n) M += cross2(k.p_J[i + 1] - k.p_L[i], F_next);
    F_next = F;
    M_next = M;
    if (joint_moments) joint_moments[i] = M;
  }
  TailLoad load;
  load.F_J1_B = F_next;
  load.M_J1 = M_next;
  return load;
}

TailLoad tailBaseLoad(const std::vector<TailLink>& links, const std::vector<JointState>& joints) {
  return tailBaseLoad(links, tailKinematics(links, joints));
}

double linkComDistance(const std::vector<TailLink>& links, const std::vector<double>& theta, int link_index) {
  std::vector<JointState> js(theta.size());
  for (size_t i = 0; i < theta.size(); ++i) js[i].theta = theta[i];
  return tailKinematics(links, js).p_L.at(link_index).norm();
}

}  // namespace tailsim
