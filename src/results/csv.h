// A TimeSeries as CSV text and files: written whole or not at all (common/atomic_file.h), read back.
#pragma once

#include <string>

#include "results/time_series.h"

namespace tailsim {

// CSV with a header row of column names; numbers with 12 significant digits.
std::string toCsv(const TimeSeries& ts);
void writeCsvAtomic(const std::string& path, const TimeSeries& ts);

// Reads a CSV written by toCsv back (for `tailsim plot`, reports and tests).
TimeSeries readCsv(const std::string& path);

}  // namespace tailsim
