// Degrees and radians: the one conversion between them. Inside tailsim every angle is in radians;
// degrees appear only at the edges (YAML keys and CSV columns named *_deg, *_dps, console text).
// degrees(x) and radians(x) compute x * 180 / pi and x * pi / 180 in that order (one rounding
// each of the product and the quotient), kDegPerRad and kRadPerDeg are the rounded constants
// 180 / pi and pi / 180 for code that multiplies by a constant: the two differ in the last bit
// for some x, so a call keeps the form its output was written with.
#pragma once

#include <cmath>

namespace tailsim::units {

constexpr double kDegPerRad = 180.0 / M_PI;
constexpr double kRadPerDeg = M_PI / 180.0;

constexpr double degrees(double rad) { return rad * 180.0 / M_PI; }
constexpr double radians(double deg) { return deg * M_PI / 180.0; }

}  // namespace tailsim::units
