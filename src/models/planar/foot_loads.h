// Foot-load distribution and friction moment arm L_F (paper Eqs. 17-19, Appendix A1-A5).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include "models/planar/tail_dynamics.h"

namespace tailsim {

// The system COM left the feet's support rectangle: the robot tips; no friction arm exists.
struct TippingError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Feet: 1 front-left (+x,+y), 2 front-right (+x,-y), 3 rear-right (-x,-y), 4 rear-left (-x,+y).
struct FootLoads {
  std::array<double, 4> f_C{};  // f_C,i: fraction of the weight on foot i (sum 1, each >= 0)
  std::array<Vec2, 4> p_F{};    // p_F,i: foot i relative to the system COM, in Q  [m] (Eq. 17)
  double L_F = 0;               // Eq. (19)  [m]
  bool clipped = false;         // the (A4) fit gave a negative load that was zeroed (b > 0.5 w_F fallback)
};

// A COM this far (times l_F + w_F) beyond an edge of the support rectangle still stands: the
// pre-run check (support_check.h) resolves margins to this, and footLoads allows twice it, so a
// run the check passed never tips in footLoads (0.06 nm on the paper's feet: round-off, not physics).
constexpr double kSupportSlack = 1e-10;

// Eq. (A2), typo fixed: the system COM relative to the foot centroid, in Q (the centroid offset is
// body-fixed, so it is subtracted in Q). p_QC: system COM relative to the quadruped COM, in Q.
inline Vec2 comFromFootCentroid(const QuadrupedParams& q, const Vec2& p_QC) { return p_QC - Vec2(q.d_Q2C_m, 0.0); }

// How far beyond each edge footLoads still accepts a COM: an edge up to round-off still stands.
inline double supportSlack(const QuadrupedParams& q) { return 2.0 * kSupportSlack * (q.l_F_m + q.w_F_m); }

// How far a point p_CC (relative to the foot centroid, in Q) is inside the support rectangle that
// footLoads accepts (supportSlack beyond the edges): >= 0 standing, < 0 tipping.
inline double supportMargin(const QuadrupedParams& q, double x_CC, double y_CC) {
  const double slack = supportSlack(q);
  return std::min(0.5 * q.l_F_m + slack - std::abs(x_CC), 0.5 * q.w_F_m + slack - std::abs(y_CC));
}
inline double supportMargin(const QuadrupedParams& q, const Vec2& p_CC) { return supportMargin(q, p_CC.x(), p_CC.y()); }

// p_QC: system COM relative to the quadruped COM, in Q.  Throws TippingError outside the
// support rectangle (beyond 2 kSupportSlack (l_F + w_F)).
FootLoads footLoads(const QuadrupedParams& q, const Vec2& p_QC);
// footLoads(q, p_QC).f_C for the point (x_CC, y_CC) relative to the foot centroid (in Q), given
// directly: a point clamped onto the accepted rectangle stays on it (no round trip through p_QC,
// whose rounding can put it 1 ulp outside). Throws TippingError outside.
std::array<double, 4> footLoadFractions(const QuadrupedParams& q, double x_CC, double y_CC);
// footLoads(q, p_QC).L_F alone (the same arithmetic, bit for bit, and the same TippingError).
double frictionArm(const QuadrupedParams& q, const Vec2& p_QC);

// The TippingError message for a system COM (or `what`, e.g. the load transfer's centre of
// pressure) at (xe, ye) from the foot centroid.
std::string tippingMessage(const QuadrupedParams& q, double xe, double ye, const char* what = "system COM");

}  // namespace tailsim
