// Outputs are written whole or not at all: write to a temporary file beside the target,
// flush, then rename over it (rename is atomic within one filesystem).
#pragma once

#include <string>

#include "results/time_series.h"

namespace tailsim {

// Writes `contents` to `path` atomically; throws std::runtime_error naming the path on failure.
void writeFileAtomic(const std::string& path, const std::string& contents);

// CSV with a header row of column names; numbers with 12 significant digits.
std::string toCsv(const TimeSeries& ts);
void writeCsvAtomic(const std::string& path, const TimeSeries& ts);

// Reads a CSV written by toCsv back (for `tailsim plot`, reports and tests).
TimeSeries readCsv(const std::string& path);

}  // namespace tailsim
