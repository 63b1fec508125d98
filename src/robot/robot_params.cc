#include "robot/robot_params.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace tailsim {

double RobotParams::tailMass() const {
  double m = 0.0;
  for (const TailLink& l : tail) m += l.mass_kg;
  return m;
}

TailLink paperTailLink(int n) {
  // Table 2 (I_zz in kg m^2; the table's "kg/m^2" is a typo).
  static const double kMass[] = {2.40, 1.20, 0.80, 0.60, 0.48, 0.40};
  static const double kIzz[] = {2.236e-2, 3.469e-3, 1.268e-3, 6.521e-4, 4.022e-4, 2.743e-4};
  static const double kLength[] = {0.300, 0.150, 0.100, 0.075, 0.060, 0.050};
  if (n < 1 || n > 6) throw std::invalid_argument("paper tails have n = 1..6 links, got " + std::to_string(n));
  return TailLink{kMass[n - 1], kIzz[n - 1], kLength[n - 1], 0.5 * kLength[n - 1]};
}

namespace {
void requireFinite(double v, const std::string& what) {
  if (!std::isfinite(v)) throw std::invalid_argument(what + " must be finite");
}
void requireNonNegative(double v, const std::string& what) {
  requireFinite(v, what);
  if (v < 0.0) throw std::invalid_argument(what + " must be >= 0, got " + std::to_string(v));
}
}  // namespace

QuadrupedParams quadrupedFromBox(const QuadrupedBox& b) {
  settings::validateFields(b, "quadruped.");
  const double l = b.size_m[0], w = b.size_m[1], h = b.size_m[2];
  for (double x : b.size_m)
    if (!(x > 0.0)) throw std::invalid_argument("quadruped.size_m must be three lengths > 0 [l, w, h]");
  if (!(l - 2.0 * b.foot_inset_m > 0.0) || !(w - 2.0 * b.foot_inset_m > 0.0))
    throw std::invalid_argument("quadruped.foot_inset_m must be less than half the box's length and width");
  QuadrupedParams q;
  q.mass_kg = b.mass_kg;
  q.izz_kgm2 = b.mass_kg * (l * l + w * w) / 12.0;
  q.d_Q2C_m = 0.0;
  q.d_Q2B_m = 0.5 * l;
  q.l_F_m = l - 2.0 * b.foot_inset_m;
  q.w_F_m = w - 2.0 * b.foot_inset_m;
  q.com_height_m = 0.5 * h;
  return q;
}

void validate(const RobotParams& p) {
  settings::validateFields(p.quadruped, "quadruped.");  // the declared ranges (robot_params.h)
  if (p.tail.empty()) throw std::invalid_argument("tail must have at least one link (n >= 1)");
  for (size_t i = 0; i < p.tail.size(); ++i) settings::validateFields(p.tail[i], "tail link " + std::to_string(i + 1) + " ");
  settings::validateFields(p.friction, "friction.");
  const FrictionParams& f = p.friction;
  if (!(f.phidot_d_radps > f.phidot_s_radps))
    throw std::invalid_argument("friction.phidot_d_radps must exceed friction.phidot_s_radps");
  if (!(f.v_d_mps > f.v_s_mps)) throw std::invalid_argument("friction.v_d_mps must exceed friction.v_s_mps");
  requireNonNegative(p.gravity_mps2, "gravity_mps2");
}

}  // namespace tailsim
