#include "models/planar/stick_slip.h"

#include <algorithm>
#include <cmath>

#include "robot/friction_law.h"

namespace tailsim {

SlidingFriction slidingFriction(FrictionLaw law, const FrictionParams& fp, double weight, double L_F,
                                double rot_dir, double phi_dot, double vx, double vy, double v_reg) {
  SlidingFriction f;
  const double speed = std::sqrt(vx * vx + vy * vy);  // v.norm()
  switch (law) {
    case FrictionLaw::kNone:
      break;
    case FrictionLaw::kStiction:
      f.MzF = -fp.mu_d * weight * L_F * rot_dir;                                // Eq. (16), sliding
      if (speed > 0.0) {  // Eq. (15), sliding
        const double k = -fp.mu_d * weight, d = std::max(speed, v_reg);
        f.FF = Vec2(k * vx / d, k * vy / d);
      }
      break;
    case FrictionLaw::kContinuous: {
      const double w = phi_dot;
      const double mu_r = adamsFrictionCoefficient(std::abs(w), fp.phidot_s_radps, fp.phidot_d_radps, fp.mu_s, fp.mu_d);
      f.MzF = -mu_r * weight * L_F * (w > 0 ? 1.0 : (w < 0 ? -1.0 : 0.0));
      if (speed > 0.0) {
        const double k = -adamsFrictionCoefficient(speed, fp.v_s_mps, fp.v_d_mps, fp.mu_s, fp.mu_d) * weight;
        f.FF = Vec2(k * vx / speed, k * vy / speed);
      }
      break;
    }
  }
  return f;
}

int dofToSwitch(const Modes& m, const Margins& g, bool translation) {
  int which = -1;
  for (int w : {kRot, kTrans})
    if (m.stuck[w] && g[w] <= 0) which = w;
  if (which < 0 && translation && !m.stuck[kTrans] && g[kTrans] < 0) which = kTrans;
  if (which < 0 && !m.stuck[kRot] && g[kRot] < 0) which = kRot;
  return which;
}

}  // namespace tailsim
