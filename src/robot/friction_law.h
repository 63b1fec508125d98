// The ADAMS ("continuous") friction law of the paper's multibody model (Sec. 3.2, Fig. 4;
// paper-notes point 6). Shared by the MuJoCo model (per-foot coefficient each step) and the
// analytic model (kContinuous).
#pragma once

namespace tailsim {

// ADAMS' STEP function: h0 for x <= x0, h1 for x >= x1, in between the cubic
// h0 + (h1 - h0) d^2 (3 - 2 d), d = (x - x0) / (x1 - x0). Requires x1 > x0.
double adamsStep(double x, double x0, double h0, double x1, double h1);

// Friction coefficient mu(v) of Fig. 4 at slip speed v (its sign is ignored: mu >= 0):
//   |v| <= v_s:        the "half step": the upper half of STEP(v, -v_s, -mu_s, v_s, mu_s),
//                      i.e. mu(0) = 0, steepest at v = 0, mu(v_s) = mu_s with zero slope.
//                      This is ADAMS' contact-friction law (the coefficient is an odd function
//                      of slip velocity, a cubic step from -mu_s to +mu_s across [-v_s, v_s]).
//   v_s < |v| < v_d:   STEP(|v|, v_s, mu_s, v_d, mu_d)   (the "full step")
//   |v| >= v_d:        mu_d
// mu is C1 in v everywhere except |v| = 0, where it has a kink (odd extension is C1).
// Requires 0 < v_s < v_d, mu_s, mu_d >= 0.
double adamsFrictionCoefficient(double slip_speed, double v_s, double v_d, double mu_s, double mu_d);

}  // namespace tailsim
