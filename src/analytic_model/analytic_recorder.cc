#include "analytic_model/analytic_recorder.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "results/columns.h"
#include "results/thin_series.h"

namespace tailsim {

AnalyticRecorder::AnalyticRecorder(int n_links, double dt, long n_samples, const std::vector<double>* thin_marks)
    : dt_(dt), n_samples_(n_samples), marks_(thin_marks) {
  ts_.addColumn(col::kT);
  for (int i = 1; i <= n_links; ++i) ts_.addColumn(col::theta(i));
  for (int i = 1; i <= n_links; ++i) ts_.addColumn(col::thetadot(i));
  for (int i = 1; i <= n_links; ++i) ts_.addColumn(col::thetaddot(i));
  for (const char* c : {col::kX, col::kY, col::kPhi, col::kPhidot, col::kPhiddot, col::kMzT, col::kMzTAcc,
                        col::kMzTSpeed, col::kMzTTan, col::kMzTCen, col::kMzF, col::kIzzPhiddot, col::kIzz,
                        col::kLF, col::kFTx, col::kFTy, col::kFFx, col::kFFy, col::kRotState, col::kTransState})
    ts_.addColumn(c);
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
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  const bool decomp = m.effects.load_decomposition;
  const Eval ev = evaluate(m, w, t, y, modes, decomp);
  const std::vector<JointState>& js = w.joints;  // the joint states at t (evaluate())
  // Written in place (one slot per column: t, 3 per joint, 20 more): no capacity check per value.
  if (row_.size() != 21 + 3 * js.size()) throw std::logic_error("analytic row: the joints do not match the columns");
  double* r = out;
  *r++ = t;
  const double d = 180.0 / M_PI;
  for (const auto& j : js) *r++ = j.theta * d;
  for (const auto& j : js) *r++ = j.theta_dot * d;
  for (const auto& j : js) *r++ = j.theta_ddot * d;
  const bool stiction = m.stiction();
  for (double v : {y[kX], y[kY], y[kPhi] * d, y[kPhiDot] * d, ev.phi_ddot * d, ev.loads.MzT,
                   decomp ? ev.loads.MzT_acc : kNaN, decomp ? ev.loads.MzT_speed : kNaN,
                   decomp ? ev.loads.MzT_tan : kNaN, decomp ? ev.loads.MzT_cen : kNaN, ev.MzF,
                   ev.loads.Izz_kgm2 * ev.phi_ddot, ev.loads.Izz_kgm2, ev.L_F, ev.FT_W.x(), ev.FT_W.y(),
                   ev.FF_W.x(), ev.FF_W.y(), stiction ? (modes.stuck[kRot] ? 0.0 : 1.0) : kNaN,
                   stiction && m.translation() ? (modes.stuck[kTrans] ? 0.0 : 1.0) : kNaN})
    *r++ = v;
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
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
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
