// The CSV number text (src/common/number_text.h): formatG12 must write exactly what
// std::to_chars(..., general, 12) writes, for every double. Checked on random bit patterns over
// the whole range, on the values a run writes, and on the places a fast path gets wrong: ties
// and near-ties at the 12th digit, powers of ten and their neighbours, the fixed/scientific
// switch (exponents -5/-4 and 11/12), integers, subnormals, zero, inf.
#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include "common/number_text.h"

namespace tailsim {
namespace {

std::string reference(double v) {
  char buf[64];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 12).ptr);
}
std::string fast(double v) {
  char buf[64];
  return std::string(buf, formatG12(buf, v));
}

// Counts mismatches, reporting the first few.
struct Checker {
  long checked = 0, wrong = 0;
  void operator()(double v) {
    ++checked;
    const std::string a = fast(v), b = reference(v);
    if (a != b && ++wrong <= 5) ADD_FAILURE() << "bits " << std::hex << bits(v) << ": " << a << " vs " << b;
  }
  static std::uint64_t bits(double v) {
    std::uint64_t b;
    std::memcpy(&b, &v, sizeof b);
    return b;
  }
};

TEST(NumberText, SameTextAsToCharsOnRandomBitPatterns) {
  std::mt19937_64 rng(20261125);
  Checker check;
  for (int i = 0; i < 2'000'000; ++i) {
    const std::uint64_t b = rng();
    double v;
    std::memcpy(&v, &b, sizeof v);
    if (std::isnan(v)) continue;
    check(v);
  }
  EXPECT_EQ(check.wrong, 0) << "of " << check.checked;
  EXPECT_GT(check.checked, 1'990'000);
}

TEST(NumberText, SameTextAsToCharsOnTheValuesARunWrites) {
  // Angles, speeds, loads: uniform and log-uniform magnitudes of both signs, values rounded to a
  // few decimals (exact decimal text, many trailing zeros), and small integers.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0), e(-12.0, 14.0);
  Checker check;
  for (int i = 0; i < 1'000'000; ++i) {
    const double mag = std::pow(10.0, e(rng));
    check(u(rng) * mag);
    check(std::round(u(rng) * 1e6) / 1e3);
    check(static_cast<double>(static_cast<long>(u(rng) * 1e6)));
    check(i * 1e-3);  // the output grid's time column
  }
  EXPECT_EQ(check.wrong, 0) << "of " << check.checked;
}

TEST(NumberText, SameTextAsToCharsAtTiesPowersOfTenAndTheFormatSwitch) {
  Checker check;
  for (int p = -300; p <= 300; ++p) {
    const double t = std::pow(10.0, p);
    double v = t;
    for (int s = 0; s < 40; ++s) v = std::nextafter(v, 0.0);
    for (int s = 0; s < 80; ++s, v = std::nextafter(v, 1e308)) {
      check(v);
      check(-v);
    }
    // 9.99999999999|5 and 9.99999999999|4999 (the 12-digit round-up to the next power of ten)
    check(t * 9.999999999995);
    check(t * 9.9999999999949);
    check(t * 9.99999999999951);
  }
  // Ties at the 12th digit and their neighbours: (k + 0.5) 10^j. For j = 0 these are exact ties
  // (k + 0.5 is a double: round half to even); for j != 0 the nearest doubles, near-ties.
  for (long k = 100000000000; k < 100000000000 + 20000; ++k) {
    for (int j = -3; j <= 3; ++j) {
      const double v = std::ldexp(static_cast<double>(k) + 0.5, 0) * std::pow(10.0, j);
      check(v);
      check(std::nextafter(v, 0.0));
      check(std::nextafter(v, 1e308));
    }
  }
  for (double v : {0.5, 1.5, 2.5, 0.125, 123456789012.5, 123456789013.5, 1234567890125.0, 0.0001, 0.00001,
                   0.000099999999999995, 99999999999.5, 999999999999.5, 999999999999.4, 1e12, 1e11})
    check(v);
  EXPECT_EQ(check.wrong, 0) << "of " << check.checked;
}

TEST(NumberText, SpecialValuesGoThroughToChars) {
  EXPECT_EQ(fast(0.0), "0");
  EXPECT_EQ(fast(-0.0), "-0");
  EXPECT_EQ(fast(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(fast(-std::numeric_limits<double>::infinity()), "-inf");
  EXPECT_EQ(fast(std::numeric_limits<double>::denorm_min()), reference(std::numeric_limits<double>::denorm_min()));
  EXPECT_EQ(fast(std::numeric_limits<double>::max()), reference(std::numeric_limits<double>::max()));
  EXPECT_EQ(fast(-90.0), "-90");
  EXPECT_EQ(fast(0.001), "0.001");
  EXPECT_EQ(fast(1.0 / 3.0), "0.333333333333");
  EXPECT_EQ(fast(1e-5), "1e-05");
  EXPECT_EQ(fast(-1234567890123.0), "-1.23456789012e+12");
}

}  // namespace
}  // namespace tailsim
