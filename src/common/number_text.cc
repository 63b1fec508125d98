#include "common/number_text.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>

namespace tailsim {
namespace {

// 10^0 .. 10^22: every one is exactly a double, so a * 10^k and a / 10^k round once.
constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                             1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

constexpr char kDigitPairs[] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

// Six decimal digits of v < 10^6, leading zeros included.
void put6(char* d, std::uint32_t v) {
  const std::uint32_t a = v / 10000, b = v % 10000;
  std::memcpy(d, kDigitPairs + 2 * a, 2);
  std::memcpy(d + 2, kDigitPairs + 2 * (b / 100), 2);
  std::memcpy(d + 4, kDigitPairs + 2 * (b % 100), 2);
}

char* slow(char* p, double v) { return std::to_chars(p, p + 32, v, std::chars_format::general, 12).ptr; }

}  // namespace

char* formatG12(char* p, double v) {
  if (v == 0.0) {  // the most common value of a time series: "0" or "-0"
    if (std::signbit(v)) *p++ = '-';
    *p++ = '0';
    return p;
  }
  const double a = std::fabs(v);
  if (!(a >= 1e-280 && a <= 1e280)) return slow(p, v);  // subnormal, inf, nan (and far outside the fast range)
  // The decimal exponent X and the 12-digit mantissa m = round(a 10^(11 - X)) in [1e11, 1e12).
  // Estimate X from the binary exponent (a = f 2^e, f in [1, 2): log10 a in [e log10 2, (e + 1)
  // log10 2)), so it is exact or one too low; the loop below corrects it.
  std::uint64_t bits;
  std::memcpy(&bits, &a, sizeof bits);
  const int e2 = static_cast<int>(bits >> 52) - 1023;
  int X = static_cast<int>(std::floor(e2 * 0.30102999566398120));
  std::uint64_t m = 0;
  for (int attempt = 0;; ++attempt) {
    const int k = 11 - X;
    if (k > 22 || k < -22 || attempt > 3) return slow(p, v);
    // One rounding: |error| <= 1.2e-4 when X is right (s < 1e12); about 1e-3 on a pass where X is
    // one too low (s < 1e13), whose m >= 1e12 then only sends it round the loop again.
    const double s = k >= 0 ? a * kPow10[k] : a / kPow10[-k];
    const auto whole = static_cast<std::uint64_t>(s);          // floor: 0 < s < 2^53
    const double frac = s - static_cast<double>(whole);         // exact
    // Within the rounding error of a tie the nearest integer of the exact product is not
    // known from s (and exact ties round to even): leave those to to_chars.
    if (std::fabs(frac - 0.5) < 1e-3) return slow(p, v);
    m = whole + (frac > 0.5 ? 1 : 0);
    if (m >= 1000000000000ull) ++X;        // rounded up to the next power of ten
    else if (m < 100000000000ull) --X;     // log10 was one too high
    else break;
  }
  // The 12 digits, two at a time from a table, in two 6-digit halves (32-bit arithmetic).
  char d[12];
  const auto hi = static_cast<std::uint32_t>(m / 1000000), lo = static_cast<std::uint32_t>(m % 1000000);
  put6(d, hi);
  put6(d + 6, lo);
  int nz = 12;  // significant digits without trailing zeros
  while (nz > 1 && d[nz - 1] == '0') --nz;
  if (v < 0) *p++ = '-';
  if (X < -4 || X >= 12) {  // scientific: d.ddde[+-]XX
    *p++ = d[0];
    if (nz > 1) {
      *p++ = '.';
      for (int i = 1; i < nz; ++i) *p++ = d[i];
    }
    *p++ = 'e';
    *p++ = X < 0 ? '-' : '+';
    const int e = X < 0 ? -X : X;
    if (e >= 100) *p++ = static_cast<char>('0' + e / 100);
    *p++ = static_cast<char>('0' + e / 10 % 10);
    *p++ = static_cast<char>('0' + e % 10);
  } else if (X >= 0) {  // ddd[.ddd]
    for (int i = 0; i <= X; ++i) *p++ = d[i];
    if (nz > X + 1) {
      *p++ = '.';
      for (int i = X + 1; i < nz; ++i) *p++ = d[i];
    }
  } else {  // 0.000ddd
    *p++ = '0';
    *p++ = '.';
    for (int i = 0; i < -X - 1; ++i) *p++ = '0';
    for (int i = 0; i < nz; ++i) *p++ = d[i];
  }
  return p;
}

std::string formatNumber(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

std::string formatG(double v, int digits) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*g", digits, v);
  return b;
}

}  // namespace tailsim
