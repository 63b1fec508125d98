// sinCos (src/numerics/sin_cos.h) against libm: the table plus polynomials is as accurate as
// libm's sin and cos to within 1 ulp of 1, exact where the models rely on it, and libm itself
// outside the table.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "numerics/sin_cos.h"

using namespace tailsim;

namespace {
bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
}  // namespace

// Against long double sinl/cosl (64-bit mantissa) over the whole table range, and over the
// first steps of it where the angle is small: the error is at most 1 ulp of 1 (2.2e-16) and
// never more than 1 ulp above libm's own.
TEST(SinCos, WithinOneUlpOfOneOverTheTable) {
  std::mt19937_64 rng(20261126);
  std::uniform_real_distribution<double> wide(-16.0, 16.0), narrow(-0.05, 0.05);
  const double ulp1 = std::numeric_limits<double>::epsilon();
  double worst = 0, worst_libm = 0;
  for (int i = 0; i < 400000; ++i) {
    const double x = (i % 4 == 0) ? narrow(rng) : wide(rng);
    const SinCos sc = sinCos(x);
    const long double xs = std::sin(static_cast<long double>(x)), xc = std::cos(static_cast<long double>(x));
    const double e = std::max(std::abs(static_cast<double>(sc.s - xs)), std::abs(static_cast<double>(sc.c - xc)));
    const double el = std::max(std::abs(static_cast<double>(std::sin(x) - xs)), std::abs(static_cast<double>(std::cos(x) - xc)));
    worst = std::max(worst, e);
    worst_libm = std::max(worst_libm, el);
  }
  EXPECT_LE(worst, ulp1) << "libm's worst: " << worst_libm;
  EXPECT_LE(worst, worst_libm + ulp1);
}

// Small angles keep their relative accuracy (k = 0: the polynomials alone), and the table's
// grid points and 0 are exact.
TEST(SinCos, SmallAnglesAndGridPoints) {
  for (double x : {1e-300, 1e-20, 1e-10, -3e-7, 1e-4, 0.0078}) {
    const SinCos sc = sinCos(x);
    EXPECT_NEAR(sc.s / std::sin(x), 1.0, 2.3e-16) << x;
    EXPECT_NEAR(sc.c, std::cos(x), 1.2e-16) << x;
  }
  EXPECT_TRUE(sameBits(sinCos(0.0).s, 0.0));
  EXPECT_TRUE(sameBits(sinCos(0.0).c, 1.0));
  for (int k = -1024; k <= 1024; k += 7) {
    const double x = k / 64.0;
    EXPECT_TRUE(sameBits(sinCos(x).s, std::sin(x))) << x;
    EXPECT_TRUE(sameBits(sinCos(x).c, std::cos(x))) << x;
  }
}

// The rounding of 64 x to the nearest grid point: halfway cases and the ends of the table.
TEST(SinCos, TableEndsAndHalfwayPoints) {
  for (double x : {16.0, -16.0, std::nextafter(16.0, 0.0), 15.9921875, -15.9921875, 1.0 / 128, -1.0 / 128, 0.5 + 1.0 / 128,
                   std::nextafter(1.0 / 128, 1.0), std::nextafter(-1.0 / 128, -1.0)}) {
    const SinCos sc = sinCos(x);
    EXPECT_NEAR(sc.s, std::sin(x), 2.3e-16) << x;
    EXPECT_NEAR(sc.c, std::cos(x), 2.3e-16) << x;
    EXPECT_NEAR(sc.s * sc.s + sc.c * sc.c, 1.0, 4.5e-16) << x;
  }
}

// Outside the table it is libm, bit for bit; inf and NaN give NaN.
TEST(SinCos, OutsideTheTableIsLibm) {
  for (double x : {std::nextafter(16.0, 17.0), 16.0 + 1.0 / 128 + 1e-12, 16.2, -16.2, -16.5, 100.0, -1e6, 1e300}) {
    EXPECT_TRUE(sameBits(sinCos(x).s, std::sin(x))) << x;
    EXPECT_TRUE(sameBits(sinCos(x).c, std::cos(x))) << x;
  }
  EXPECT_TRUE(std::isnan(sinCos(std::numeric_limits<double>::infinity()).s));
  EXPECT_TRUE(std::isnan(sinCos(std::numeric_limits<double>::quiet_NaN()).c));
}
