#include "models/planar/foot_loads.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace tailsim {

std::string tippingMessage(const QuadrupedParams& q, double xe, double ye, const char* what) {
  // Which edge, and how far beyond it (the first exit is only just beyond: 9 digits and the distance).
  const double beyond_x = std::abs(xe) - 0.5 * q.l_F_m, beyond_y = std::abs(ye) - 0.5 * q.w_F_m;
  const bool side = beyond_y >= beyond_x;
  const char* edge = side ? (ye > 0 ? "left" : "right") : (xe > 0 ? "front" : "rear");
  std::ostringstream os;
  os.precision(9);
  os << what << " at (" << xe << ", " << ye << ") m from the foot centroid is outside the support "
     << "rectangle (+-" << 0.5 * q.l_F_m << ", +-" << 0.5 * q.w_F_m << ") m";
  os.precision(3);
  os << ", " << (side ? beyond_y : beyond_x) << " m beyond its " << edge << " edge: the robot tips over";
  return os.str();
}

namespace {
// Out of line: the message's stream would otherwise give every call a large stack frame.
[[noreturn]] __attribute__((noinline, cold)) void throwTipping(const QuadrupedParams& q, double xe, double ye) {
  throw TippingError(tippingMessage(q, xe, ye));
}
}  // namespace

namespace {
// Eqs. (A3)-(A5) at (xe, ye), the system COM relative to the foot centroid: the loads f (clipped:
// a negative one was zeroed). Throws TippingError outside the accepted rectangle.
[[gnu::always_inline]] inline void fractionsAt(const QuadrupedParams& q, double xe, double ye, std::array<double, 4>& f,
                                               bool& clipped) {
  const double l = q.l_F_m, w = q.w_F_m;
  if (supportMargin(q, xe, ye) < 0) throwTipping(q, xe, ye);
  // Eq. (A3) solved (paper-notes point 5): ellipse with a/b = l_F/w_F,
  //   xi = atan2(y_e, x_e w_F / l_F), b = hypot(x_e w_F / l_F, y_e).
  // Eqs. (A4)-(A5), f_i = 1/4 + B sin(xi + C_i) with B = b sqrt(2) / (2 w_F), expanded with
  // b sin(xi) = y_e, b cos(xi) = x_e w_F / l_F and C_i = 45, 135, 225, 315 deg: no trigonometry.
  //   f_1,2 = 1/4 + x_e/(2 l_F) +- y_e/(2 w_F),  f_3,4 = 1/4 - x_e/(2 l_F) -+ y_e/(2 w_F).
  // (tests/test_foot_loads.cc checks this against (A4) as printed.)
  const double ax = xe / (2.0 * l), ay = ye / (2.0 * w);
  f = {0.25 + ax + ay, 0.25 + ax - ay, 0.25 - ax - ay, 0.25 - ax + ay};
  // Every solution of Eq. (A1) is f + lambda (1, -1, 1, -1). (A4) gives lambda = 0; when a load
  // is negative (possible for b > w_F/(2 sqrt 2) off the axes), choose the lambda closest to 0
  // that makes all loads >= 0: this zeroes the negative load and solves (A1) for the other three.
  // Feasible lambda: [max(-f1, -f3), min(f2, f4)], non-empty exactly when the COM is inside.
  const double lo = std::max(-f[0], -f[2]), hi = std::min(f[1], f[3]);
  const double lambda = std::clamp(0.0, lo, std::max(lo, hi));
  clipped = false;
  if (lambda != 0.0) {
    clipped = true;
    f[0] += lambda; f[1] -= lambda; f[2] += lambda; f[3] -= lambda;
    for (double& v : f) v = std::max(v, 0.0);  // round-off at exactly zero
  }
}
}  // namespace

std::array<double, 4> footLoadFractions(const QuadrupedParams& q, double x_CC, double y_CC) {
  std::array<double, 4> f;
  bool clipped;
  fractionsAt(q, x_CC, y_CC, f, clipped);
  return f;
}

namespace {
// Eqs. (A1)-(A5), (17) and (19): the loads f (clipped: a negative one was zeroed) and L_F, the
// returned value; the foot positions into p_F unless it is null. footLoads() and frictionArm()
// share it (frictionArm, the analytic model's hot path, needs L_F alone).
[[gnu::always_inline]] inline double footLoadsCore(const QuadrupedParams& q, const Vec2& p_QC, std::array<double, 4>& f,
                                                   bool& clipped, std::array<Vec2, 4>* p_F) {
  const double l = q.l_F_m, w = q.w_F_m;
  // Eq. (A2), comFromFootCentroid in scalars; Eqs. (A3)-(A5).
  const double xe = p_QC.x() - q.d_Q2C_m, ye = p_QC.y() - 0.0;
  fractionsAt(q, xe, ye, f, clipped);
  // Eq. (17): foot positions relative to the system COM, in Q; Eq. (19): L_F. In scalars, in
  // Eigen's order ((centroid + corner) - p_QC, then x^2 + y^2): Vec2 temporaries here went through
  // the stack as two 8-byte stores read back as one 16-byte load, a store-forwarding stall each.
  static const double kX[4] = {0.5, 0.5, -0.5, -0.5}, kY[4] = {0.5, -0.5, -0.5, 0.5};
  const double cx = q.d_Q2C_m, cy = 0.0, qx = p_QC.x(), qy = p_QC.y();
  double L_F = 0;
  for (int i = 0; i < 4; ++i) {
    const double px = (cx + kX[i] * l) - qx, py = (cy + kY[i] * w) - qy;
    if (p_F) (*p_F)[i] = Vec2(px, py);
    L_F += f[i] * std::sqrt(px * px + py * py);
  }
  return L_F;
}
}  // namespace

FootLoads footLoads(const QuadrupedParams& q, const Vec2& p_QC) {
  FootLoads out;
  out.L_F = footLoadsCore(q, p_QC, out.f_C, out.clipped, &out.p_F);
  return out;
}

double frictionArm(const QuadrupedParams& q, const Vec2& p_QC) {
  std::array<double, 4> f;
  bool clipped;
  return footLoadsCore(q, p_QC, f, clipped, nullptr);
}

}  // namespace tailsim
