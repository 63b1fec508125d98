// Output rows of the analytic model on the sample grid 0, dt, 2 dt, ... (docs/ARCHITECTURE.md
// "Time-series columns").
#pragma once

#include <limits>
#include <vector>

#include "analytic_model/analytic_model.h"
#include "results/time_series.h"

namespace tailsim {

class AnalyticRecorder {
 public:
  // n_samples: rows on the grid 0, dt, ... <= t_end (bounded by the caller before any work).
  AnalyticRecorder(int n_links, double dt, long n_samples);

  // Next sample time not yet written (or +inf when done).
  double nextTime() const { return next_ < n_samples_ ? next_ * dt_ : std::numeric_limits<double>::infinity(); }
  bool done() const { return next_ >= n_samples_; }

  // Evaluates the model at (t, y) in modes and appends the row.
  void record(const AnalyticModel& m, AnalyticWorkspace& w, double t, const State& y, const Modes& modes);

  // Once everything is at rest for good (tail stopped, body stuck), every remaining row is the
  // last one with a later time: copy it instead of re-evaluating the model.
  void repeatLastUntilDone();

  TimeSeries take() { return std::move(ts_); }

 private:
  double dt_;
  long n_samples_ = 0, next_ = 0;
  TimeSeries ts_;
  std::vector<double> row_;
};

}  // namespace tailsim
