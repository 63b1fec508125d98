// The reduced time series of `output.time_series: thin` (docs/experiment-format.md "Time-series
// output"): a subset of the sampled rows, unchanged, chosen so that a plot of the kept rows shows
// everything the full series shows at its corners.
#pragma once

#include <algorithm>
#include <array>
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

// The rows of a run with `time_series: thin`, kept as states until the run ends, so that only the
// rows thinRowIndices keeps are evaluated (the analytic and per-foot recorders). The rule reads t,
// phi and the stick/slip states, which a state gives without evaluating the model. P: a row's
// state, with its time in P::t. The same rows, bit for bit, as thinning the full series.
template <class P>
class LazyThinRows {
 public:
  void reserve(size_t rows) { pending_.reserve(rows); }
  void push(const P& p) { pending_.push_back(p); }
  bool empty() const { return pending_.empty(); }
  // The grid rows first .. first + count - 1 repeat the last state (a run at rest for good), each
  // at its own time (first + i) * dt, as TimeSeries::appendRepeated writes it.
  void repeatLast(long first, long count) {
    repeat_first_ = first;
    repeat_count_ = count;
  }
  // light(p) -> {phi_deg, rot_state, trans_state} of state p, as the full row would hold them.
  // emit(p, t, same) for every kept row in order: its state and time; `same`: p is the state of
  // the row emitted just before (a repeated row: only the time differs). Frees the states.
  template <class Light, class Emit>
  void take(const std::vector<double>& marks, double dt, const Light& light, const Emit& emit) {
    TimeSeries ts;
    for (const char* c : {"t_s", "phi_deg", "rot_state", "trans_state"}) ts.addColumn(c);
    const size_t n = pending_.size();
    ts.reserveRows(n + static_cast<size_t>(repeat_count_));
    std::vector<double> r(4);
    auto row = [&](double t, const P& p) {
      const std::array<double, 3> l = light(p);
      r = {t, l[0], l[1], l[2]};
      ts.appendRow(r);
    };
    for (const P& p : pending_) row(p.t, p);
    for (long i = 0; i < repeat_count_; ++i) row(gridTime(i, dt), pending_.back());
    const P* last = nullptr;
    for (size_t k : thinRowIndices(ts, marks)) {
      const P& p = pending_[std::min(k, n - 1)];
      emit(p, k < n ? p.t : gridTime(static_cast<long>(k - n), dt), last == &p);
      last = &p;
    }
    std::vector<P>().swap(pending_);
  }

 private:
  double gridTime(long i, double dt) const { return static_cast<double>(repeat_first_ + i) * dt; }
  std::vector<P> pending_;
  long repeat_first_ = 0, repeat_count_ = 0;
};

}  // namespace tailsim
