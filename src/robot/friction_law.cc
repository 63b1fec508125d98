#include "robot/friction_law.h"

#include <cmath>

namespace tailsim {

double adamsStep(double x, double x0, double h0, double x1, double h1) {
  if (x <= x0) return h0;
  if (x >= x1) return h1;
  const double d = (x - x0) / (x1 - x0);
  return h0 + (h1 - h0) * d * d * (3.0 - 2.0 * d);
}

double adamsFrictionCoefficient(double slip_speed, double v_s, double v_d, double mu_s, double mu_d) {
  const double v = std::abs(slip_speed);
  if (v <= v_s) return adamsStep(v, -v_s, -mu_s, v_s, mu_s);  // half step: mu(0) = 0
  return adamsStep(v, v_s, mu_s, v_d, mu_d);                    // full step mu_s -> mu_d
}

}  // namespace tailsim
