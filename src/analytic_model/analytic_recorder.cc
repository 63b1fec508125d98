#include "analytic_model/analytic_recorder.h"

#include <cmath>
#include <string>

#include "results/columns.h"

namespace tailsim {

AnalyticRecorder::AnalyticRecorder(int n_links, double dt, long n_samples) : dt_(dt), n_samples_(n_samples) {
  ts_.addColumn(col::kT);
  for (int i = 1; i <= n_links; ++i) ts_.addColumn(col::theta(i));
  for (int i = 1; i <= n_links; ++i) ts_.addColumn(col::thetadot(i));
  for (int i = 1; i <= n_links; ++i) ts_.addColumn(col::thetaddot(i));
  for (const char* c : {col::kX, col::kY, col::kPhi, col::kPhidot, col::kPhiddot, col::kMzT, col::kMzTAcc,
                        col::kMzTSpeed, col::kMzTTan, col::kMzTCen, col::kMzF, col::kIzzPhiddot, col::kIzz,
                        col::kLF, col::kFTx, col::kFTy, col::kFFx, col::kFFy, col::kRotState, col::kTransState})
    ts_.addColumn(c);
  ts_.reserveRows(static_cast<size_t>(n_samples));  // bounded by limits::kMaxRowsPerRun (planRun)
  row_.assign(ts_.numColumns(), 0.0);
}

void AnalyticRecorder::record(const AnalyticModel& m, AnalyticWorkspace& w, double t, const State& y,
                              const Modes& modes) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  const bool decomp = m.effects.load_decomposition;
  const Eval ev = evaluate(m, w, t, y, modes, decomp);
  const std::vector<JointState>& js = w.joints;  // the joint states at t (evaluate())
  // Written in place (row_ has one slot per column): no capacity check per value.
  double* r = row_.data();
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
  ts_.appendRow(row_);
  ++next_;
}

void AnalyticRecorder::repeatLastUntilDone() {
  if (ts_.numRows() == 0 || done()) return;
  // Column 0 is the time, next_ * dt_ as nextTime() gives it.
  ts_.appendRepeated(row_, static_cast<size_t>(n_samples_ - next_), 0, next_, dt_);
  next_ = n_samples_;
}

}  // namespace tailsim
