#include "models/analytic/analytic_rows.h"

#include <stdexcept>
#include <string>

#include "results/columns.h"

namespace tailsim {

namespace {

// The analytic model's columns: name and value, in the CSV's order.
std::vector<RowColumn<PlanarRow>> columnTable(int links) {
  std::vector<RowColumn<PlanarRow>> t;
  addTimeAndJointColumns(t, links);
  addBodyColumns(t);
  return t;
}

}  // namespace

std::vector<std::string> analyticColumns(int links) { return columnNames(columnTable(links)); }

AnalyticRows::AnalyticRows(int n_links) : links_(n_links), table_(columnTable(n_links)), names_(columnNames(table_)) {}

void AnalyticRows::fill(const AnalyticModel& m, AnalyticWorkspace& w, double t, const State& y, const Modes& modes,
                        double* out) const {
  const bool decomp = m.effects.load_decomposition;
  const Eval ev = evaluate(m, w, t, y, modes, decomp);
  // w.joints: the joint states at t (evaluate()).
  if (w.joints.size() != static_cast<size_t>(links_))
    throw std::logic_error("analytic row: the joints do not match the columns");
  const bool stiction = m.stiction();
  const PlanarRow row{t, w.joints, y[kX], y[kY], y[kPhi], y[kPhiDot], ev.phi_ddot, ev.loads, decomp, ev.MzF, ev.L_F,
                      ev.FT_W, ev.FF_W, stickSlipState(stiction, modes.stuck[kRot]),
                      stickSlipState(stiction && m.translation(), modes.stuck[kTrans])};
  fillColumns(table_, row, out);
}

}  // namespace tailsim
