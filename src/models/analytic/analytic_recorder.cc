#include "models/analytic/analytic_recorder.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "results/columns.h"
#include "results/thin_series.h"

namespace tailsim {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kDeg = 180.0 / M_PI;

// The analytic model's columns: name and value, in the CSV's order.
std::vector<RowColumn<AnalyticRow>> columnTable(int links) {
  using R = const AnalyticRow&;
  std::vector<RowColumn<AnalyticRow>> t;
  addTimeAndJointColumns(t, links);
  const std::vector<RowColumn<AnalyticRow>> body = {
      {col::kX, [](R r, int) { return r.y[kX]; }},
      {col::kY, [](R r, int) { return r.y[kY]; }},
      {col::kPhi, [](R r, int) { return r.y[kPhi] * kDeg; }},
      {col::kPhidot, [](R r, int) { return r.y[kPhiDot] * kDeg; }},
      {col::kPhiddot, [](R r, int) { return r.ev.phi_ddot * kDeg; }},
      {col::kMzT, [](R r, int) { return r.ev.loads.MzT; }},
      {col::kMzTAcc, [](R r, int) { return r.decomp ? r.ev.loads.MzT_acc : kNaN; }},
      {col::kMzTSpeed, [](R r, int) { return r.decomp ? r.ev.loads.MzT_speed : kNaN; }},
      {col::kMzTTan, [](R r, int) { return r.decomp ? r.ev.loads.MzT_tan : kNaN; }},
      {col::kMzTCen, [](R r, int) { return r.decomp ? r.ev.loads.MzT_cen : kNaN; }},
      {col::kMzF, [](R r, int) { return r.ev.MzF; }},
      {col::kIzzPhiddot, [](R r, int) { return r.ev.loads.Izz_kgm2 * r.ev.phi_ddot; }},
      {col::kIzz, [](R r, int) { return r.ev.loads.Izz_kgm2; }},
      {col::kLF, [](R r, int) { return r.ev.L_F; }},
      {col::kFTx, [](R r, int) { return r.ev.FT_W.x(); }},
      {col::kFTy, [](R r, int) { return r.ev.FT_W.y(); }},
      {col::kFFx, [](R r, int) { return r.ev.FF_W.x(); }},
      {col::kFFy, [](R r, int) { return r.ev.FF_W.y(); }},
      {col::kRotState, [](R r, int) { return r.stiction ? (r.modes.stuck[kRot] ? 0.0 : 1.0) : kNaN; }},
      {col::kTransState,
       [](R r, int) { return r.stiction && r.translation ? (r.modes.stuck[kTrans] ? 0.0 : 1.0) : kNaN; }},
  };
  t.insert(t.end(), body.begin(), body.end());
  return t;
}

}  // namespace

std::vector<std::string> analyticColumns(int links) { return columnNames(columnTable(links)); }

AnalyticRecorder::AnalyticRecorder(int n_links, double dt, long n_samples, const std::vector<double>* thin_marks)
    : links_(n_links), dt_(dt), n_samples_(n_samples), table_(columnTable(n_links)), marks_(thin_marks) {
  for (const RowColumn<AnalyticRow>& c : table_) ts_.addColumn(c.name);
  // Bounded by limits::kMaxRowsPerRun (planRun).
  if (thin_marks) thin_.reserve(static_cast<size_t>(n_samples));
  else {
    ts_.reserveRows(static_cast<size_t>(n_samples));
    rows_.reset(new double[kBlockRows * ts_.numColumns()]);  // written before read
  }
  row_.assign(ts_.numColumns(), 0.0);
}

void AnalyticRecorder::record(const AnalyticModel& m, AnalyticWorkspace& w, double t, const State& y,
                              const Modes& modes) {
  if (next_ >= n_samples_) throw std::logic_error("analytic recorder: more rows than the run's grid");
  if (marks_) thin_.push({t, y, modes});
  else {
    if (next_ - flushed_ == static_cast<long>(kBlockRows)) flushRows();
    fillRow(m, w, t, y, modes, rows_.get() + static_cast<size_t>(next_ - flushed_) * ts_.numColumns());
  }
  ++next_;
}

void AnalyticRecorder::flushRows() {
  if (marks_ || flushed_ == next_) return;
  ts_.appendRowMajor(rows_.get(), static_cast<size_t>(next_ - flushed_));
  flushed_ = next_;
}

void AnalyticRecorder::fillRow(const AnalyticModel& m, AnalyticWorkspace& w, double t, const State& y,
                               const Modes& modes, double* out) {
  const bool decomp = m.effects.load_decomposition;
  const Eval ev = evaluate(m, w, t, y, modes, decomp);
  // w.joints: the joint states at t (evaluate()).
  if (w.joints.size() != static_cast<size_t>(links_))
    throw std::logic_error("analytic row: the joints do not match the columns");
  fillColumns(table_, AnalyticRow{t, y, modes, ev, w.joints, decomp, m.stiction(), m.translation()}, out);
}

void AnalyticRecorder::repeatLastUntilDone() {
  if (marks_) {
    if (thin_.empty() || done()) return;
    thin_.repeatLast(next_, n_samples_ - next_);
    next_ = n_samples_;
    return;
  }
  if (next_ == 0 || done()) return;
  const size_t width = ts_.numColumns();
  if (next_ == flushed_) throw std::logic_error("analytic recorder: the last row was already flushed");
  const double* last = rows_.get() + static_cast<size_t>(next_ - flushed_ - 1) * width;
  row_.assign(last, last + width);
  flushRows();
  // Column 0 is the time, next_ * dt_ as nextTime() gives it.
  ts_.appendRepeated(row_, static_cast<size_t>(n_samples_ - next_), 0, next_, dt_);
  next_ = flushed_ = n_samples_;
}

TimeSeries AnalyticRecorder::take(const AnalyticModel& m, AnalyticWorkspace& w) {
  if (!marks_) {
    flushRows();
    return std::move(ts_);
  }
  // The columns the thinning rule reads, as fillRow writes them.
  const bool stiction = m.stiction(), trans = stiction && m.translation();
  auto light = [&](const Pending& p) {
    return std::array<double, 3>{p.y[kPhi] * (180.0 / M_PI), stiction ? (p.modes.stuck[kRot] ? 0.0 : 1.0) : kNaN,
                                 trans ? (p.modes.stuck[kTrans] ? 0.0 : 1.0) : kNaN};
  };
  auto emit = [&](const Pending& p, double t, bool same) {
    if (!same) fillRow(m, w, p.t, p.y, p.modes, row_.data());
    row_[0] = t;  // a repeated row: its grid time
    ts_.appendRow(row_);
  };
  thin_.take(*marks_, dt_, light, emit);
  return std::move(ts_);
}

}  // namespace tailsim
