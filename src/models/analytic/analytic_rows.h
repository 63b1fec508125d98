// The analytic model's output columns (docs/ARCHITECTURE.md "Time-series columns"); the rows are
// written on the sample grid by the planar models' recorder (models/planar/planar_recorder.h).
#pragma once

#include <vector>

#include "models/analytic/analytic_model.h"
#include "models/planar/row_columns.h"

namespace tailsim {

// The analytic model's columns for an n-link tail, in its CSV's order.
std::vector<std::string> analyticColumns(int links);

// Writes the analytic model's rows (its column table, analytic_rows.cc) for PlanarRecorder.
class AnalyticRows {
 public:
  explicit AnalyticRows(int n_links);
  const std::vector<std::string>& names() const { return names_; }
  // The row of (t, y, modes) into out[0 .. names().size()).
  void fill(const AnalyticModel& m, AnalyticWorkspace& w, double t, const State& y, const Modes& modes,
            double* out) const;

 private:
  int links_;
  std::vector<RowColumn<PlanarRow>> table_;
  std::vector<std::string> names_;
};

}  // namespace tailsim
