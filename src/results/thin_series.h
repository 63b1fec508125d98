// The reduced time series of `output.time_series: thin` (docs/experiment-format.md "Time-series
// output"): a subset of the sampled rows, unchanged, chosen so that a plot of the kept rows shows
// everything the full series shows at its corners.
#pragma once

#include <cstddef>
#include <vector>

#include "results/time_series.h"

namespace tailsim {

// Every `grid`-th sample of the full series.
constexpr size_t kThinGrid = 10;

// The indices (increasing, no repeats) of the rows kept from `ts`:
//  1. rows 0, grid, 2 grid, ... and the last row;
//  2. both rows around every change of `rot_state` or `trans_state` (the last row of the old state
//     and the first of the new: stick/slip switches);
//  3. around each time of `marks` (the tail's phase boundaries t0, t1, t2 of every joint), the
//     last row at or before it and the first row at or after it;
//  4. every row where the sign of phi_deg's change differs from that of the row before
//     (sign in {-, 0, +}): phi's turning points (local extremes) and where it starts or stops
//     changing, and the rows of phi_deg's global minimum and maximum.
// Columns a series lacks (MuJoCo has no rot_state) add no rows.
std::vector<size_t> thinRowIndices(const TimeSeries& ts, const std::vector<double>& marks, size_t grid = kThinGrid);

// The series with only those rows (same columns, same order).
TimeSeries thinRows(const TimeSeries& ts, const std::vector<double>& marks, size_t grid = kThinGrid);

}  // namespace tailsim
