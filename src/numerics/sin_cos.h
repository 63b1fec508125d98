// sin and cos of one angle together in about 45 instructions instead of libm sincos's ~110, on the angles
// the models evaluate most (the split-cycle phase, the link angles, the yaw: |x| <= 16 rad), to
// within 1 ulp of 1 absolute error (docs/scale.md "sin and cos from a table").
//
// x = k/64 + d with k the integer nearest 64 x, so |d| <= 1/128 and d is exact (Sterbenz). sin and cos of
// k/64 come from a table (libm's values, computed once), those of d from short Taylor
// polynomials (truncation below 1e-21), and the angle-addition formulas join them, written
// as corrections to the table's value:
//   sin x = S_k + (S_k (cos d - 1) + C_k sin d),  cos x = C_k + (C_k (cos d - 1) - S_k sin d).
// Outside the table (|x| > 16 rad, inf, NaN) it is libm's std::sin and std::cos. A pure function
// of x: the same angle gives the same bits wherever and in whatever order it is evaluated.
#pragma once

#include <array>
#include <cmath>

namespace tailsim {

struct SinCos {
  double s, c;  // sin x, cos x
};

namespace sin_cos_detail {
constexpr int kPerRad = 64;   // table entries per radian
constexpr int kHalf = 1024;   // entries each side of 0: |x| <= kHalf / kPerRad = 16 rad
struct Entry {
  double s, c;
};
// Entry k + kHalf: sin and cos of k / kPerRad (std::sin, std::cos), for |k| <= kHalf.
// Initialized before main (sin_cos.cc); not for use by other static initializers.
extern const std::array<Entry, 2 * kHalf + 1> kTable;
}  // namespace sin_cos_detail

inline SinCos sinCos(double x) {
  using namespace sin_cos_detail;
  constexpr double kMax = static_cast<double>(kHalf) / kPerRad;
  if (!(std::abs(x) <= kMax)) return {std::sin(x), std::cos(x)};  // also inf and NaN
  // kd: the integer nearest 64 x (as a double). On x86-64 by adding and removing 1.5 * 2^52, with
  // empty asm statements that hide the values from the optimizer: -ffast-math's reassociation
  // folded the add and the subtraction into a plain truncation (errors up to 1/64 rad, found in
  // review; CTest sin_cos_fast_math) and could distribute d's product over kd. Elsewhere by
  // truncating 64 x +- 1/2 to int (a conversion no floating-point optimization may rewrite; one
  // conversion more on the critical path, 4 % of Fig. 7's time on x86-64).
#if defined(__GNUC__) && defined(__x86_64__) && !defined(TAILSIM_SIN_COS_PORTABLE)  // (the test forces the other way)
  constexpr double kShift = 6755399441055744.0;
  double t = x * kPerRad + kShift;
  asm("" : "+x"(t));
  double kd = t - kShift;
  asm("" : "+x"(kd));
#else
  const double kd = static_cast<double>(static_cast<int>(x * kPerRad + std::copysign(0.5, x)));
#endif
  // Exact (Sterbenz: kd / 64 is within a factor 2 of x), or within 4e-19 just below x = 1/128.
  const double d = x - kd * (1.0 / kPerRad);
  const Entry& e = kTable[static_cast<int>(kd) + kHalf];
  const double d2 = d * d;
  const double sd = d + d * d2 * (-1.0 / 6 + d2 * (1.0 / 120 + d2 * (-1.0 / 5040)));   // sin d
  const double cm1 = d2 * (-0.5 + d2 * (1.0 / 24 + d2 * (-1.0 / 720)));              // cos d - 1
  return {e.s + (e.s * cm1 + e.c * sd), e.c + (e.c * cm1 - e.s * sd)};
}

}  // namespace tailsim
