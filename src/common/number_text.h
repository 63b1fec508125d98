// The text of a number in the CSV files: 12 significant digits, printf's "%.12g" (what
// std::to_chars(first, last, v, std::chars_format::general, 12) writes), made fast for the
// common case. Formatting is most of the cost of writing a run's output: to_chars with a
// precision takes ~400 instructions a number, this ~100.
#pragma once

#include <string>

namespace tailsim {

// The text of v as printf's format f writes it (f takes one double: "%g", "%.3f", "%+.17g", ...):
// every number in messages, Markdown, scripts and JSON-free text goes through here or formatG12.
std::string formatNumber(const char* f, double v);
// "%.<digits>g" (default "%g"): the shortest general form, for messages and labels.
std::string formatG(double v, int digits = 6);

// Writes v as "%.12g" would (C locale) at p, returns one past the last character. p must hold
// 32 characters. Bit-for-bit the same text as std::to_chars(..., general, 12) for every double
// (tests/test_number_text.cc): the fast path is taken only where its rounding is provably the
// correctly rounded one (and for 0 and -0); every other value goes to std::to_chars: ties and
// near-ties at the 12th digit, values whose scaling needs a power of ten beyond 10^22 (|v| below
// about 1e-11 or from about 1e34 up), inf and nan.
char* formatG12(char* p, double v);

}  // namespace tailsim
