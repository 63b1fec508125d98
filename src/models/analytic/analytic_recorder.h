// Output rows of the analytic model on the sample grid 0, dt, 2 dt, ... (docs/ARCHITECTURE.md
// "Time-series columns").
#pragma once

#include <limits>
#include <memory>
#include <vector>

#include "models/analytic/analytic_model.h"
#include "models/planar/row_columns.h"
#include "results/thin_series.h"
#include "results/time_series.h"

namespace tailsim {

// What one output row of the analytic model is read from (its column table, analytic_recorder.cc).
struct AnalyticRow {
  double t;
  const State& y;
  const Modes& modes;
  const Eval& ev;
  const std::vector<JointState>& joints;  // at t
  bool decomp;       // effects.load_decomposition: the M_zT parts were evaluated
  bool stiction;     // the stick/slip states exist
  bool translation;  // the body translates
};

// The analytic model's columns for an n-link tail, in its CSV's order.
std::vector<std::string> analyticColumns(int links);

class AnalyticRecorder {
 public:
  // n_samples: rows on the grid 0, dt, ... <= t_end (bounded by the caller before any work).
  // thin_marks (output.time_series: thin): the tail's phase boundaries. The rows are then kept as
  // states and evaluated in take(), only those thinRowIndices keeps (results/thin_series.h): the
  // rule reads t, phi and the stick/slip states alone, which the state gives without evaluating
  // the model. The same rows, bit for bit, as thinning the full series.
  AnalyticRecorder(int n_links, double dt, long n_samples, const std::vector<double>* thin_marks = nullptr);

  // Next sample time not yet written (or +inf when done).
  double nextTime() const { return next_ < n_samples_ ? next_ * dt_ : std::numeric_limits<double>::infinity(); }
  bool done() const { return next_ >= n_samples_; }

  // Evaluates the model at (t, y) in modes and appends the row (thin: keeps the state for take()).
  void record(const AnalyticModel& m, AnalyticWorkspace& w, double t, const State& y, const Modes& modes);

  // Once everything is at rest for good (tail stopped, body stuck), every remaining row is the
  // last one with a later time: copy it instead of re-evaluating the model.
  void repeatLastUntilDone();

  // The rows (thin: the kept ones, evaluated now with m and w).
  TimeSeries take(const AnalyticModel& m, AnalyticWorkspace& w);
  // take() gives the thin subset, not every sample.
  bool thinned() const { return marks_ != nullptr; }

 private:
  // The row of (t, y, modes) into out[0 .. numColumns).
  void fillRow(const AnalyticModel& m, AnalyticWorkspace& w, double t, const State& y, const Modes& modes, double* out);
  // Moves the rows recorded since the last flush from rows_ into ts_.
  void flushRows();
  struct Pending {
    double t;
    State y;
    Modes modes;
  };
  int links_;
  double dt_;
  long n_samples_ = 0, next_ = 0;
  std::vector<RowColumn<AnalyticRow>> table_;
  TimeSeries ts_;
  // Every sample (not thin): up to kBlockRows rows recorded one after another, row-major, then
  // moved into ts_'s columns in one pass (flushRows): a row written in place costs no per-column
  // append, and the block stays small (a whole-run buffer above malloc's mmap threshold cost a
  // fresh mapping and its page faults on every run).
  static constexpr size_t kBlockRows = 32;
  std::unique_ptr<double[]> rows_;
  long flushed_ = 0;  // rows already in ts_ (rows_ holds rows flushed_ .. next_ - 1)
  std::vector<double> row_;  // one row (thin: take()'s rows; repeatLastUntilDone's source)
  const std::vector<double>* marks_ = nullptr;
  LazyThinRows<Pending> thin_;  // thin: the states of the rows recorded so far
};

}  // namespace tailsim
