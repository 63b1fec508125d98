// Output rows of a planar model (analytic, per-foot) on the sample grid 0, dt, 2 dt, ...
// (docs/ARCHITECTURE.md "Time-series columns"). The model says what one row holds; the recorder
// says when a row is written, keeps the rows of `output.time_series: thin` as states until the run
// ends, and copies the last row once the run is at rest for good.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <stdexcept>
#include <vector>

#include "models/planar/stick_slip.h"
#include "results/thin_series.h"
#include "results/time_series.h"
#include "common/units.h"

namespace tailsim {

// Model (the driver's model, stick_slip_driver.h) gives:
//   State;  columns() -> std::vector<std::string>;  fillRow(t, y, modes, out) writes one row;
//   phi(y) [rad];  stiction();  translation().
template <class Model>
class PlanarRecorder {
 public:
  using State = typename Model::State;

  // n_samples: rows on the grid 0, dt, ... <= t_end (bounded by the caller before any work).
  // thin_marks (output.time_series: thin): the tail's phase boundaries. The rows are then kept as
  // states and evaluated in take(), only those thinRowIndices keeps (results/thin_series.h): the
  // rule reads t, phi and the stick/slip states alone, which the state gives without evaluating
  // the model. The same rows, bit for bit, as thinning the full series.
  PlanarRecorder(Model& model, double dt, long n_samples, const std::vector<double>* thin_marks)
      : model_(model), dt_(dt), n_samples_(n_samples), marks_(thin_marks) {
    for (const std::string& c : model.columns()) ts_.addColumn(c);
    // Bounded by limits::kMaxRowsPerRun (the model's plan).
    if (thin_marks) thin_.reserve(static_cast<size_t>(n_samples));
    else {
      ts_.reserveRows(static_cast<size_t>(n_samples));
      rows_.reset(new double[kBlockRows * ts_.numColumns()]);  // written before read
    }
    row_.assign(ts_.numColumns(), 0.0);
  }

  // Next sample time not yet written (or +inf when done).
  double nextTime() const { return next_ < n_samples_ ? next_ * dt_ : std::numeric_limits<double>::infinity(); }
  bool done() const { return next_ >= n_samples_; }

  // Evaluates the model at (t, y) in modes and appends the row (thin: keeps the state for take()).
  void record(double t, const State& y, const Modes& modes) {
    if (next_ >= n_samples_) throw std::logic_error("planar recorder: more rows than the run's grid");
    if (marks_) thin_.push({t, y, modes});
    else {
      if (next_ - flushed_ == static_cast<long>(kBlockRows)) flushRows();
      model_.fillRow(t, y, modes, rows_.get() + static_cast<size_t>(next_ - flushed_) * ts_.numColumns());
    }
    ++next_;
  }

  // Once everything is at rest for good (tail stopped, body stuck), every remaining row is the
  // last one with a later time: copy it instead of re-evaluating the model.
  void repeatLastUntilDone() {
    if (marks_) {
      if (thin_.empty() || done()) return;
      thin_.repeatLast(next_, n_samples_ - next_);
      next_ = n_samples_;
      return;
    }
    if (next_ == 0 || done()) return;
    const size_t width = ts_.numColumns();
    if (next_ == flushed_) throw std::logic_error("planar recorder: the last row was already flushed");
    const double* last = rows_.get() + static_cast<size_t>(next_ - flushed_ - 1) * width;
    row_.assign(last, last + width);
    flushRows();
    // Column 0 is the time, next_ * dt_ as nextTime() gives it.
    ts_.appendRepeated(row_, static_cast<size_t>(n_samples_ - next_), 0, next_, dt_);
    next_ = flushed_ = n_samples_;
  }

  // The rows (thin: the kept ones, evaluated now).
  TimeSeries take() {
    if (!marks_) {
      flushRows();
      return std::move(ts_);
    }
    // The columns the thinning rule reads, as fillRow writes them.
    const bool stiction = model_.stiction(), trans = stiction && model_.translation();
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    auto light = [&](const Pending& p) {
      return std::array<double, 3>{model_.phi(p.y) * units::kDegPerRad,
                                   stiction ? (p.modes.stuck[kRot] ? 0.0 : 1.0) : kNaN,
                                   trans ? (p.modes.stuck[kTrans] ? 0.0 : 1.0) : kNaN};
    };
    auto emit = [&](const Pending& p, double t, bool same) {
      if (!same) model_.fillRow(p.t, p.y, p.modes, row_.data());
      row_[0] = t;  // a repeated row: its grid time
      ts_.appendRow(row_);
    };
    thin_.take(*marks_, dt_, light, emit);
    return std::move(ts_);
  }
  // take() gives the thin subset, not every sample.
  bool thinned() const { return marks_ != nullptr; }

 private:
  // Moves the rows recorded since the last flush from rows_ into ts_.
  void flushRows() {
    if (marks_ || flushed_ == next_) return;
    ts_.appendRowMajor(rows_.get(), static_cast<size_t>(next_ - flushed_));
    flushed_ = next_;
  }
  struct Pending {
    double t;
    State y;
    Modes modes;
  };
  Model& model_;
  double dt_;
  long n_samples_ = 0, next_ = 0;
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
